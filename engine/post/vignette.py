"""VIGNETTE: darkens (or tints) the image towards its edges. A point layer: it shares a pass
with its neighbours."""

from ..settings import Param
from .base import PointEffect, point_words


def vignette_factor(x, y, width, height, radius, softness, roundness):
    """Reference of the shader's weight (0 = untouched, 1 = full vignette colour), numpy-ready.

    ``x``, ``y`` are pixel centres. Distances are measured from the image centre in units of
    half the image height; ``roundness`` 1 gives a circle in pixels, 0 an ellipse that follows
    the frame's aspect.
    """
    import numpy as np

    aspect = width / height
    px = (np.asarray(x, dtype=np.float64) / width - 0.5) * 2.0
    py = (np.asarray(y, dtype=np.float64) / height - 0.5) * 2.0
    px = px * (1.0 + (aspect - 1.0) * roundness)
    d = np.sqrt(px * px + py * py)
    if softness <= 0.0:
        return (d > radius).astype(np.float64)
    t = np.clip((d - radius) / softness, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


class Vignette(PointEffect):
    id = "VIGNETTE"
    label = "Vignette"
    icon = "CLIPUV_DEHLT"
    description = "Darken or tint the image towards its edges"
    point_glsl = "post/vignette.frag.glsl"
    point_function = "vignette_point"
    params = (
        Param(
            "radius",
            "FLOAT",
            0.8,
            "Distance from the centre where the falloff starts (1 = half the height)",
            min=0.0,
            soft_max=2.0,
        ),
        Param("softness", "FLOAT", 0.6, "Width of the falloff; 0 is a hard edge", min=0.0, soft_max=2.0),
        Param(
            "roundness",
            "FLOAT",
            1.0,
            "1: a circle in pixels; 0: an ellipse following the frame",
            min=0.0,
            max=1.0,
            subtype="FACTOR",
        ),
        Param("color", "COLOR", (0.0, 0.0, 0.0), "Colour at the edges"),
    )

    def point_data(self, ctx, params):
        return point_words(*params.color[:3], params.radius, params.softness, params.roundness)
