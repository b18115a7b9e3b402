"""BLUR: separable Gaussian, two 1-D passes (O(2n) taps per pixel instead of O(n^2))."""

from .. import kernels
from ..settings import Param
from .base import GAUSSIAN_MAX_RADIUS, GAUSSIAN_VEC4S, GAUSSIAN_WEIGHTS, GaussianWeights, PostEffect, post_program

PROGRAM = post_program(
    "post_blur",
    "post/blur.frag.glsl",
    push_constants=(("VEC2", "direction"), ("INT", "radius")),
    samplers=(("FLOAT_2D", "input_tex"),),
    uniform_blocks=((GAUSSIAN_WEIGHTS, "weights", GAUSSIAN_VEC4S),),
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


def gaussian_reference(img, radius, sigma=None):
    """Reference of the two BLUR passes, numpy-ready: the separable Gaussian of
    ``kernels.gaussian_1d(radius, sigma)`` with clamp-to-edge, in float64 (``img``: (h, w, C))."""
    import numpy as np

    from .. import kernels

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
