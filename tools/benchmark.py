"""Render-time benchmark: Penumbra against Blender's own engines on the demo scene.

Usage (from the repository root, with a Blender-as-a-module venv)::

    python tools/benchmark.py --out out [--runs 5] [--width 640 --height 360]

Every engine renders the same demo scene (``tools/scenes.py``) in this one process:

* Penumbra   - the scene as built, post layers included;
* EEVEE      - ``BLENDER_EEVEE_NEXT`` on 4.x, ``BLENDER_EEVEE`` on 5.x; 16 TAA render samples,
               shadows on, everything else at factory defaults;
* Workbench  - factory defaults;
* Cycles     - CPU, 16 samples, adaptive sampling and denoiser off.

Each engine gets one warm-up render that is not counted (it pays for shader compilation and
first-time allocations), then ``--runs`` timed calls of
``bpy.ops.render.render(write_still=False)``. The machine is shared and noisy, so absolute
seconds only describe this run: the number to quote is each engine's median time divided by
Penumbra's median from the same run.

Writes ``<out>/benchmark.csv`` and prints a Markdown table (for the README) to stdout. Exits
with status 1 if any engine failed to render (its row is still written, with empty times).
"""

import argparse
import contextlib
import csv
import os
import statistics
import sys
import time
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "tests"))

from devkit import eevee_id, load_penumbra  # noqa: E402  (needs the sys.path entries above)
from scenes import demo_scene  # noqa: E402

EEVEE_SAMPLES = 16
CYCLES_SAMPLES = 16
CSV_FIELDS = ["engine", "median_s", "min_s", "ratio_to_penumbra", "runs", "width", "height", "blender"]


# --- engine set-up ------------------------------------------------------------------------


def setup_penumbra(scene):
    scene.render.engine = "PENUMBRA"


def setup_eevee(scene):
    scene.render.engine = eevee_id()
    scene.eevee.taa_render_samples = EEVEE_SAMPLES
    scene.eevee.use_shadows = True


def setup_workbench(scene):
    scene.render.engine = "BLENDER_WORKBENCH"


def setup_cycles(scene):
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = CYCLES_SAMPLES
    cycles.use_adaptive_sampling = False  # a fixed amount of work per pixel
    cycles.use_denoising = False


# (key used by --engines, name in the outputs, set-up function); Penumbra first: it is the
# baseline. The settings behind each name are listed under the Markdown table.
ENGINES = [
    ("penumbra", "Penumbra", setup_penumbra),
    ("eevee", "EEVEE", setup_eevee),
    ("workbench", "Workbench", setup_workbench),
    ("cycles", "Cycles", setup_cycles),
]


# --- measurements -------------------------------------------------------------------------


def triangle_count(scene):
    """Triangles of every evaluated mesh instance in the scene (modifiers and instancing applied)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    total = 0
    for instance in depsgraph.object_instances:
        ob = instance.object
        if ob.type != "MESH":
            continue
        mesh = ob.to_mesh()
        try:
            mesh.calc_loop_triangles()
            total += len(mesh.loop_triangles)
        finally:
            ob.to_mesh_clear()
    return total


def gpu_renderer():
    """The GPU renderer string, or None: the gpu module only answers once a GPU context exists
    (after a GPU engine has rendered) and not at all on some Blender versions in background mode."""
    try:
        import gpu

        return gpu.platform.renderer_get()
    except Exception:
        return None


def time_engine(setup, width, height, runs):
    """Build a fresh demo scene for one engine, render once to warm up, then time ``runs``
    renders. Returns the list of timings in seconds."""
    scene = demo_scene(width, height)  # resets to factory settings: a clean scene per engine
    if not hasattr(bpy.types.Scene, "penumbra"):
        raise RuntimeError("Penumbra was unregistered by read_factory_settings")
    setup(scene)
    bpy.ops.render.render(write_still=False)  # warm-up: shader compilation, first allocations
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        bpy.ops.render.render(write_still=False)
        times.append(time.perf_counter() - start)
    return times


# --- output -------------------------------------------------------------------------------


@contextlib.contextmanager
def stdout_to_stderr():
    """Send file descriptor 1 to stderr for the duration: Blender's render progress and reports
    ("Fra:1 Mem:..." lines) are printed by C code straight to it, and stdout is kept for the table."""
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def fmt(value, digits=3):
    return "" if value is None else f"{value:.{digits}f}"


def markdown(rows, info):
    """A README-ready Markdown block: the table, then the conditions it was measured under."""
    lines = [
        "| Engine | Median (s) | Min (s) | Time relative to Penumbra |",
        "|---|---:|---:|---:|",
    ]
    for row in rows:
        if row["error"]:
            lines.append(f"| {row['label']} | failed | | |")
            continue
        ratio = f"{row['ratio']:.2f}x" if row["ratio"] is not None else "n/a"
        lines.append(f"| {row['label']} | {fmt(row['median'])} | {fmt(row['min'])} | {ratio} |")
    lines += [
        "",
        f"Demo scene (`tools/scenes.py`), {info['width']}x{info['height']}, {info['triangles']} triangles; "
        f"median and min of {info['runs']} timed renders after one warm-up render per engine.",
        f"Blender {info['blender']}; GPU: {info['gpu'] or 'n/a'}.",
        f"EEVEE: {EEVEE_SAMPLES} TAA render samples, shadows on. "
        f"Cycles: CPU, {CYCLES_SAMPLES} samples, no adaptive sampling, no denoiser. Workbench: defaults.",
        "Ratios come from one run on one machine; a ratio above 1 means slower than Penumbra.",
    ]
    return "\n".join(lines)


def write_csv(path, rows, info):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=CSV_FIELDS)
        writer.writeheader()
        for row in rows:
            writer.writerow({
                "engine": row["label"],
                "median_s": fmt(row["median"], 4),
                "min_s": fmt(row["min"], 4),
                "ratio_to_penumbra": fmt(row["ratio"], 3),
                "runs": info["runs"],
                "width": info["width"],
                "height": info["height"],
                "blender": info["blender"],
            })


# --- main ---------------------------------------------------------------------------------


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, type=Path, help="output folder for benchmark.csv")
    parser.add_argument("--runs", type=int, default=5, help="timed renders per engine (default 5)")
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=360)
    parser.add_argument(
        "--engines", default=",".join(key for key, _, _ in ENGINES),
        help="comma-separated subset of: " + ", ".join(key for key, _, _ in ENGINES),
    )
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error("--runs must be at least 1")
    known = {key for key, _, _ in ENGINES}
    args.engines = [e.strip() for e in args.engines.split(",") if e.strip()]
    unknown = set(args.engines) - known
    if unknown:
        parser.error(f"unknown engine(s): {', '.join(sorted(unknown))}")
    return args


def main(argv=None):
    args = parse_args(argv)
    load_penumbra().register()

    demo_scene(args.width, args.height)
    info = {
        "blender": bpy.app.version_string,
        "width": args.width,
        "height": args.height,
        "runs": args.runs,
        "triangles": triangle_count(bpy.context.scene),
        "gpu": None,
    }

    rows = []
    for key, label, setup in ENGINES:
        if key not in args.engines:
            continue
        row = {"label": label, "median": None, "min": None, "ratio": None, "error": None}
        print(f"benchmark: {label}: 1 warm-up + {args.runs} timed renders", file=sys.stderr, flush=True)
        try:
            with stdout_to_stderr():
                times = time_engine(setup, args.width, args.height, args.runs)
            row["median"], row["min"] = statistics.median(times), min(times)
        except Exception as exc:  # keep going: one broken engine should not hide the others
            row["error"] = str(exc)
            print(f"benchmark: {label} failed: {exc}", file=sys.stderr, flush=True)
        info["gpu"] = info["gpu"] or gpu_renderer()
        rows.append(row)

    base = next((r["median"] for r in rows if r["label"] == "Penumbra"), None)
    if base:
        for row in rows:
            if row["median"] is not None:
                row["ratio"] = row["median"] / base

    args.out.mkdir(parents=True, exist_ok=True)
    write_csv(args.out / "benchmark.csv", rows, info)
    print()
    print(markdown(rows, info), flush=True)
    return 1 if any(r["error"] for r in rows) else 0


if __name__ == "__main__":
    status = main()
    sys.stdout.flush()
    sys.stderr.flush()
    # Leave without running the interpreter's and bpy's exit handlers: with Blender 4.5 as a
    # module, a static destructor can wait forever on a GPU/file worker thread at exit.
    os._exit(status)
