"""SCANLINES: horizontal dark bands, optionally scrolling with the frame number.

The image height holds ``count`` line periods; the lower ``thickness`` of every period is the
dark band, which multiplies the colour by ``1 - intensity``. Periods start at the bottom edge
of the image on frame 0 and move up by ``scroll_speed`` periods per frame (down if negative);
the offset depends only on ``ctx.frame``. With ``antialias`` a pixel is darkened by the
fraction of its own height covered by dark bands (an exact box filter), otherwise by whether
its centre is inside one. A point layer: it shares a pass with its neighbours.
"""

from ..settings import Param
from .base import PointEffect, point_words


def scroll_offset(frame, speed):
    """The bands' upward shift in periods, reduced to [0, 1) in double precision."""
    return (float(frame) * float(speed)) % 1.0


def scanline_darkness(rows, height, count, thickness, offset, antialias=True):
    """Reference of the shader's ``dark`` (0 = untouched, 1 = full band) per pixel row, numpy-ready.

    ``rows`` are integer row indices (0 = bottom); ``offset`` comes from ``scroll_offset``.
    """
    import numpy as np

    rows = np.asarray(rows, dtype=np.float64)
    w = count / height  # periods per pixel
    th = min(max(thickness, 0.0), 1.0)
    if not antialias:
        u = (rows + 0.5) * w - offset
        return ((u - np.floor(u)) < th).astype(np.float64)

    def dark_measure(f):  # dark length in [0, f] for f >= 0, in periods
        n = np.floor(f)
        return n * th + np.minimum(f - n, th)

    u0 = rows * w - offset
    f0 = u0 - np.floor(u0)
    return (dark_measure(f0 + w) - dark_measure(f0)) / w


class Scanlines(PointEffect):
    id = "SCANLINES"
    label = "Scanlines"
    icon = "ALIGN_JUSTIFY"
    description = "Darken horizontal bands like the lines of a CRT screen"
    point_glsl = "post/scanlines.frag.glsl"
    point_function = "scanlines_point"
    params = (
        Param("count", "INT", 240, "Number of lines over the image height", min=1, soft_max=1080),
        Param(
            "thickness", "FLOAT", 0.5, "Fraction of each line period that is dark", min=0.0, max=1.0, subtype="FACTOR"
        ),
        Param(
            "intensity", "FLOAT", 0.5, "How much the dark bands darken (1 = black)", min=0.0, max=1.0, subtype="FACTOR"
        ),
        Param("scroll_speed", "FLOAT", 0.0, "Upward motion in lines per frame (negative scrolls down)", soft_max=2.0),
        Param("antialias", "BOOL", True, "Darken each pixel by the fraction of it the bands cover"),
    )

    def is_identity(self, params):
        return params.intensity <= 0.0 or params.thickness <= 0.0

    def point_data(self, ctx, params):
        return point_words(
            params.count / ctx.height,  # periods per pixel
            params.thickness,
            params.intensity,
            scroll_offset(ctx.frame, params.scroll_speed),  # offset in periods, in [0, 1)
            int(params.count),
            int(params.antialias),
        )


def scanlines_reference(img, count, thickness, intensity, speed, frame, antialias):
    """Reference of the whole SCANLINES layer, numpy-ready: returns (``img`` (h, w, 4) with its
    rgb darkened row by row, in float64; the rows' darkness from ``scanline_darkness``)."""
    import numpy as np

    h = img.shape[0]
    dark = scanline_darkness(np.arange(h), h, count, thickness, scroll_offset(frame, speed), antialias)
    out = np.asarray(img).astype(np.float64)
    out[..., :3] *= (1.0 - intensity * dark)[:, None, None]
    return out, dark
