"""GLOW: bright-pass -> separable Gaussian -> added back to the image (bloom).

Two passes. The horizontal one applies the bright-pass to every tap it reads (so the
bright-pass costs no pass of its own) and blurs; the vertical one finishes the blur and adds
the result, scaled by ``intensity``, to the layer's input. The weights are blur.py's
(``kernels.gaussian_1d``, normalised), so away from the image edges the light added equals
the bright-pass energy times ``intensity``.

``half_resolution`` blurs at half the size instead (four passes: the bright-pass averaged over
2x2 pixels, the two blurs at half size with half the radius and sigma, then the result read
bilinearly back at full size and added): a quarter of the pixels and half the taps, for a
glow a little softer than the exact one (``glow_reference`` states both, exactly).
"""

import numpy as np

from ..enums import Enum
from ..settings import Param
from .base import (
    GAUSSIAN_MAX_RADIUS,
    GAUSSIAN_VEC4S,
    GAUSSIAN_WEIGHTS,
    GaussianWeights,
    PostEffect,
    bilinear_up,
    half_size_mean,
    post_program,
)
from .blur import gaussian_reference, half_kernel

# The shader's passes, selected by the GLOW_PASS define (see glow.frag.glsl).
PASS = Enum(
    "glow pass",
    "GLOW",
    (
        ("BRIGHT_H", "Bright, horizontal", "Horizontal blur of the bright-passed source", 0),
        ("COMPOSITE_V", "Composite, vertical", "Vertical blur added to the source", 1),
        ("DOWN", "Down", "Bright-pass averaged over 2x2 pixels, at half size", 2),
        ("BLUR_H", "Blur, horizontal", "Horizontal blur at half size", 3),
        ("BLUR_V", "Blur, vertical", "Vertical blur at half size", 4),
        ("UP", "Up", "The half-size glow read bilinearly and added to the source", 5),
    ),
)

PROGRAM = post_program(
    "post_glow",
    "post/glow.frag.glsl",
    push_constants=(
        ("FLOAT", "threshold"),
        ("FLOAT", "knee"),  # in colour units
        ("FLOAT", "intensity"),
        ("INT", "square_samples"),
        ("INT", "radius"),
    ),
    samplers=(("FLOAT_2D", "input_tex"),),
    uniform_blocks=((GAUSSIAN_WEIGHTS, "weights", GAUSSIAN_VEC4S),),
    defines=PASS.defines(),
)


def bright_pass(rgb, threshold, knee):
    """Reference of the shader's bright-pass, numpy-ready (``rgb``: (..., 3)).

    The standard soft-knee curve on ``b = max(r, g, b)``: nothing below ``threshold - knee``,
    ``b - threshold`` above ``threshold + knee``, a quadratic in between; the colour is scaled
    so its maximum component follows the curve. ``knee`` is in colour units (the effect passes
    ``threshold * knee fraction``, so the curve is 0 at black). Negative components (out of
    gamut) are clamped to 0 first: they do not glow.
    """
    c = np.maximum(np.asarray(rgb, dtype=np.float64), 0.0)
    b = c.max(axis=-1, keepdims=True)
    soft = np.clip(b - threshold + knee, 0.0, 2.0 * knee)
    soft = soft * soft / (4.0 * knee + 1e-5)
    contribution = np.maximum(soft, b - threshold) / np.maximum(b, 1e-5)
    return c * contribution


class Glow(PostEffect):
    id = "GLOW"
    label = "Glow"
    icon = "LIGHT_SUN"
    description = "Bloom: blur the highlights above a threshold and add them back"
    params = (
        Param(
            "threshold",
            "FLOAT",
            1.0,
            "Brightness (largest RGB component) above which pixels glow",
            min=0.0,
            soft_max=10.0,
        ),
        Param(
            "knee",
            "FLOAT",
            0.5,
            "Softness of the threshold as a fraction of it: 0 is a hard cut, 1 fades in from black",
            min=0.0,
            max=1.0,
            subtype="FACTOR",
        ),
        Param(
            "intensity",
            "FLOAT",
            0.5,
            "Scale of the glow added to the image; 0 turns the layer off",
            min=0.0,
            max=1000.0,
            soft_max=4.0,
        ),
        Param(
            "radius",
            "INT",
            16,
            "Blur half-width in pixels; sigma is radius / 2",
            min=0,
            max=GAUSSIAN_MAX_RADIUS,
            soft_max=64,
            unit="PIXELS",
        ),
        Param(
            "square_samples",
            "BOOL",
            False,
            "Square each bright-pass sample before blurring: favours the strongest highlights",
        ),
        Param(
            "half_resolution",
            "BOOL",
            False,
            "Blur the highlights at half resolution: a quarter of the pixels and half the taps, "
            "much faster for wide glows, a little softer",
        ),
    )

    def __init__(self):
        self._weights = GaussianWeights()

    def is_identity(self, params):
        return params.intensity <= 0.0

    def execute(self, ctx, src, params, mix):
        if params.half_resolution:
            return self._half(ctx, src, params, mix)
        ubo = self._weights.get(params.radius)
        uniforms = self._uniforms(params, params.radius)
        tmp = ctx.acquire(src)
        ctx.fullscreen(
            PROGRAM,
            tmp,
            defines={"GLOW_PASS": PASS.define("BRIGHT_H")},
            samplers={"source_tex": src, "input_tex": src},
            uniforms={**uniforms, "mix_factor": 1.0},
            blocks={"weights": ubo},
        )
        dst = ctx.acquire(src, tmp.texture)
        return ctx.fullscreen(
            PROGRAM,
            dst,
            defines={"GLOW_PASS": PASS.define("COMPOSITE_V")},
            samplers={"source_tex": src, "input_tex": tmp.texture},
            uniforms={**uniforms, "mix_factor": mix},
            blocks={"weights": ubo},
        )

    @staticmethod
    def _uniforms(params, radius):
        """The shader's parameters of both paths, for a blur of ``radius``."""
        return {
            "threshold": params.threshold,
            "knee": params.threshold * params.knee,  # in colour units
            "intensity": params.intensity,
            "square_samples": int(params.square_samples),
            "radius": radius,
        }

    def _half(self, ctx, src, params, mix):
        """The half-resolution path: down, blur across, blur up, up (four passes)."""
        radius, sigma = half_kernel(params.radius)
        ubo = self._weights.get(radius, sigma)
        uniforms = self._uniforms(params, radius)
        steps = [({"GLOW_PASS": PASS.define(p)}, uniforms) for p in ("DOWN", "BLUR_H", "BLUR_V")]
        up = ({"GLOW_PASS": PASS.define("UP")}, uniforms)
        return ctx.half_size(PROGRAM, src, mix, steps, up, {"weights": ubo})


def glow_reference(img, threshold, knee, intensity, radius, square_samples=False, half_resolution=False):
    """Reference of the whole GLOW layer, numpy-ready: ``img`` (h, w, 4) rgb + intensity *
    Gaussian(bright-pass), alpha kept, in float64. ``knee`` is the parameter (a fraction of
    ``threshold``); non-finite input components read as 0. ``half_resolution``: the
    half-size path (2x2 means of the bright-pass over the pixels that exist, the blur of
    ``blur.half_kernel``, a bilinear read at each pixel's centre, clamped to the edge)."""
    import numpy as np

    clean = np.where(np.isfinite(img), img, 0.0).astype(np.float64)
    bright = bright_pass(clean[..., :3], threshold, threshold * knee)
    if square_samples:
        bright = bright * bright
    out = clean.copy()
    if not half_resolution:
        padded = np.concatenate([bright, np.zeros_like(bright[..., :1])], -1)
        out[..., :3] += intensity * gaussian_reference(padded, radius)[..., :3]
        return out
    h, w = bright.shape[:2]
    r, sigma = half_kernel(radius)
    blurred = gaussian_reference(half_size_mean(bright), r, sigma)
    out[..., :3] += intensity * bilinear_up(blurred, h, w)
    return out
