"""SEPIA: the classic sepia-tone matrix, blended with the input by ``amount``.

The matrix lives here as data and reaches the shader as push constants, so the shader and
any reference share one set of constants. Values are not clamped (the stack is HDR): white
maps to (1.351, 1.203, 0.937).
"""

from ..settings import Param
from .base import PostEffect, post_program

# Rows give R', G', B' from (R, G, B).
SEPIA_MATRIX = (
    (0.393, 0.769, 0.189),
    (0.349, 0.686, 0.168),
    (0.272, 0.534, 0.131),
)

PROGRAM = post_program(
    "post_sepia",
    "post/sepia.frag.glsl",
    push_constants=(("VEC4", "sepia_r"), ("VEC4", "sepia_g"), ("VEC4", "sepia_b"), ("FLOAT", "amount")),
)


class Sepia(PostEffect):
    id = "SEPIA"
    label = "Sepia"
    icon = "COLOR"
    description = "Old-photograph brown tone (standard sepia matrix)"
    params = (
        Param(
            "amount",
            "FLOAT",
            1.0,
            "Blend from the original colour (0) to full sepia (1)",
            min=0.0,
            max=1.0,
            subtype="FACTOR",
        ),
    )

    def is_identity(self, params):
        return params.amount <= 0.0

    def execute(self, ctx, src, params, mix):
        rows = {f"sepia_{ch}": (*row, 0.0) for ch, row in zip("rgb", SEPIA_MATRIX)}
        return ctx.single_pass(PROGRAM, src, mix, uniforms={"amount": params.amount, **rows})


def sepia_reference(rgb, amount):
    """Reference of the SEPIA layer's colour, numpy-ready (``rgb``: (..., 3)), in float64:
    ``rgb`` blended towards ``SEPIA_MATRIX @ rgb`` by ``amount``, not clamped."""
    import numpy as np

    rgb = np.asarray(rgb, dtype=np.float64)
    return rgb + amount * (rgb @ np.array(SEPIA_MATRIX).T - rgb)
