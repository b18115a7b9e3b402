"""NOISE: animated film grain, reproducible from the frame number.

Each ``size`` x ``size`` cell of pixels (anchored at pixel (0, 0)) draws, per channel, a value
``g`` uniform in (-1, 1) from an integer hash of (cell x, cell y, frame, seed, channel), and
the colour becomes ``c + min(amount, c) * g``: additive, zero-mean grain of the same strength
wherever the channel is at least ``amount``, and no stronger than the channel itself where it
is darker, so light never goes negative (a channel at or below zero takes no grain) and the
image mean is preserved. ``monochrome`` uses channel 0's value for R, G and B. Alpha is
untouched. The hash is PCG (O'Neill's permuted congruential output function) chained over
the inputs; ``grain_reference`` is its numpy twin and ``apply_reference`` the whole layer's.
A point layer: it shares a pass with its neighbours.
"""

from ..settings import Param
from .base import PointEffect, point_words


def _pcg(v):
    import numpy as np

    state = v * np.uint32(747796405) + np.uint32(2891336453)
    word = ((state >> ((state >> np.uint32(28)) + np.uint32(4))) ^ state) * np.uint32(277803737)
    return (word >> np.uint32(22)) ^ word


def grain_reference(width, height, frame, size=1, seed=0, monochrome=False):
    """The shader's grain ``g`` in (-1, 1) as an array (height, width, 3), row 0 at the bottom."""
    import numpy as np

    def u32(x):
        return np.asarray(np.asarray(x, dtype=np.int64) & 0xFFFFFFFF, dtype=np.uint32)

    y, x = np.mgrid[0:height, 0:width]
    cx, cy = u32(x // size), u32(y // size)
    out = np.empty((height, width, 3), np.float64)
    with np.errstate(over="ignore"):
        for ch in range(3):
            channel = 0 if monochrome else ch
            h = _pcg(u32(frame) + _pcg(u32(seed) * np.uint32(4) + np.uint32(channel)))
            h = _pcg(cx + _pcg(cy + h))
            k = (h >> np.uint32(8)).astype(np.int64) - 8388608
            out[..., ch] = (k + 0.5) / 8388608.0
    return out


def apply_reference(image, amount, grain):
    """The layer's output for ``image`` (h, w, 4) and ``grain_reference``'s ``grain``, in float64."""
    import numpy as np

    out = np.asarray(image, np.float64).copy()
    out[..., :3] += np.minimum(float(amount), np.maximum(out[..., :3], 0.0)) * grain
    return out


class Noise(PointEffect):
    id = "NOISE"
    label = "Noise"
    icon = "MOD_NOISE"
    description = "Animated film grain (the same frame always gives the same grain)"
    point_glsl = "post/noise.frag.glsl"
    point_function = "noise_point"
    params = (
        Param(
            "amount",
            "FLOAT",
            0.05,
            "Grain strength: each channel moves by up to this much (and never below zero)",
            min=0.0,
            max=1000.0,
            soft_max=1.0,
        ),
        Param("size", "INT", 1, "Grain size in pixels", min=1, soft_max=16, unit="PIXELS"),
        Param("monochrome", "BOOL", True, "Same grain in R, G and B (luminance grain) instead of per channel"),
        Param("seed", "INT", 0, "Pattern variant, so stacked noise layers differ"),
    )

    def is_identity(self, params):
        return params.amount <= 0.0

    def point_data(self, ctx, params):
        return point_words(params.amount, int(params.size), int(ctx.frame), int(params.seed), int(params.monochrome))
