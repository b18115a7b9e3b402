"""Cost of Object › Shading › Shadow Terminator's geometry offset: the same frame of smooth
low-poly spheres with Geometry Offset 0 (indexed batches, the plain variant) and 0.1 (one
vertex per triangle corner with the offset's corner data, the TERMINATOR_OFFSET variant),
F12 renders timed in one process (median of ``--runs`` after a warm-up)."""

import statistics
import sys

import bpy

from devkit import report, scenes, session, timing

HELP = "frame time with Shadow Terminator Geometry Offset 0 against 0.1 (smooth spheres)"


def add_arguments(parser):
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--spheres", type=int, default=6, help="spheres per side of the grid (default 6)")
    parser.add_argument("--samples", type=int, default=4, help="render samples (default 4)")


def build(args):
    scene = scenes.empty_scene(args.width, args.height)
    grey = scenes.white("Grey", 0.6)
    scenes.plane(scene, "Ground", size=40.0, mat=scenes.white("Plane", 0.8))
    n = args.spheres
    spheres = []
    for i in range(n):
        for j in range(n):
            center = (2.2 * (i - (n - 1) / 2), 2.2 * (j - (n - 1) / 2), 1.0)
            spheres.append(scenes.uv_sphere(scene, f"S{i}_{j}", center=center, radius=1.0, mat=grey))
    sun = scenes.light(scene, "Sun", "SUN", 3.0, angle=0.01)
    sun.rotation_euler = (1.1, 0.0, 0.8)
    scenes.look_at(scene, (0.0, -2.6 * n, 1.6 * n), (0.0, 0.0, 0.5), lens=35.0)
    scene.penumbra.render_samples = args.samples
    return scene, spheres


def run(args):
    session.load_penumbra().register()
    scene, spheres = build(args)

    def frame(offset):
        for ob in spheres:
            ob.shadow_terminator_geometry_offset = offset
        with session.stdout_to_stderr():
            bpy.ops.render.render(write_still=False)

    offsets = (0.0, 0.1)
    times = {offset: [] for offset in offsets}
    for offset in offsets:  # warm-up: programs compiled, batches built
        frame(offset)
    for run_index in range(args.runs):  # interleaved, so load from elsewhere hits both alike
        for offset in offsets:
            times[offset].append(timing.measure(lambda o=offset: frame(o), 1, warmup=0).times[0])
        print(f"terminator: run {run_index + 1}/{args.runs}", file=sys.stderr, flush=True)
    medians = {o: statistics.median(t) for o, t in times.items()}
    rows = [[o, f"{medians[o] * 1000:.0f}", f"{min(times[o]) * 1000:.0f}"] for o in offsets]
    print(report.markdown_table(["Geometry Offset", "F12 median (ms)", "fastest (ms)"], rows))
    triangles = len(spheres) * 2 * 32 * 15  # 32 segments, 16 rings
    print(
        f"\n{bpy.app.version_string}; {len(spheres)} smooth UV spheres (32 x 16, {triangles} triangles), "
        f"{args.width}x{args.height}, {args.samples} samples; 0.1 / 0 = {medians[0.1] / medians[0.0]:.3f}."
    )
    return 0
