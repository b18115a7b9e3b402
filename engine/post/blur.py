"""BLUR: separable Gaussian, two 1-D passes (O(2n) taps per pixel instead of O(n^2)).

``half_resolution`` blurs at half the size instead (four passes: 2x2 means, the two 1-D passes
at half size with half the radius and sigma, then a bilinear read back at full size): a
quarter of the pixels and half the taps, for a blur a little softer than the exact one
(``blur_reference`` states both, exactly).
"""

from ..enums import Enum
from ..settings import Param
from ..shadows import kernels
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

# The shader's passes, selected by the BLUR_PASS define (see blur.frag.glsl).
PASS = Enum(
    "blur pass",
    "BLUR",
    (
        ("AXIS", "Axis", "One 1-D Gaussian pass along a direction", 0),
        ("DOWN", "Down", "2x2 means at half size", 1),
        ("UP", "Up", "The half-size blur read bilinearly at full size", 2),
    ),
)

PROGRAM = post_program(
    "post_blur",
    "post/blur.frag.glsl",
    push_constants=(("VEC2", "direction"), ("INT", "radius")),
    samplers=(("FLOAT_2D", "input_tex"),),
    uniform_blocks=((GAUSSIAN_WEIGHTS, "weights", GAUSSIAN_VEC4S),),
    defines={**PASS.defines(), "BLUR_PASS": PASS.define("AXIS")},
)


class Blur(PostEffect):
    id = "BLUR"
    label = "Blur"
    icon = "MATFLUID"
    description = "Separable Gaussian blur"
    params = (
        Param(
            "radius",
            "INT",
            4,
            "Kernel half-width in pixels",
            min=0,
            max=GAUSSIAN_MAX_RADIUS,
            soft_max=64,
            unit="PIXELS",
        ),
        Param(
            "sigma",
            "FLOAT",
            0.0,
            "Gaussian sigma in pixels; 0 uses radius / 2",
            min=0.0,
            max=1000.0,
            soft_max=64.0,
            unit="PIXELS",
        ),
        Param(
            "half_resolution",
            "BOOL",
            False,
            "Blur at half resolution: a quarter of the pixels and half the taps, much faster for "
            "wide blurs, a little softer",
        ),
    )

    def __init__(self):
        self._weights = GaussianWeights()

    def is_identity(self, params):
        return params.radius <= 0

    @staticmethod
    def sigma(params):
        return params.sigma if params.sigma > 0.0 else None

    def weights(self, params):
        return kernels.gaussian_1d(params.radius, self.sigma(params))

    def execute(self, ctx, src, params, mix):
        if params.half_resolution:
            return self._half(ctx, src, params, mix)
        ubo = self._weights.get(params.radius, self.sigma(params))
        tmp = ctx.acquire(src)
        ctx.fullscreen(
            PROGRAM,
            tmp,
            samplers={"source_tex": src, "input_tex": src},
            uniforms={"direction": (1.0, 0.0), "radius": params.radius, "mix_factor": 1.0},
            blocks={"weights": ubo},
        )
        dst = ctx.acquire(src, tmp.texture)
        return ctx.fullscreen(
            PROGRAM,
            dst,
            samplers={"source_tex": src, "input_tex": tmp.texture},
            uniforms={"direction": (0.0, 1.0), "radius": params.radius, "mix_factor": mix},
            blocks={"weights": ubo},
        )

    def _half(self, ctx, src, params, mix):
        """The half-resolution path: down, blur across, blur up, up (four passes)."""
        radius, sigma = half_kernel(params.radius, self.sigma(params))
        ubo = self._weights.get(radius, sigma)

        def step(pass_id, direction):
            return {"BLUR_PASS": PASS.define(pass_id)}, {"direction": direction, "radius": radius}

        steps = [step("DOWN", (0.0, 0.0)), step("AXIS", (1.0, 0.0)), step("AXIS", (0.0, 1.0))]
        return ctx.half_size(PROGRAM, src, mix, steps, step("UP", (0.0, 0.0)), {"weights": ubo})


def half_kernel(radius, sigma=None):
    """(radius, sigma) of the half-resolution blur: half the full one's (sigma None: radius /
    2), in half-size pixels."""
    radius = int(radius)
    return (radius + 1) // 2, (sigma if sigma is not None else radius / 2.0) / 2.0


def blur_reference(img, radius, sigma=None, half_resolution=False):
    """Reference of the whole BLUR layer, numpy-ready, in float64; non-finite input reads as
    0. ``half_resolution``: 2x2 means (``half_size_mean``), the blur of ``half_kernel``, then a
    bilinear read at each pixel's centre (``bilinear_up``)."""
    import numpy as np

    clean = np.where(np.isfinite(img), img, 0.0).astype(np.float64)
    if not half_resolution:
        return gaussian_reference(clean, radius, sigma)
    r, s = half_kernel(radius, sigma)
    small = gaussian_reference(half_size_mean(clean), r, s)
    return bilinear_up(small, *clean.shape[:2])


def gaussian_reference(img, radius, sigma=None):
    """Reference of the two BLUR passes, numpy-ready: the separable Gaussian of
    ``kernels.gaussian_1d(radius, sigma)`` with clamp-to-edge, in float64 (``img``: (h, w, C))."""
    import numpy as np

    from ..shadows import kernels

    w = kernels.gaussian_1d(radius, sigma)
    out = np.asarray(img).astype(np.float64)
    for axis in (1, 0):
        pad = [(0, 0)] * 3
        pad[axis] = (radius, radius)
        p = np.pad(out, pad, mode="edge")
        acc = np.zeros_like(out)
        for i, wi in enumerate(w):
            sl = [slice(None)] * 3
            sl[axis] = slice(i, i + out.shape[axis])
            acc += wi * p[tuple(sl)]
        out = acc
    return out
