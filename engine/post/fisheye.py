"""FISHEYE: radial lens bulge (strength > 0) or pinch (strength < 0) about the image centre.

Each output pixel reads the layer input at a source position on the same ray from the centre
(see ``fisheye_source``). With ``r`` the distance to the centre divided by the half-diagonal
(0 at the centre, 1 at the corners; a circle in pixels), the source radius is ``r ** k`` with
``k = 2 ** strength``, k in [0.5, 2]. The radial map is continuous and strictly increasing for
every strength, keeps the centre and the corner circle fixed, and has no division by zero, so
even the limits +-1 give neither NaN nor folds nor holes. Sources are read with bilinear
filtering; ``edge`` says what lies outside the image (only a pinch reads outside it).
"""

import numpy as np

from ..enums import Enum
from ..settings import Param
from .base import PostEffect, post_program

EDGE = Enum(
    "fisheye edge",
    "EDGE",
    (
        ("CLAMP", "Clamp", "Repeat the border pixels outside the image", 0),
        ("BLACK", "Black", "Transparent black (all channels 0) outside the image", 1),
        ("MIRROR", "Mirror", "Mirror the image at its borders", 2),
    ),
)

PROGRAM = post_program(
    "post_fisheye",
    "post/fisheye.frag.glsl",
    push_constants=(("FLOAT", "strength"), ("INT", "edge_mode")),
    defines=EDGE.defines(),
)


def fisheye_source(x, y, width, height, strength):
    """Reference of the shader's mapping, numpy-ready: the source position (pixels, texel
    centres at i + 0.5) read by the output pixel centred at ``x``, ``y``."""
    cx, cy = width * 0.5, height * 0.5
    dx = np.asarray(x, dtype=np.float64) - cx
    dy = np.asarray(y, dtype=np.float64) - cy
    r = np.hypot(dx, dy) / np.hypot(cx, cy)
    k = 2.0 ** float(strength)
    with np.errstate(divide="ignore"):
        scale = np.where(r > 0.0, np.power(np.where(r > 0.0, r, 1.0), k - 1.0), 1.0)
    return cx + dx * scale, cy + dy * scale


class Fisheye(PostEffect):
    id = "FISHEYE"
    label = "Fisheye"
    icon = "SPHERE"
    description = "Bulge (positive) or pinch (negative) the image about its centre"
    params = (
        Param(
            "strength",
            "FLOAT",
            0.5,
            "Positive bulges the centre outwards, negative pinches it; 0 = no change",
            min=-1.0,
            max=1.0,
            subtype="FACTOR",
        ),
        Param("edge", "ENUM", "CLAMP", "What a pinch shows beyond the image borders", enum=EDGE),
    )

    def is_identity(self, params):
        return params.strength == 0.0

    def execute(self, ctx, src, params, mix):
        return ctx.single_pass(
            PROGRAM,
            src,
            mix,
            uniforms={
                "strength": params.strength,
                "edge_mode": EDGE.value(params.edge),
            },
        )


def bilinear_reference(img, px, py, edge="CLAMP"):
    """Bilinear read of ``img`` (h, w, C) at pixel positions ``px``, ``py`` (texel centres at
    i + 0.5), numpy-ready, in float64, with the ``edge`` modes: CLAMP repeats the border
    texels, BLACK reads 0 outside, MIRROR reflects at the borders."""
    import numpy as np

    img = np.asarray(img, dtype=np.float64)
    h, w = img.shape[:2]
    tx, ty = np.asarray(px, np.float64) - 0.5, np.asarray(py, np.float64) - 0.5
    x0, y0 = np.floor(tx).astype(int), np.floor(ty).astype(int)
    fx, fy = (tx - x0)[..., None], (ty - y0)[..., None]

    def fold(i, n):
        if edge == "MIRROR":
            m = np.mod(i, 2 * n)
            return np.where(m >= n, 2 * n - 1 - m, m)
        return np.clip(i, 0, n - 1)

    def tap(ix, iy):
        v = img[fold(iy, h), fold(ix, w)]
        if edge == "BLACK":
            inside = (ix >= 0) & (ix < w) & (iy >= 0) & (iy < h)
            v = v * inside[..., None]
        return v

    bottom = tap(x0, y0) * (1 - fx) + tap(x0 + 1, y0) * fx
    top = tap(x0, y0 + 1) * (1 - fx) + tap(x0 + 1, y0 + 1) * fx
    return bottom * (1 - fy) + top * fy


def fisheye_reference(img, strength, edge):
    """Reference of the whole FISHEYE layer, numpy-ready, in float64: ``img`` (h, w, C), with
    non-finite components read as 0, read at ``fisheye_source`` of every pixel centre."""
    import numpy as np

    h, w = img.shape[:2]
    y, x = np.mgrid[0:h, 0:w] + 0.5
    sx, sy = fisheye_source(x, y, w, h, strength)
    clean = np.nan_to_num(np.asarray(img).astype(np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    return bilinear_reference(clean, sx, sy, edge)
