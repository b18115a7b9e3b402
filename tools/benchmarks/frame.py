"""Render time: Penumbra against Blender's own engines on the demo scene.

Every engine renders the same demo scene (``devkit.scenes.demo_scene``) in this one process,
set up by ``devkit.engines`` (Penumbra with the scene's post layers; EEVEE, Workbench and
Cycles as described there). Each engine gets one warm-up render that is not counted (it pays
for shader compilation and first-time allocations), then ``--runs`` timed calls of
``bpy.ops.render.render(write_still=False)``. The machine is shared and noisy, so absolute
seconds only describe this run: the number to quote is each engine's median time divided by
Penumbra's median from the same run.

Writes ``<out>/benchmark.csv`` and prints a Markdown table (for the README) to stdout. Exits
with status 1 if any engine failed to render (its row is still written, with empty times).
"""

import argparse
import sys
from pathlib import Path

import bpy

from devkit import engines, report, scenes, session, timing

HELP = "render time of Penumbra, EEVEE, Workbench and Cycles on the demo scene"
ENGINES = ("PENUMBRA", "EEVEE", "WORKBENCH", "CYCLES")  # Penumbra first: it is the baseline
PENUMBRA_SAMPLES = 16
CSV_FIELDS = ["engine", "median_s", "min_s", "ratio_to_penumbra", "runs", "width", "height", "blender"]


def engine_list(text):
    keys = [e.strip().upper() for e in text.split(",") if e.strip()]
    unknown = sorted(set(keys) - set(ENGINES))
    if unknown:
        raise argparse.ArgumentTypeError(f"unknown engine(s): {', '.join(k.lower() for k in unknown)}")
    return keys


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder for benchmark.csv (default out)")
    timing.add_runs_argument(parser, 5, "timed renders per engine")
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=360)
    parser.add_argument(
        "--engines",
        type=engine_list,
        default=list(ENGINES),
        help="comma-separated subset of: " + ", ".join(e.lower() for e in ENGINES),
    )


def time_engine(engine, width, height, runs):
    """Build a fresh demo scene for one engine, render once to warm up, then time ``runs``
    renders."""
    scene = scenes.demo_scene(width, height)  # resets to factory settings: a clean scene per engine
    if not hasattr(bpy.types.Scene, "penumbra"):
        raise RuntimeError("Penumbra was unregistered by read_factory_settings")
    # Penumbra at its default 16 render samples, as EEVEE (16 TAA samples) and Cycles (16 spp).
    engines.configure(scene, engine, **({"render_samples": PENUMBRA_SAMPLES} if engine == "PENUMBRA" else {}))
    return timing.render(runs, warmup=1)


def markdown(rows, info):
    """A README-ready Markdown block: the table, then the conditions it was measured under."""
    cells = []
    for row in rows:
        if row["error"]:
            cells.append([row["engine"], "failed", "", ""])
            continue
        ratio = f"{row['ratio_to_penumbra']:.2f}x" if row["ratio_to_penumbra"] is not None else "n/a"
        cells.append([row["engine"], f"{row['median_s']:.3f}", f"{row['min_s']:.3f}", ratio])
    table = report.markdown_table(["Engine", "Median (s)", "Min (s)", "Time relative to Penumbra"], cells)
    return "\n".join(
        [
            table,
            "",
            f"Demo scene (`devkit/scenes.py`), {info['width']}x{info['height']}, {info['triangles']} triangles; "
            f"median and min of {info['runs']} timed renders after one warm-up render per engine.",
            f"Blender {info['blender']}; GPU: {info['gpu'] or 'n/a'}.",
            f"Penumbra: {PENUMBRA_SAMPLES} render samples. " + engines.SUMMARY,
            "Ratios come from one run on one machine; a ratio above 1 means slower than Penumbra.",
        ]
    )


def run(args):
    session.load_penumbra().register()
    scene = scenes.demo_scene(args.width, args.height)
    info = {
        "blender": bpy.app.version_string,
        "width": args.width,
        "height": args.height,
        "runs": args.runs,
        "triangles": scenes.triangle_count(scene),
        "gpu": None,
    }

    rows = []
    for engine in ENGINES:
        if engine not in args.engines:
            continue
        label = engines.LABELS[engine]
        row = {
            "engine": label,
            "median_s": None,
            "min_s": None,
            "ratio_to_penumbra": None,
            "error": None,
            "runs": args.runs,
            "width": args.width,
            "height": args.height,
            "blender": info["blender"],
        }
        print(f"bench frame: {label}: 1 warm-up + {args.runs} timed renders", file=sys.stderr, flush=True)
        try:
            with session.stdout_to_stderr():
                t = time_engine(engine, args.width, args.height, args.runs)
            row["median_s"], row["min_s"] = t.median, t.min
        except Exception as exc:  # keep going: one broken engine should not hide the others
            row["error"] = str(exc)
            print(f"bench frame: {label} failed: {exc}", file=sys.stderr, flush=True)
        info["gpu"] = info["gpu"] or session.gpu_renderer()
        rows.append(row)

    base = next((r["median_s"] for r in rows if r["engine"] == engines.LABELS["PENUMBRA"]), None)
    if base:
        for row in rows:
            if row["median_s"] is not None:
                row["ratio_to_penumbra"] = row["median_s"] / base

    args.out.mkdir(parents=True, exist_ok=True)
    report.write_csv(args.out / "benchmark.csv", rows, CSV_FIELDS)
    print()
    print(markdown(rows, info), flush=True)
    return 1 if any(r["error"] for r in rows) else 0
