"""Cost of each post layer, and the separable blur against a direct 2-D kernel.

    .venv/blender-5.2/bin/python tools/post_benchmark.py --out out [--runs 7] [--width 1920 --height 1080]

The input is the demo scene rendered by Penumbra at the given size. Each effect runs alone with
its default parameters (mix 1); the whole stack runs every effect in menu order. A run is timed
from the first pass to a one-pixel read-back of the result (which waits for the GPU), median of
``--runs`` after one warm-up. Machines here are shared and noisy, so the figure to quote is the
ratio to a bare full-screen pass (one texel fetch and write per pixel) timed in the same run.
Writes ``<out>/post_costs.csv`` and prints Markdown tables.
"""

import argparse
import csv
import os
import statistics
import sys
import time
from pathlib import Path
from types import SimpleNamespace

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tools")]

import bpy  # noqa: E402

import scenes  # noqa: E402
from devkit import GpuRunner, load_penumbra  # noqa: E402

TOOL_SHADERS = Path(__file__).resolve().parent / "shaders"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out")
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--width", type=int, default=1920)
    ap.add_argument("--height", type=int, default=1080)
    ap.add_argument("--radii", default="2,4,8,16")
    args = ap.parse_args()
    out_dir = Path(args.out).resolve()
    out_dir.mkdir(parents=True, exist_ok=True)

    load_penumbra().register()
    runner = GpuRunner()
    runner.register()
    scene = scenes.demo_scene(args.width, args.height)
    scene.penumbra.layers.clear()
    w, h = args.width, args.height

    def job(engine, depsgraph):
        import gpu
        import numpy as np
        from penumbra.engine import kernels
        from penumbra.engine.extract import camera_from_scene
        from penumbra.engine.post import EFFECTS, PostContext, PostStack
        from penumbra.engine.post.base import post_program
        from penumbra.engine.post.blur import WEIGHT_VEC4S, WEIGHTS
        from penumbra.engine.renderer import FrameStats

        frame = engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, w, h), w, h)
        src = frame.color
        stack = PostStack()
        ctx = PostContext(engine.renderer.shaders, w, h, frame=1, stats=FrameStats())

        def timed(run):
            run()  # warm-up: shader compilation, target allocation
            times = []
            for _ in range(args.runs):
                t = time.perf_counter()
                tex = run()
                fb = gpu.types.GPUFrameBuffer(color_slots=(tex,))
                with fb.bind():
                    fb.read_color(0, 0, 1, 1, 4, 0, "FLOAT")  # waits for the GPU
                times.append(time.perf_counter() - t)
            return statistics.median(times)

        copy = post_program("tool_copy", str(TOOL_SHADERS / "copy.frag.glsl"))
        bare = timed(lambda: ctx.fullscreen(copy, ctx.acquire(src), samplers={"source_tex": src}, uniforms={"mix_factor": 1.0}))

        rows = []
        for eid, cls in EFFECTS.items():
            layer = [(eid, True, 1.0, cls.defaults())]
            passes_before = ctx.stats.post_passes
            stack.run(ctx, src, layer)
            passes = ctx.stats.post_passes - passes_before
            rows.append((eid, passes, timed(lambda: stack.run(ctx, src, layer))))
        everything = [(eid, True, 1.0, cls.defaults()) for eid, cls in EFFECTS.items()]
        rows.append(("whole stack", None, timed(lambda: stack.run(ctx, src, everything))))

        naive = post_program(
            "tool_naive_blur",
            str(TOOL_SHADERS / "naive_blur.frag.glsl"),
            push_constants=(("INT", "radius"),),
            uniform_blocks=((WEIGHTS, "weights", WEIGHT_VEC4S),),
        )
        blur_rows = []
        for r in (int(x) for x in args.radii.split(",")):
            packed = np.zeros(WEIGHT_VEC4S * 4, np.float32)
            wts = kernels.gaussian_1d(r)
            packed[: len(wts)] = wts
            ubo = gpu.types.GPUUniformBuf(packed.tobytes())
            layer = [("BLUR", True, 1.0, SimpleNamespace(radius=r, sigma=0.0))]
            sep = timed(lambda: stack.run(ctx, src, layer))
            direct = timed(
                lambda: ctx.fullscreen(
                    naive, ctx.acquire(src), samplers={"source_tex": src}, uniforms={"mix_factor": 1.0, "radius": r}, blocks={"weights": ubo}
                )
            )
            blur_rows.append((r, 2 * (2 * r + 1), (2 * r + 1) ** 2, sep, direct))
        return bare, rows, blur_rows, gpu.platform.renderer_get()

    bare, rows, blur_rows, renderer = runner(job)

    with open(out_dir / "post_costs.csv", "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["effect", "passes", "median_ms", "ratio_to_bare_pass", "width", "height", "runs"])
        wr.writerow(["bare pass", 1, f"{bare * 1e3:.3f}", "1.00", w, h, args.runs])
        for eid, passes, t in rows:
            wr.writerow([eid, "" if passes is None else passes, f"{t * 1e3:.3f}", f"{t / bare:.2f}", w, h, args.runs])

    print(f"Post layers at {w}x{h}, default parameters, median of {args.runs} runs; {renderer}; Blender {bpy.app.version_string}\n")
    print("| Layer | Passes | Median (ms) | Cost / bare pass |")
    print("|---|---:|---:|---:|")
    print(f"| bare full-screen pass | 1 | {bare * 1e3:.1f} | 1.00 |")
    for eid, passes, t in rows:
        print(f"| {eid} | {'' if passes is None else passes} | {t * 1e3:.1f} | {t / bare:.2f} |")
    print("\nSeparable blur (two 1-D passes) against a direct 2-D kernel of the same radius:\n")
    print("| Radius | Taps separable | Taps 2-D | Separable (ms) | 2-D (ms) | 2-D / separable |")
    print("|---:|---:|---:|---:|---:|---:|")
    for r, taps_sep, taps_2d, sep, direct in blur_rows:
        print(f"| {r} | {taps_sep} | {taps_2d} | {sep * 1e3:.1f} | {direct * 1e3:.1f} | {direct / sep:.2f} |")
    runner.unregister()


if __name__ == "__main__":
    main()
    sys.stdout.flush()
    os._exit(0)  # bpy 4.5 can hang in its own shutdown after GPU work
