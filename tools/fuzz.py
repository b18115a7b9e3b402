"""Render random scenes (devkit/fuzz.py) and check that each ends within its time budget with a
finite, non-negative Combined. Each scene prints a line before it renders (its seed and
description) and one after (its time), so a scene that never ends is named by the last line
printed; a watchdog ends the process if a scene runs past its budget.

    python -m tools.fuzz --seeds 0:50                      # scenes 0..49
    python -m tools.fuzz --seeds 0:50 --forms 5            # ... drawn from 5 forms (the suite's)
    python -m tools.fuzz --seeds 17 --save out/17.blend    # rebuild seed 17 and save it

Prints ``FUZZ BEGIN <seed> <json>`` and ``FUZZ END <seed> <seconds> <ok|why>`` lines, then
``RESULT <json>`` (devkit.session.run_result reads it)."""

import argparse
import faulthandler
import json
import sys
import time

from devkit import session


def _seeds(text):
    if ":" in text:
        lo, hi = text.split(":")
        return list(range(int(lo), int(hi)))
    return [int(s) for s in text.split(",")]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="0:10", help="lo:hi or a comma-separated list")
    parser.add_argument("--budget", type=float, default=60.0, help="seconds a scene may take")
    parser.add_argument("--size", default="24x16", help="resolution, WxH")
    parser.add_argument(
        "--forms", type=int, default=0, help="draw the programs' choices from this many forms (0: each seed its own)"
    )
    parser.add_argument("--save", help="save the (last) scene built to this .blend instead of rendering it")
    args = parser.parse_args(argv)
    session.isolate()
    import bpy  # noqa: F401
    import numpy as np

    from devkit import fuzz
    from devkit.render import render

    module = session.load_penumbra()
    module.register()
    size = tuple(int(x) for x in args.size.split("x"))
    results = []
    for seed in _seeds(args.seeds):
        scene, desc = fuzz.random_scene(seed, size, form=(seed % args.forms) if args.forms else None)
        if args.save:
            bpy.ops.wm.save_as_mainfile(filepath=args.save, copy=True)
            print(f"saved seed {seed} to {args.save}")
            continue
        print(f"FUZZ BEGIN {seed} {json.dumps(desc)}", flush=True)
        faulthandler.dump_traceback_later(args.budget, exit=True)
        start = time.perf_counter()
        combined = render(scene)["Combined"]
        seconds = time.perf_counter() - start
        faulthandler.cancel_dump_traceback_later()
        why = session.light_check_failure(combined)
        if why is None and combined.shape[:2] != (size[1], size[0]):
            why = f"Combined is {combined.shape[1]}x{combined.shape[0]}, not {size[0]}x{size[1]}"
        print(f"FUZZ END {seed} {seconds:.2f} {why or 'ok'}", flush=True)
        results.append({"seed": seed, "seconds": seconds, "failure": why, "max": float(np.max(combined))})
    print("RESULT " + json.dumps(results), flush=True)
    session.hard_exit(0)


if __name__ == "__main__":
    sys.exit(main())
