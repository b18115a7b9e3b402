"""Memory over many final renders: does the process keep growing?

Renders the demo scene (``devkit.scenes.demo_scene``) with Penumbra ``--renders`` times through
``bpy.ops.render.render`` (an F12 each: a new engine instance, targets and shadow atlas from the
texture pool, ``engine/gpu_pool.py``) and reads the process's resident memory after each
render. Reports, at a few counts, how much more the process holds than after the first render
(which pays for the GPU context, shader compilation and first allocations once), and what the
texture pool holds. On llvmpipe GPU textures live in system memory, so they count in it.

Writes ``<out>/soak.csv`` and prints a Markdown table. Linux only (reads /proc/self/statm).
"""

import os
import sys
from pathlib import Path

import bpy

from devkit import report, scenes, session

HELP = "process memory over repeated F12 renders (texture pool bound)"
CSV_FIELDS = ["renders", "rss_mib", "more_than_first_mib", "pool_mib", "pool_textures", "width", "height"]


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder for soak.csv (default out)")
    parser.add_argument("--renders", type=int, default=300, help="F12 renders in all (default 300)")
    parser.add_argument("--width", type=int, default=160)
    parser.add_argument("--height", type=int, default=90)


def resident_mib():
    """This process's resident memory in MiB."""
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def run(args):
    session.load_penumbra().register()
    from penumbra.engine import gpu_pool

    pool = gpu_pool.FINAL_RENDERS
    scene = scenes.demo_scene(args.width, args.height)
    scene.render.engine = "PENUMBRA"
    marks = sorted({1, 2, 10, 50, 100, 200, args.renders} & set(range(1, args.renders + 1)))
    rows, first = [], None
    before = resident_mib()  # the scene built, no render yet: no GPU context, no program compiled
    for n in range(1, args.renders + 1):
        with session.stdout_to_stderr():
            bpy.ops.render.render(write_still=False)
        if n in marks:
            rss = resident_mib()
            first = rss if first is None else first
            rows.append(
                {
                    "renders": n,
                    "rss_mib": round(rss, 1),
                    "more_than_first_mib": round(rss - first, 1),
                    "pool_mib": round(pool.held_bytes / 2**20, 1),
                    "pool_textures": len(pool),
                    "width": args.width,
                    "height": args.height,
                }
            )
            print(f"soak: {n} renders, {rss:.1f} MiB resident", file=sys.stderr, flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    report.write_csv(args.out / "soak.csv", rows, CSV_FIELDS)
    header = ["F12 renders", "resident (MiB)", "more than after the first (MiB)", "pool (MiB)", "pool textures"]
    table = [[r["renders"], r["rss_mib"], r["more_than_first_mib"], r["pool_mib"], r["pool_textures"]] for r in rows]
    print(report.markdown_table(header, table))
    print(
        f"\n{bpy.app.version_string}; demo scene at {args.width}x{args.height}, F12 renders in one process. "
        f"Before the first render the process held {before:.1f} MiB: the first render adds "
        f"{rows[0]['rss_mib'] - before:.1f} MiB once (GPU context, compiled programs, first targets)."
    )
    return 0
