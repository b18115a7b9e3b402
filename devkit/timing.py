"""The one timing loop of the benchmarks: warm-up calls that are not counted (shader
compilation, first allocations), then timed calls. Machines here are shared and noisy, so a
benchmark quotes medians and ratios between things timed in the same run."""

import argparse
import statistics
import time
from dataclasses import dataclass


@dataclass(frozen=True)
class Timing:
    """Seconds of each timed call, in order."""

    times: tuple

    @property
    def median(self):
        return statistics.median(self.times)

    @property
    def min(self):
        return min(self.times)

    @property
    def max(self):
        return max(self.times)


def measure(fn, runs, warmup=1):
    """Call ``fn()`` ``warmup`` times untimed, then ``runs`` times, each timed on its own with
    ``time.perf_counter``. ``fn`` must not return before its work is done (a GPU job ends with a
    read-back)."""
    if runs < 1:
        raise ValueError("runs must be at least 1")
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return Timing(tuple(times))


def render(runs, warmup=1):
    """Timing of ``bpy.ops.render.render(write_still=False)`` of the current scene with its
    current engine."""
    import bpy

    return measure(lambda: bpy.ops.render.render(write_still=False), runs, warmup)


def add_runs_argument(parser, default, help):
    """``--runs N`` (N >= 1) on an argparse parser; ``default`` may be None."""

    def runs(text):
        try:
            value = int(text)
        except ValueError:
            value = 0
        if value < 1:
            raise argparse.ArgumentTypeError(f"must be a whole number of at least 1, not {text!r}")
        return value

    suffix = f" (default {default})" if default is not None else ""
    parser.add_argument("--runs", type=runs, default=default, help=help + suffix)
