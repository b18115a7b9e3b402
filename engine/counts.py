"""Counts made from floats (loop lengths, reaches, sample and octave counts): clamped to their
bounds before they become integers, so no input (NaN, infinities, 1e30) can make a loop, a
define or an allocation without end, and none raises on the way (``math.ceil`` of NaN or
infinity does). No bpy."""

import math


def ceil_count(x, lo, hi):
    """``ceil(x)`` clamped to [``lo``, ``hi``] (integers); NaN gives ``lo``."""
    x = float(x)
    if not x >= lo:  # NaN too
        return int(lo)
    if x >= hi:
        return int(hi)
    return max(int(lo), min(int(hi), math.ceil(x)))
