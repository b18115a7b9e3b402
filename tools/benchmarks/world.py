"""The world's light with visibility: error against time on scenes lit by the world alone.

On ``devkit.world_scenes`` (``sky_outdoor``: objects on a ground under a uniform sky;
``sky_outdoor_hdri``: the same under a procedural HDRI rotated by a Mapping node;
``window_room``: a closed room lit through one window), in this one process:

- Penumbra at 1, 4, 16, 64 render samples with ``world_shadows`` on, and off (the world
  lighting every surface as if nothing blocked it: the "before"); in the room also with
  ``indirect_bounces = 1`` (one diffuse bounce). Settings go through ``scene.penumbra`` and
  are skipped, and named, where this build lacks them. Penumbra's Noise Threshold stays at
  the scene's (0.01), so a frame may end before its samples, as it does for a user.
- Cycles with max_bounces 0 (the world's direct light with visibility) at 1, 4, 16, 64 and
  128 spp; in the room also with one diffuse bounce. Same pixel filter as Penumbra
  (``reference_kit.matched_filter``), a light portal over the room's window.
- In the rooms, Cycles again without its light portals (what a user without portals gets).
- EEVEE once, as ``devkit.engines`` sets it up (16 TAA samples; no light probe baked).

Error: the mean absolute difference of display-referred RGB (the 'Standard' view, 0..1, every
pixel) against Cycles at 512 spp (256 with --quick) with another seed, cached in
out/reference_cache (``world_scenes.cycles_reference``; rendered when missing). Each render
is compared with the reference of the light it computes: direct light, or one bounce for
the bounce configurations (EEVEE: both in the room; its plotted point is the direct one).
Time: the median of ``--runs`` F12 renders (``bpy.ops.render.render``) after the measured
render, which is the warm-up.

-> ``<out>/world.csv`` and ``<out>/world.png`` (error against time, log-log, one panel per
scene); a Markdown table to stdout. ``--quick``: 160x90, fewer sample counts.
"""

import dataclasses
import sys
import time
from pathlib import Path

import bpy
import numpy as np

from devkit import report, session, timing
from devkit import world_scenes as ws
from devkit.engines import EEVEE_SAMPLES

HELP = "world light with visibility: error against time, Penumbra (shadows on/off, bounce) vs Cycles and EEVEE"


@dataclasses.dataclass(frozen=True)
class Plan:
    scenes: tuple
    samples: tuple  # Penumbra render samples, world shadows on (and the bounce)
    before_samples: tuple  # Penumbra render samples with world shadows off
    cycles_spp: tuple
    reference_spp: int
    width: int
    height: int
    runs: int


FULL = Plan(
    scenes=tuple(ws.SCENES),
    samples=(1, 4, 16, 64),
    before_samples=(1, 4, 16, 64),
    cycles_spp=(1, 4, 16, 64, 128),
    reference_spp=512,
    width=320,
    height=180,
    runs=1,
)
QUICK = Plan(
    scenes=tuple(ws.SCENES),
    samples=(1, 16, 64),
    before_samples=(1, 64),
    cycles_spp=(1, 16, 128),
    reference_spp=256,
    width=160,
    height=90,
    runs=1,
)

FIELDS = ["scene", "config", "engine", "samples", "light", "time_s", "mae", "mae_direct", "mae_bounce1", "skipped"]
SHADOWS_ON = "Penumbra"
SHADOWS_OFF = "Penumbra, world shadows off"
BOUNCE = "Penumbra, 1 bounce"
CYCLES = "Cycles"
CYCLES_BOUNCE = "Cycles, 1 bounce"
CYCLES_BARE = "Cycles, no portal"
EEVEE = f"EEVEE ({EEVEE_SAMPLES} TAA)"


def log(message):
    print(f"bench world: {message}", file=sys.stderr, flush=True)


def configs(plan, name):
    """(config label, engine, samples, light, settings) of every render of scene ``name``."""
    out = []
    for n in plan.samples:
        out.append((SHADOWS_ON, "PENUMBRA", n, "direct", {"render_samples": n, "world_shadows": True}))
    for n in plan.before_samples:
        out.append((SHADOWS_OFF, "PENUMBRA", n, "direct", {"render_samples": n, "world_shadows": False}))
    if name in ws.INDOOR:
        for n in plan.samples:
            settings = {"render_samples": n, "world_shadows": True, "indirect_bounces": 1}
            out.append((BOUNCE, "PENUMBRA", n, "bounce1", settings))
    for n in plan.cycles_spp:
        out.append((CYCLES, "CYCLES", n, "direct", {"samples": n, "bounces": 0}))
    if name in ws.PORTALLED:  # what a user without portals gets from Cycles
        for n in plan.cycles_spp:
            out.append((CYCLES_BARE, "CYCLES", n, "direct", {"samples": n, "bounces": 0, "portals": False}))
    if name in ws.INDOOR:
        for n in plan.cycles_spp:
            out.append((CYCLES_BOUNCE, "CYCLES", n, "bounce1", {"samples": n, "bounces": 1}))
    out.append((EEVEE, "EEVEE", EEVEE_SAMPLES, "direct", {}))
    return out


def sweep(plan, cache):
    rows, identical = [], []
    for name in plan.scenes:
        w, h = plan.width, plan.height
        refs = {}
        for light, bounces in (("direct", 0), ("bounce1", 1)):
            if light == "bounce1" and name not in ws.INDOOR:
                continue
            log(f"{name}: Cycles reference, {light}, {plan.reference_spp} spp at {w}x{h}")
            refs[light] = ws.cycles_reference(name, plan.reference_spp, w, h, bounces=bounces, cache_dir=cache)
        scene = ws.build(name, w, h)
        images = {}
        for label, engine, n, light, settings in configs(plan, name):
            log(f"{name}: {label}, {n}")
            skipped = ws.use_engine(scene, engine, **settings)
            image = ws.render_display(scene)
            seconds = timing.render(plan.runs, warmup=0).median
            images[label, n] = image
            errors = {k: ws.mae(image, ref) for k, ref in refs.items()}
            rows.append(
                {
                    "scene": name,
                    "config": label,
                    "engine": engine.title() if engine != "EEVEE" else "EEVEE",
                    "samples": n,
                    "light": light,
                    "time_s": seconds,
                    "mae": errors[light],
                    "mae_direct": errors["direct"],
                    "mae_bounce1": errors.get("bounce1"),
                    "skipped": " ".join(skipped),
                }
            )
            log(f"  {rows[-1]}")
        # (A one-sample frame takes the ambient occlusion either way: only frames of several
        # samples take the world's directions.)
        for n in set(plan.samples) & set(plan.before_samples) - {1}:
            if np.array_equal(images[SHADOWS_ON, n], images[SHADOWS_OFF, n]):
                identical.append((name, n))
    return rows, identical


def plot(rows, path, plan):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    styles = {
        SHADOWS_ON: ("tab:blue", "-o"),
        SHADOWS_OFF: ("tab:gray", "--o"),
        BOUNCE: ("tab:cyan", "-s"),
        CYCLES: ("tab:red", "-P"),
        CYCLES_BOUNCE: ("tab:orange", "--P"),
        CYCLES_BARE: ("tab:red", ":x"),
    }
    fig, axes = plt.subplots(1, len(plan.scenes), figsize=(5.2 * len(plan.scenes), 4.6), squeeze=False)
    for ax, name in zip(axes[0], plan.scenes, strict=True):
        for label, (colour, style) in styles.items():
            pts = sorted((r for r in rows if r["scene"] == name and r["config"] == label), key=lambda r: r["samples"])
            if not pts:
                continue
            reference = "one-bounce" if pts[0]["light"] == "bounce1" else "direct"
            ax.plot(
                [r["time_s"] for r in pts],
                [max(r["mae"], 1e-5) for r in pts],
                style,
                color=colour,
                label=f"{label} (vs {reference})",
            )
            for r in pts:
                ax.annotate(
                    str(r["samples"]), (r["time_s"], max(r["mae"], 1e-5)), fontsize=7, xytext=(3, 3),
                    textcoords="offset points", color=colour,
                )  # fmt: skip
        for r in (r for r in rows if r["scene"] == name and r["config"] == EEVEE):
            ax.plot([r["time_s"]], [r["mae_direct"]], "*", color="tab:purple", ms=12, label=f"{EEVEE} (vs direct)")
            if r["mae_bounce1"] is not None:
                ax.plot(
                    [r["time_s"]], [r["mae_bounce1"]], "*", mfc="none", color="tab:purple", ms=12,
                    label=f"{EEVEE} (vs one-bounce)",
                )  # fmt: skip
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(name, fontsize=10)
        ax.set_xlabel("time per frame (s, median, log)")
        ax.set_ylabel(f"display RGB MAE vs Cycles {plan.reference_spp} spp")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(
        f"World light with visibility: error against time, {plan.width}x{plan.height}, "
        f"Blender {bpy.app.version_string}",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(rows):
    cells = []
    for r in rows:
        bounce = "" if r["mae_bounce1"] is None else f"{r['mae_bounce1']:.4f}"
        cells.append([r["scene"], r["config"], r["samples"], f"{r['time_s']:.3f}", f"{r['mae_direct']:.4f}", bounce])
    header = ["Scene", "Configuration", "Samples", "Time (s)", "MAE vs direct", "MAE vs one bounce"]
    return report.markdown_table(header, cells, align="llrrrr")


def parse_size(text):
    try:
        w, h = (int(x) for x in text.lower().split("x"))
    except ValueError:
        raise SystemExit(f"bench world: --size takes WIDTHxHEIGHT, not {text!r}") from None
    return w, h


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default out)")
    timing.add_runs_argument(parser, 1, "timed renders per configuration, after the measured one")
    parser.add_argument("--quick", action="store_true", help="160x90, fewer sample counts, 256 spp references")
    parser.add_argument("--size", default=None, help="WIDTHxHEIGHT (default 320x180; 160x90 with --quick)")
    parser.add_argument("--scenes", default=None, help=f"comma-separated subset of {', '.join(ws.SCENES)}")
    parser.add_argument("--reference-spp", type=int, default=None, help="Cycles reference spp (512; 256 --quick)")
    parser.add_argument("--cache", type=Path, default=ws.CACHE, help="Cycles reference cache folder")


def run(args):
    plan = QUICK if args.quick else FULL
    changes = {"runs": args.runs}
    if args.size:
        changes["width"], changes["height"] = parse_size(args.size)
    if args.scenes:
        names = tuple(n.strip() for n in args.scenes.split(",") if n.strip())
        unknown = sorted(set(names) - set(ws.SCENES))
        if unknown:
            raise SystemExit(f"bench world: unknown scene(s) {', '.join(unknown)}; known: {', '.join(ws.SCENES)}")
        changes["scenes"] = names
    if args.reference_spp:
        changes["reference_spp"] = args.reference_spp
    plan = dataclasses.replace(plan, **changes)
    args.out.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()
    started = time.perf_counter()
    with session.stdout_to_stderr():
        rows, identical = sweep(plan, args.cache)
    report.write_csv(args.out / "world.csv", rows, FIELDS)
    plot(rows, args.out / "world.png", plan)
    print(
        f"### World light with visibility ({plan.width}x{plan.height}; display RGB MAE against Cycles "
        f"{plan.reference_spp} spp, direct light and, in the room, one diffuse bounce)\n"
    )
    print(markdown(rows))
    skipped = sorted({s for r in rows for s in r["skipped"].split()})
    if skipped:
        print(f"\nNot in this build, skipped: {', '.join(skipped)}.")
    if identical:
        pairs = ", ".join(f"{name} at {n}" for name, n in identical)
        print(f"\nWorld shadows on and off gave identical images ({pairs}): no direction of the world was drawn.")
    print(
        f"\nBlender {bpy.app.version_string}; GPU: {session.gpu_renderer() or 'n/a'}; median of {plan.runs} "
        f"F12 render(s) per configuration after the measured one; {(time.perf_counter() - started) / 60:.1f} min. "
        f"Wrote {args.out / 'world.csv'} and {args.out / 'world.png'}."
    )
    return 0
