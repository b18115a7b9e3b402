"""BLUR: separable Gaussian, two 1-D passes (O(2n) taps per pixel instead of O(n^2))."""

import numpy as np

from ...shaders.loader import Struct
from .. import kernels
from .base import Param, PostEffect, post_program

MAX_RADIUS = 256
WEIGHTS = Struct("BlurWeights", (("VEC4", "w"),))
WEIGHT_VEC4S = (2 * MAX_RADIUS + 1 + 3) // 4

PROGRAM = post_program(
    "post_blur",
    "post/blur.frag.glsl",
    push_constants=(("VEC2", "direction"), ("INT", "radius")),
    samplers=(("FLOAT_2D", "input_tex"),),
    uniform_blocks=((WEIGHTS, "weights", WEIGHT_VEC4S),),
)


class Blur(PostEffect):
    id = "BLUR"
    label = "Blur"
    icon = "MATFLUID"
    description = "Separable Gaussian blur"
    params = (
        Param("radius", "INT", 4, "Kernel half-width in pixels (clamped to 256)", min=0, max=MAX_RADIUS, soft_max=64),
        Param("sigma", "FLOAT", 0.0, "Gaussian sigma in pixels; 0 uses radius / 2", min=0.0, soft_max=64.0),
    )

    def __init__(self):
        self._ubo = None
        self._key = None

    def is_identity(self, params):
        return int(params.radius) <= 0

    def weights(self, params):
        sigma = float(params.sigma) if params.sigma > 0.0 else None
        return kernels.gaussian_1d(min(int(params.radius), MAX_RADIUS), sigma)

    def execute(self, ctx, src, params, mix):
        import gpu

        radius = min(int(params.radius), MAX_RADIUS)
        key = (radius, float(params.sigma))
        if key != self._key:
            packed = np.zeros(WEIGHT_VEC4S * 4, np.float32)
            w = self.weights(params)
            packed[: len(w)] = w
            if self._ubo is None:
                self._ubo = gpu.types.GPUUniformBuf(packed.tobytes())
            else:
                self._ubo.update(packed.tobytes())
            self._key = key
        tmp = ctx.acquire(src)
        ctx.fullscreen(
            PROGRAM,
            tmp,
            samplers={"source_tex": src, "input_tex": src},
            uniforms={"direction": (1.0, 0.0), "radius": radius, "mix_factor": 1.0},
            blocks={"weights": self._ubo},
        )
        dst = ctx.acquire(src, tmp.texture)
        return ctx.fullscreen(
            PROGRAM,
            dst,
            samplers={"source_tex": src, "input_tex": tmp.texture},
            uniforms={"direction": (0.0, 1.0), "radius": radius, "mix_factor": mix},
            blocks={"weights": self._ubo},
        )
EFFECT = Blur
