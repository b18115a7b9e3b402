"""SEPIA: the classic sepia-tone matrix, blended with the input by ``amount``.

The matrix lives here as data and reaches the shader as layer data, so the shader and any
reference share one set of constants. Values are not clamped (the stack is HDR): white maps
to (1.351, 1.203, 0.937). A point layer: it shares a pass with its neighbours.
"""

from ..settings import Param
from .base import PointEffect, point_words

# Rows give R', G', B' from (R, G, B).
SEPIA_MATRIX = (
    (0.393, 0.769, 0.189),
    (0.349, 0.686, 0.168),
    (0.272, 0.534, 0.131),
)


class Sepia(PointEffect):
    id = "SEPIA"
    label = "Sepia"
    icon = "COLOR"
    description = "Old-photograph brown tone (standard sepia matrix)"
    point_glsl = "post/sepia.frag.glsl"
    point_function = "sepia_point"
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

    def point_data(self, ctx, params):
        (r, g, b) = SEPIA_MATRIX
        return point_words(*r, params.amount, *g, 0.0, *b)


def sepia_reference(rgb, amount):
    """Reference of the SEPIA layer's colour, numpy-ready (``rgb``: (..., 3)), in float64:
    ``rgb`` blended towards ``SEPIA_MATRIX @ rgb`` by ``amount``, not clamped."""
    import numpy as np

    rgb = np.asarray(rgb, dtype=np.float64)
    return rgb + amount * (rgb @ np.array(SEPIA_MATRIX).T - rgb)
