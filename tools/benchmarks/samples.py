"""Render samples against path-traced samples: what each buys in error, and what it costs.

On the reference kit's scenes (``devkit.reference_kit``), Penumbra at its defaults with
``render_samples`` 1, 4, 16, 64 (and 256 in a full run), Cycles at 1 ... 64 spp and EEVEE
(16 TAA samples) render the same frame in this one process. For each: the median time of
``--runs`` renders after a warm-up, the shadow error (visibility MAE and IoU against Cycles
at the reference spp, as in ``bench shadows``) and the whole-image error (luminance MAE
against that Cycles reference, relative to its mean). Also the cost of one extra sample as a
ratio to the first, and a close-up of an edge at 1 and 16 samples.

Writes ``<out>/samples.csv``, ``<out>/samples.png`` (error against time) and
``<out>/samples_closeup.png``; Markdown tables to stdout. ``--quick``: three scenes at
160x90, Penumbra up to 64 samples (about 5 minutes, Cycles references cached).
"""

import sys
import time
from pathlib import Path

import bpy
import numpy as np

from devkit import reference_kit as kit
from devkit import report, session, timing
from devkit.engines import EEVEE_SAMPLES, configure

HELP = "render samples: error against time vs Cycles spp and EEVEE, cost per sample, edge close-up"

FULL = {
    "scenes": kit.LIGHT_SCENES,
    "samples": (1, 4, 16, 64, 256),
    "cycles_spp": (1, 4, 16, 64),
    "reference_spp": 512,
    "size": (480, 270),
    "runs": 3,
}
QUICK = {
    "scenes": ("sun_soft", "spot", "area"),
    "samples": (1, 4, 16, 64),
    "cycles_spp": (1, 4, 16, 64),
    "reference_spp": 256,
    "size": (160, 90),
    "runs": 1,
}
CSV_FIELDS = ["scene", "engine", "samples", "time_s", "shadow_mae", "shadow_iou", "image_mae"]


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default out)")
    timing.add_runs_argument(parser, None, "timed renders per configuration (default 3; 1 with --quick)")
    parser.add_argument("--quick", action="store_true", help="three scenes at 160x90, up to 64 samples")
    parser.add_argument("--cache", type=Path, default=kit.DEFAULT_CACHE, help="Cycles reference cache folder")
    parser.add_argument("--width", type=int, default=None, help="frame width (480; 160 with --quick)")
    parser.add_argument("--height", type=int, default=None, help="frame height (270; 90 with --quick)")
    parser.add_argument("--scenes", default=None, help="comma-separated reference scenes (default: the plan's)")
    parser.add_argument("--samples", default=None, help="comma-separated Penumbra sample counts (default: the plan's)")
    parser.add_argument("--cycles-spp", default=None, help="comma-separated Cycles spp to time (default: the plan's)")
    parser.add_argument(
        "--sweep-only", action="store_true", help="only the error/time sweep: no demo-scene cost, no close-up"
    )
    parser.add_argument(
        "--noise-threshold",
        type=float,
        default=None,
        help="Penumbra's Noise Threshold (default: the scene's, 0.01; 0: no settling, no noise check)",
    )


def log(message):
    print(f"bench samples: {message}", file=sys.stderr, flush=True)


def measure(scene, engine, runs, vis_ref, lum_ref, **settings):
    """(median seconds, shadow compare dict, relative whole-image MAE) of one configuration."""
    configure(scene, engine, **settings)
    light = kit.scene_light(scene).data
    light.use_shadow = False
    unshadowed = kit.render_luminance(scene)
    light.use_shadow = True
    shadowed = kit.render_luminance(scene)  # also the warm-up
    seconds = timing.render(runs, warmup=0).median
    score = kit.compare(kit.visibility_from(shadowed, unshadowed), vis_ref)
    image = float(np.abs(shadowed - lum_ref).mean() / max(lum_ref.mean(), 1e-12))
    return seconds, score, image


def sweep(plan, cache):
    w, h = plan["size"]
    rows = []
    for name in plan["scenes"]:
        log(f"{name}: Cycles reference {plan['reference_spp']} spp at {w}x{h}")
        vis_ref = kit.cycles_reference(name, plan["reference_spp"], w, h, cache)
        lum_ref = kit.cycles_luminance(name, plan["reference_spp"], w, h, cache)
        scene = kit.build(name, w, h)
        penumbra = {} if plan.get("threshold") is None else {"adaptive_threshold": plan["threshold"]}
        configs = [("Penumbra", n, "PENUMBRA", {"render_samples": n, **penumbra}) for n in plan["samples"]]
        configs += [("Cycles", n, "CYCLES", {"samples": n}) for n in plan["cycles_spp"]]
        configs += [("EEVEE", EEVEE_SAMPLES, "EEVEE", {"taa_render_samples": EEVEE_SAMPLES})]
        for label, n, engine, settings in configs:
            log(f"{name}: {label} {n}")
            seconds, score, image = measure(scene, engine, plan["runs"], vis_ref, lum_ref, **settings)
            rows.append(
                {
                    "scene": name,
                    "engine": label,
                    "samples": n,
                    "time_s": seconds,
                    "shadow_mae": score["mae"],
                    "shadow_iou": score["iou"],
                    "image_mae": image,
                }
            )
    return rows


def mean_rows(rows):
    groups = {}
    for r in rows:
        groups.setdefault((r["engine"], r["samples"]), []).append(r)
    out = []
    for (engine, n), group in groups.items():
        out.append(
            {
                "scene": "mean",
                "engine": engine,
                "samples": n,
                **{
                    k: float(np.mean([g[k] for g in group]))
                    for k in ("time_s", "shadow_mae", "shadow_iou", "image_mae")
                },
            }
        )
    return out


def plot(means, path, plan):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    styles = {"Penumbra": ("tab:blue", "-o"), "Cycles": ("tab:red", "-P"), "EEVEE": ("tab:purple", "*")}
    for ax, key, title in ((axes[0], "shadow_mae", "shadow visibility MAE"), (axes[1], "image_mae", "image MAE")):
        for engine, (colour, style) in styles.items():
            pts = sorted((r for r in means if r["engine"] == engine), key=lambda r: r["samples"])
            ax.plot([r["time_s"] for r in pts], [r[key] for r in pts], style, color=colour, label=engine)
            for r in pts:
                ax.annotate(
                    str(r["samples"]), (r["time_s"], r[key]), fontsize=7, xytext=(3, 3), textcoords="offset points"
                )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per frame (s, median, log)")
        ax.set_ylabel(f"{title} vs Cycles {plan['reference_spp']} spp")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    w, h = plan["size"]
    fig.suptitle(
        f"Samples against error, mean over {len(plan['scenes'])} scenes, {w}x{h}, Blender {bpy.app.version_string}"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def sample_cost(plan, width=960, height=540):
    """Seconds of one sample and of each further sample (median), demo scene."""
    from devkit import scenes

    scene = scenes.demo_scene(width, height)
    scene.penumbra.layers.clear()
    scene.objects["Spot"].data.shadow_soft_size = 0.3
    times = {}
    for n in (1, 16):
        configure(scene, "PENUMBRA", render_samples=n)
        times[n] = timing.render(max(plan["runs"], 3), warmup=1).median
    return times[1], (times[16] - times[1]) / 15


def closeup(path, size=(96, 54), crop=(28, 10, 40, 24), zoom=8):
    """The demo scene's crate edge at 1 and 16 samples, side by side, enlarged without
    smoothing (display-referred PNG)."""
    from devkit import scenes
    from devkit.imageio import write_png

    scene = scenes.demo_scene(*size)
    scene.penumbra.layers.clear()
    scene.view_settings.view_transform = "Standard"
    panels = []
    for n in (1, 16):
        scene.penumbra.render_samples = n
        img = kit.render(scene)["Combined"][::-1]  # top row first
        x, y, cw, ch = crop
        tile = np.clip(img[y : y + ch, x : x + cw, :3], 0, 1) ** (1 / 2.2)
        panels.append(np.kron(tile, np.ones((zoom, zoom, 1))))
    gap = np.ones((panels[0].shape[0], 4, 3))
    write_png(path, np.concatenate([panels[0], gap, panels[1]], axis=1))


def run(args):
    plan = dict(QUICK if args.quick else FULL)
    if args.runs:
        plan["runs"] = args.runs
    if args.width or args.height:
        plan["size"] = (args.width or plan["size"][0], args.height or plan["size"][1])
    if args.scenes:
        plan["scenes"] = tuple(name.strip() for name in args.scenes.split(",") if name.strip())
    if args.samples:
        plan["samples"] = tuple(int(n) for n in args.samples.split(","))
    plan["threshold"] = args.noise_threshold
    if args.cycles_spp:
        plan["cycles_spp"] = tuple(int(n) for n in args.cycles_spp.split(","))
    args.out.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()
    started = time.perf_counter()
    with session.stdout_to_stderr():
        rows = sweep(plan, args.cache)
        if not args.sweep_only:
            first, extra = sample_cost(plan)
            closeup(args.out / "samples_closeup.png")
    means = mean_rows(rows)
    report.write_csv(args.out / "samples.csv", rows + means, CSV_FIELDS)
    plot(means, args.out / "samples.png", plan)
    cells = [
        [
            r["engine"],
            r["samples"],
            f"{r['time_s']:.3f}",
            f"{r['shadow_mae']:.4f}",
            f"{r['shadow_iou']:.3f}",
            f"{r['image_mae']:.4f}",
        ]
        for r in sorted(means, key=lambda r: (r["engine"], r["samples"]))
    ]
    w, h = plan["size"]
    scenes = ", ".join(plan["scenes"])
    print(f"### Samples against error (mean over {scenes}; {w}x{h}; Cycles {plan['reference_spp']} spp reference)\n")
    print(report.markdown_table(["Engine", "Samples", "Time (s)", "Shadow MAE", "Shadow IoU", "Image MAE"], cells))
    per_scene = [
        [r["scene"], r["engine"], r["samples"], f"{r['time_s']:.3f}", f"{r['shadow_mae']:.4f}"]
        + [f"{r['shadow_iou']:.3f}"]
        for r in rows
    ]
    columns = ["Scene", "Engine", "Samples", "Time (s)", "Shadow MAE", "Shadow IoU"]
    print("\n" + report.markdown_table(columns, per_scene))
    if not args.sweep_only:
        print(
            f"\nOne sample of the demo scene at 960x540 (soft spot): {first * 1e3:.0f} ms; each further sample "
            f"{extra * 1e3:.0f} ms ({extra / first:.2f}x the first)."
        )
    print(
        f"\nBlender {bpy.app.version_string}; GPU: {session.gpu_renderer() or 'n/a'}; {plan['runs']} timed render(s) "
        f"per configuration; {(time.perf_counter() - started) / 60:.1f} min. Wrote samples.csv, samples.png, "
        "samples_closeup.png."
    )
    return 0
