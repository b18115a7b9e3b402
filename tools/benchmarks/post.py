"""Cost of each post layer, and the separable blur against a direct 2-D kernel.

The input is the demo scene rendered by Penumbra at the given size. Each effect runs alone with
its default parameters (mix 1); the whole stack runs every effect in menu order. A run is timed
from the first pass to a one-pixel read-back of the result (which waits for the GPU), median of
``--runs`` after one warm-up (``devkit.timing``). Machines here are shared and noisy, so the
figure to quote is the ratio to a bare full-screen pass (one texel fetch and write per pixel,
``shaders/copy.frag.glsl`` beside this module) timed in the same run.

Writes ``<out>/post_costs.csv`` and prints Markdown tables.
"""

import argparse
from pathlib import Path
from types import SimpleNamespace

import bpy

from devkit import report, scenes, session, timing

HELP = "cost of each post layer; separable against direct 2-D blur"
SHADERS = Path(__file__).resolve().parent / "shaders"
CSV_FIELDS = ["effect", "passes", "median_ms", "ratio_to_bare_pass", "width", "height", "runs"]


def radius_list(text):
    try:
        radii = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        radii = []
    if not radii or min(radii) < 0:
        raise argparse.ArgumentTypeError(f"expected comma-separated radii such as 2,4,8, not {text!r}")
    return radii


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder for post_costs.csv (default out)")
    timing.add_runs_argument(parser, 7, "timed runs per layer")
    parser.add_argument("--width", type=int, default=1920)
    parser.add_argument("--height", type=int, default=1080)
    parser.add_argument(
        "--radii",
        type=radius_list,
        default=[2, 4, 8, 16],
        help="blur radii of the separable/2-D comparison (default 2,4,8,16)",
    )


def measure(runner, scene, w, h, runs, radii):
    """(bare pass seconds, [(effect, passes, seconds)], [blur rows], GPU renderer) measured in
    one GPU context."""

    def job(engine, depsgraph):
        import gpu

        from penumbra.engine.frame.stats import FrameStats
        from penumbra.engine.post import EFFECTS, PostContext, base, post_stack
        from penumbra.engine.post.base import GAUSSIAN_VEC4S, GAUSSIAN_WEIGHTS, GaussianWeights, post_program
        from penumbra.engine.scene.extract import camera_from_scene

        frame = engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, w, h), w, h)
        src = frame.color
        stack = post_stack()
        ctx = PostContext(engine.renderer.shaders, w, h, frame=1, stats=FrameStats())

        def timed(draw):
            def once():
                fb = gpu.types.GPUFrameBuffer(color_slots=(draw(),))
                with fb.bind():
                    fb.read_color(0, 0, 1, 1, 4, 0, "FLOAT")  # waits for the GPU

            return timing.measure(once, runs, warmup=1).median

        copy = post_program("tool_copy", str(SHADERS / "copy.frag.glsl"))
        bare = timed(
            lambda: ctx.fullscreen(copy, ctx.acquire(src), samplers={"source_tex": src}, uniforms={"mix_factor": 1.0})
        )

        rows = []
        for eid, cls in EFFECTS.items():
            layer = [(eid, True, 1.0, cls.defaults())]
            passes_before = ctx.stats.post_passes
            stack.run(ctx, src, layer)
            passes = ctx.stats.post_passes - passes_before
            rows.append((eid, passes, timed(lambda: stack.run(ctx, src, layer))))
        # The half-resolution paths of GLOW and BLUR at the same (default) parameters, and BLUR
        # at radius 16 both ways.
        wide = {"radius": 16}
        for eid, extra, name in (
            ("GLOW", {}, "GLOW, half resolution"),
            ("BLUR", {}, "BLUR, half resolution"),
            ("BLUR", wide, "BLUR (radius 16)"),
            ("BLUR", wide, "BLUR (radius 16), half resolution"),
        ):
            half = "half" in name
            params = SimpleNamespace(**{**vars(EFFECTS[eid].defaults()), **extra, "half_resolution": half})
            layer = [(eid, True, 1.0, params)]
            passes_before = ctx.stats.post_passes
            stack.run(ctx, src, layer)
            passes = ctx.stats.post_passes - passes_before
            rows.append((name, passes, timed(lambda layer=layer: stack.run(ctx, src, layer))))
        everything = [(eid, True, 1.0, cls.defaults()) for eid, cls in EFFECTS.items()]
        # The point layers stacked: one shared pass (as the stack runs them), then one pass each.
        points = [layer for layer in everything if issubclass(EFFECTS[layer[0]], base.PointEffect)]
        for fuse, how in ((True, "in one pass"), (False, "one pass each")):
            base.FUSE_POINT_LAYERS = fuse
            try:
                passes_before = ctx.stats.post_passes
                stack.run(ctx, src, points)
                passes = ctx.stats.post_passes - passes_before
                name = f"{' + '.join(layer[0] for layer in points)}, {how}"
                rows.append((name, passes, timed(lambda: stack.run(ctx, src, points))))
            finally:
                base.FUSE_POINT_LAYERS = True
        rows.append(("whole stack", None, timed(lambda: stack.run(ctx, src, everything))))

        naive = post_program(
            "tool_naive_blur",
            str(SHADERS / "naive_blur.frag.glsl"),
            push_constants=(("INT", "radius"),),
            uniform_blocks=((GAUSSIAN_WEIGHTS, "weights", GAUSSIAN_VEC4S),),
        )
        weights = GaussianWeights()  # the separable blur's normalised 1-D weights
        blur_rows = []
        for r in radii:
            ubo = weights.get(r)
            layer = [("BLUR", True, 1.0, SimpleNamespace(**{**vars(EFFECTS["BLUR"].defaults()), "radius": r}))]
            sep = timed(lambda: stack.run(ctx, src, layer))
            direct = timed(
                lambda: ctx.fullscreen(
                    naive,
                    ctx.acquire(src),
                    samplers={"source_tex": src},
                    uniforms={"mix_factor": 1.0, "radius": r},
                    blocks={"weights": ubo},
                )
            )
            blur_rows.append((r, 2 * (2 * r + 1), (2 * r + 1) ** 2, sep, direct))
        return bare, rows, blur_rows, gpu.platform.renderer_get()

    return runner(job)


def run(args):
    out_dir = args.out.resolve()
    out_dir.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()
    runner = session.GpuRunner()
    runner.register()
    w, h = args.width, args.height
    try:
        scene = scenes.demo_scene(w, h)
        scene.penumbra.layers.clear()
        with session.stdout_to_stderr():
            bare, rows, blur_rows, renderer = measure(runner, scene, w, h, args.runs, args.radii)
    finally:
        runner.unregister()

    common = {"width": w, "height": h, "runs": args.runs}
    csv_rows = [
        {"effect": "bare pass", "passes": 1, "median_ms": round(bare * 1e3, 3), "ratio_to_bare_pass": 1.0, **common}
    ]
    csv_rows += [
        {
            "effect": eid,
            "passes": passes,
            "median_ms": round(t * 1e3, 3),
            "ratio_to_bare_pass": round(t / bare, 2),
            **common,
        }
        for eid, passes, t in rows
    ]
    report.write_csv(out_dir / "post_costs.csv", csv_rows, CSV_FIELDS)

    print(
        f"Post layers at {w}x{h}, default parameters, median of {args.runs} runs; {renderer}; "
        f"Blender {bpy.app.version_string}\n"
    )
    layer_rows = [["bare full-screen pass", 1, f"{bare * 1e3:.1f}", "1.00"]]
    layer_rows += [
        [eid, "" if passes is None else passes, f"{t * 1e3:.1f}", f"{t / bare:.2f}"] for eid, passes, t in rows
    ]
    print(report.markdown_table(["Layer", "Passes", "Median (ms)", "Cost / bare pass"], layer_rows))
    print("\nSeparable blur (two 1-D passes) against a direct 2-D kernel of the same radius:\n")
    print(
        report.markdown_table(
            ["Radius", "Taps separable", "Taps 2-D", "Separable (ms)", "2-D (ms)", "2-D / separable"],
            [
                [r, sep_taps, taps_2d, f"{sep * 1e3:.1f}", f"{direct * 1e3:.1f}", f"{direct / sep:.2f}"]
                for r, sep_taps, taps_2d, sep, direct in blur_rows
            ],
            align="rrrrrr",
        )
    )
    return 0
