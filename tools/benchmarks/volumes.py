"""Light through air: homogeneous media lit through the shadow maps, error against time.

Three scenes of this module's own: ``spot_gap`` (a spot behind a wall shining through a gap
into a room of fog), ``sun_mist`` (a low sun through a wall pierced by a grid of windows into
mist: the shafts), ``backlit_box`` (a Principled Volume box, coloured and anisotropic, lit from
behind by a point light over a floor), and ``world_fog`` (a World > Volume around a lamp and a
few objects). Each is rendered by Penumbra at ``--samples`` (4, 16, 64, 256), by Cycles at 16
... 256 spp and by EEVEE at its defaults (16 samples, its own volumetrics), against Cycles at
``--reference`` spp (1024) with Volume Bounces 0 (single scattering, the light Penumbra
computes; direct light only, transparent bounces enough to cross the media's boxes; cached per
clone under out/reference_cache), and by Penumbra at 16 samples with View Layer › Filter ›
Volumes off (what the media cost). For each: the median time of ``--runs`` F12 renders after a
warm-up and the display MAE (Standard view, sRGB-encoded, clipped to [0, 1]).

Writes ``<out>/volumes.csv`` and ``<out>/volumes.png`` (error against time per scene, each
scene's reference beside Penumbra's 64 samples and EEVEE's image); a Markdown table to stdout.
``--quick``: 160x90, reference 256 spp, Penumbra 4/16/64, one run. Not measured: OpenVDB grids
(Volume objects are named, not drawn).
"""

import math
import sys
import time
from pathlib import Path

import bpy
import numpy as np

from devkit import report, scenes, session, timing
from devkit import volume_scenes as vs
from devkit.engines import EEVEE_SAMPLES, configure
from devkit.render import cached_image, render
from devkit.world_scenes import display

HELP = "volumes: error against time vs Cycles single scattering and EEVEE -> <out>/volumes.csv, volumes.png"

CSV_FIELDS = ["scene", "engine", "samples", "time_s", "mae"]


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default out)")
    timing.add_runs_argument(parser, 3, "timed renders per configuration (default 3; 1 with --quick)")
    parser.add_argument("--quick", action="store_true", help="160x90, reference 256 spp, Penumbra 4/16/64, one run")
    parser.add_argument("--width", type=int, default=240)
    parser.add_argument("--height", type=int, default=135)
    parser.add_argument("--samples", default="4,16,64,256", help="Penumbra's render samples (comma-separated)")
    parser.add_argument("--cycles-spp", default="16,64,256", help="Cycles' samples to time (comma-separated)")
    parser.add_argument("--reference", type=int, default=1024, help="Cycles' reference spp (default 1024)")
    parser.add_argument("--scenes", default=",".join(SCENES), help="comma-separated: " + ", ".join(SCENES))


def log(message):
    print(f"bench volumes: {message}", file=sys.stderr, flush=True)


def _base(width, height):
    scene = scenes.empty_scene(width, height)
    scene.render.filter_size = scene.penumbra.filter_size = 1.5
    scenes.plane(scene, "Floor", size=30.0, mat=scenes.material("Floor", (0.5, 0.5, 0.5), roughness=0.6))
    return scene


def spot_gap(width, height):
    """A spot behind a wall with a gap 0.6 wide, into a room of fog."""
    scene = _base(width, height)
    scenes.set_world(scene, (0.01, 0.01, 0.012))
    wall = scenes.material("Wall", (0.6, 0.55, 0.5))
    scenes.box(scene, "WallL", center=(-2.3, 2.0, 1.5), size=(4.0, 0.2, 3.0), mat=wall)
    scenes.box(scene, "WallR", center=(2.3, 2.0, 1.5), size=(4.0, 0.2, 3.0), mat=wall)
    spot = scenes.light(scene, "Spot", "SPOT", 2000.0, location=(0.0, 4.5, 2.6), spot_size=math.radians(70))
    spot.data.shadow_soft_size = 0.05
    scenes.aim(spot, (0.0, 0.0, 0.0))
    vs.fog_box(scene, "Fog", center=(0.0, -1.0, 1.6), size=(8.0, 6.0, 3.2), kind="SCATTER", density=0.12)
    scenes.look_at(scene, (4.5, -6.5, 2.2), (0.0, 0.5, 1.0))
    return scene


def sun_mist(width, height):
    """A low sun through a wall pierced by a 3x2 grid of windows into mist."""
    scene = _base(width, height)
    scenes.set_world(scene, (0.02, 0.025, 0.035))
    wall = scenes.material("Wall", (0.5, 0.5, 0.5))
    for i, x in enumerate((-2.4, -1.2, 0.0, 1.2, 2.4)):  # the posts between the windows
        scenes.box(scene, f"Post{i}", center=(x, 3.0, 1.5), size=(0.6, 0.2, 3.0), mat=wall)
    for k, z in enumerate((0.1, 1.2, 2.3)):  # the lintels
        scenes.box(scene, f"Lintel{k}", center=(0.0, 3.0, z), size=(5.4, 0.2, 0.4), mat=wall)
    scenes.light(scene, "Sun", "SUN", 4.0, rotation=(math.radians(-60), 0.0, math.radians(15)), angle=0.01)
    vs.fog_box(
        scene, "Mist", center=(0.0, -0.5, 1.5), size=(8.0, 6.8, 3.0), kind="SCATTER", density=0.15, anisotropy=0.4
    )
    scenes.look_at(scene, (5.0, -6.0, 1.8), (0.0, 0.5, 1.2))
    return scene


def backlit_box(width, height):
    """A box of Principled Volume (coloured, anisotropic) lit from behind by a point light."""
    scene = _base(width, height)
    scenes.set_world(scene, (0.03, 0.03, 0.04))
    vs.fog_box(
        scene,
        "Smoke",
        center=(0.0, 0.0, 1.2),
        size=(2.0, 2.0, 2.0),
        kind="PRINCIPLED",
        color=(0.9, 0.7, 0.5),
        density=0.8,
        anisotropy=0.5,
        **{"Absorption Color": (0.6, 0.6, 0.8, 1.0)},
    )
    scenes.light(scene, "Lamp", "POINT", 500.0, location=(0.4, 2.2, 1.6), shadow_soft_size=0.1)
    scenes.uv_sphere(scene, "Ball", center=(-1.6, -0.5, 0.5), radius=0.5, mat=scenes.material("Ball", (0.7, 0.2, 0.2)))
    scenes.look_at(scene, (0.8, -5.5, 1.6), (0.0, 0.0, 1.1))
    return scene


def world_fog(width, height):
    """A World > Volume (thin scattering) around a lamp, a pillar and a ball, the world's colour
    black: Cycles' world medium fills all space (no background or world light gets through it),
    Penumbra's the clip end's sphere, so a world of light would measure that choice, not the fog."""
    scene = _base(width, height)
    scenes.set_world(scene, (0.0, 0.0, 0.0))
    vs.world_volume(scene, density=0.04, anisotropy=0.2)
    scenes.box(
        scene, "Pillar", center=(0.8, 0.8, 1.0), size=(0.4, 0.4, 2.0), mat=scenes.material("Stone", (0.6, 0.6, 0.6))
    )
    scenes.uv_sphere(scene, "Ball", center=(-0.8, 0.2, 0.5), radius=0.5, mat=scenes.material("Ball", (0.2, 0.4, 0.7)))
    scenes.light(scene, "Lamp", "POINT", 800.0, location=(0.0, 2.0, 2.5), shadow_soft_size=0.05)
    cam = scenes.look_at(scene, (4.0, -6.0, 2.0), (0.0, 0.5, 0.9))
    cam.data.clip_end = 30.0
    return scene


SCENES = {"spot_gap": spot_gap, "sun_mist": sun_mist, "backlit_box": backlit_box, "world_fog": world_fog}


def cycles(scene, spp):
    """Cycles' single scattering: direct light only, Volume Bounces 0, enough transparent
    bounces for rays to cross the media's boxes, the same pixel filter as Penumbra's."""
    configure(scene, "CYCLES", samples=spp, transparent_max_bounces=16, volume_bounces=0)
    scene.cycles.pixel_filter_type = "BLACKMAN_HARRIS"
    scene.cycles.filter_width = scene.penumbra.filter_size


def reference(name, scene, spp):
    """Cycles' image of scene ``name`` at ``spp`` (display values), cached by Blender version,
    scene, size and spp (and this file's content)."""
    size = f"{scene.render.resolution_x}x{scene.render.resolution_y}"

    def make():
        cycles(scene, spp)
        return display(render(scene)["Combined"])

    return cached_image("volumes", __file__, f"{name}-{size}-{spp}", make)


def measure(scene, runs, ref):
    image = display(render(scene)["Combined"])  # also the warm-up
    return timing.render(runs, warmup=0).median, float(np.abs(image - ref).mean()), image


def sweep(name, width, height, spp, samples, cycles_spp, runs):
    """Rows of scene ``name`` and its (reference, Penumbra 64, EEVEE) images."""
    scene = SCENES[name](width, height)
    log(f"{name}: Cycles reference {spp} spp at {width}x{height}")
    ref = reference(name, scene, spp)
    rows, shown = [], [(f"Cycles {spp} spp", ref)]
    for n in samples:
        log(f"{name}: Penumbra {n}")
        configure(scene, "PENUMBRA", render_samples=n)
        seconds, mae, image = measure(scene, runs, ref)
        rows.append({"scene": name, "engine": "Penumbra", "samples": n, "time_s": seconds, "mae": mae})
        if n == 64 or (n == samples[-1] and len(shown) == 1):
            shown.append((f"Penumbra {n} samples", image))
    for n in cycles_spp:
        log(f"{name}: Cycles {n}")
        cycles(scene, n)
        seconds, mae, _image = measure(scene, runs, ref)
        rows.append({"scene": name, "engine": "Cycles", "samples": n, "time_s": seconds, "mae": mae})
    log(f"{name}: Penumbra 16, Volumes off (what the media cost)")
    configure(scene, "PENUMBRA", render_samples=16)
    scene.view_layers[0].use_volumes = False
    seconds, mae, _image = measure(scene, runs, ref)
    scene.view_layers[0].use_volumes = True
    rows.append({"scene": name, "engine": "Penumbra, Volumes off", "samples": 16, "time_s": seconds, "mae": mae})
    log(f"{name}: EEVEE")
    configure(scene, "EEVEE", taa_render_samples=EEVEE_SAMPLES)
    seconds, mae, image = measure(scene, runs, ref)
    rows.append({"scene": name, "engine": "EEVEE", "samples": EEVEE_SAMPLES, "time_s": seconds, "mae": mae})
    shown.append((f"EEVEE {EEVEE_SAMPLES}", image))
    return rows, shown


def plot(rows, shown, path, title):
    """Error against time per scene (top), and each scene's images below."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(shown)
    rows_of_images = max(len(v) for v in shown.values())
    fig, axes = plt.subplots(
        1 + rows_of_images, len(names), figsize=(4.5 * len(names), 3.2 * (1 + rows_of_images)), squeeze=False
    )
    styles = {"Penumbra": ("tab:blue", "-o"), "Cycles": ("tab:red", "-P"), "EEVEE": ("tab:purple", "*")}
    for col, name in enumerate(names):
        ax = axes[0, col]
        for engine, (colour, style) in styles.items():
            pts = sorted((r for r in rows if r["engine"] == engine and r["scene"] == name), key=lambda r: r["samples"])
            ax.plot([r["time_s"] for r in pts], [r["mae"] for r in pts], style, color=colour, label=engine)
            for r in pts:
                ax.annotate(
                    str(r["samples"]), (r["time_s"], r["mae"]), fontsize=7, xytext=(3, 3), textcoords="offset points"
                )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per frame (s, median, log)")
        ax.set_ylabel("display MAE vs the reference")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(name, fontsize=9)
        for row in range(rows_of_images):
            axes[row + 1, col].axis("off")
            if row < len(shown[name]):
                label, image = shown[name][row]
                axes[row + 1, col].imshow(image[::-1], interpolation="nearest")
                axes[row + 1, col].set_title(f"{name}: {label}", fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def run(args):
    width, height = (160, 90) if args.quick else (args.width, args.height)
    runs = 1 if args.quick else args.runs
    spp = 256 if args.quick else args.reference
    samples = [int(n) for n in ("4,16,64" if args.quick else args.samples).split(",") if n.strip()]
    cycles_spp = [int(n) for n in args.cycles_spp.split(",") if n.strip()]
    names = [n.strip() for n in args.scenes.split(",") if n.strip()]
    args.out.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()
    started = time.perf_counter()
    rows, shown = [], {}
    with session.stdout_to_stderr():
        for name in names:
            scene_rows, shown[name] = sweep(name, width, height, spp, samples, cycles_spp, runs)
            rows += scene_rows
    report.write_csv(args.out / "volumes.csv", rows, CSV_FIELDS)
    title = (
        f"Volumes (single scattering), {width}x{height}, against Cycles {spp} spp with Volume Bounces 0; "
        f"Blender {bpy.app.version_string}"
    )
    plot(rows, shown, args.out / "volumes.png", title)
    cells = [[r["scene"], r["engine"], r["samples"], f"{r['time_s']:.3f}", f"{r['mae']:.4f}"] for r in rows]
    print(f"### {title}\n")
    print(report.markdown_table(["Scene", "Engine", "Samples", "Time (s)", "Display MAE"], cells))
    print(
        f"\nGPU: {session.gpu_renderer() or 'n/a'}; {runs} timed render(s) per configuration; "
        f"{(time.perf_counter() - started) / 60:.1f} min. Wrote volumes.csv, volumes.png."
    )
    return 0
