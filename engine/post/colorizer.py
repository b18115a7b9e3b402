"""COLORIZER: a 2-D colour lookup indexed by (blurred luminance, distance to the centre).

For every pixel the lookup coordinates are

* ``x = clamp(L, 0, 1)`` with ``L`` the Rec.709 luminance (0.2126, 0.7152, 0.0722) of the
  image after a Gaussian blur of ``blur_radius`` pixels (the BLUR layer's kernel; blurring the
  colour and then taking the luminance equals blurring the luminance, both are linear);
* ``y = |p - size / 2| / |size / 2|`` with ``p`` the pixel centre in pixels: 0 at the centre,
  1 at the image corners (a circle in pixels).

The lookup table is an image of W x H texels (row 0 = y 0, the bottom row of a Blender image)
read with bilinear filtering between texel centres: ``x`` maps to the texel coordinate
``x * (W - 1)`` (texture coordinate ``u = (x * (W - 1) + 0.5) / W``), ``y`` likewise, so x = 0 is
the centre of the first column and x = 1 the centre of the last. Only the LUT's RGB is used.
The image is read as Penumbra's own float table of its pixels (``base.image_or_table``), so a
LUT reads the same on every GPU.
Without an image the built-in ``DEFAULT_LUT`` is used. The result is
``mix(c.rgb, lut.rgb, strength)``; alpha is kept.
"""

from types import SimpleNamespace

import numpy as np

from ..settings import Param
from .base import GAUSSIAN_MAX_RADIUS, PostEffect, image_or_table, post_program
from .blur import Blur

PROGRAM = post_program(
    "post_colorizer",
    "post/colorizer.frag.glsl",
    push_constants=(("FLOAT", "strength"),),
    samplers=(("FLOAT_2D", "luma_tex"), ("FLOAT_2D", "lut_tex")),
)

LUMA_WEIGHTS = (0.2126, 0.7152, 0.0722)  # Rec.709, as in the shader

# The built-in lookup: rows are y (0 = image centre, 1 = corners), columns x (0 = black,
# 1 = white). A cool-shadow / warm-highlight grade whose corner row is darker, so the default
# also acts as a gentle vignette.
DEFAULT_LUT = np.array(
    [
        [(0.00, 0.00, 0.02), (0.05, 0.07, 0.16), (0.30, 0.28, 0.30), (0.75, 0.62, 0.45), (1.00, 0.96, 0.88)],
        [(0.00, 0.00, 0.01), (0.02, 0.03, 0.09), (0.16, 0.14, 0.17), (0.45, 0.36, 0.26), (0.70, 0.64, 0.56)],
    ],
    dtype=np.float32,
)


def lookup_coords(luminance, x, y, width, height):
    """Reference of the shader's lookup coordinates, numpy-ready.

    ``luminance`` is the (blurred) luminance at pixel centres ``x``, ``y`` of a ``width`` x
    ``height`` image. Returns ``(lx, ly)`` in [0, 1].
    """
    half = np.array([width, height], dtype=np.float64) * 0.5
    dx = np.asarray(x, dtype=np.float64) - half[0]
    dy = np.asarray(y, dtype=np.float64) - half[1]
    ly = np.sqrt(dx * dx + dy * dy) / np.hypot(*half)
    return np.clip(luminance, 0.0, 1.0), np.clip(ly, 0.0, 1.0)


def lut_lookup(lut, lx, ly):
    """Reference of the shader's bilinear LUT read, numpy-ready: ``lut`` is (H, W, C), row 0 at
    ``ly`` 0; ``lx``, ``ly`` in [0, 1]. Returns (..., C)."""
    lut = np.asarray(lut, dtype=np.float64)
    h, w = lut.shape[:2]

    def axis(t, n):
        t = np.clip(np.asarray(t, dtype=np.float64), 0.0, 1.0) * (n - 1)
        i0 = np.floor(t).astype(int)
        return i0, np.minimum(i0 + 1, n - 1), (t - i0)[..., None]

    x0, x1, fx = axis(lx, w)
    y0, y1, fy = axis(ly, h)
    bottom = lut[y0, x0] * (1 - fx) + lut[y0, x1] * fx
    top = lut[y1, x0] * (1 - fx) + lut[y1, x1] * fx
    return bottom * (1 - fy) + top * fy


class Colorizer(PostEffect):
    id = "COLORIZER"
    label = "Colorizer"
    icon = "COLOR"
    description = "Recolour through a lookup image indexed by blurred luminance and distance to the centre"
    params = (
        Param("image", "IMAGE", None, "Lookup image (x: luminance, y: centre to corners); empty uses a built-in grade"),
        Param(
            "blur_radius",
            "INT",
            2,
            "Blur of the luminance before the lookup, in pixels; 0 = none",
            min=0,
            max=GAUSSIAN_MAX_RADIUS,
            soft_max=32,
            unit="PIXELS",
        ),
        Param(
            "strength",
            "FLOAT",
            1.0,
            "Blend between the original colour (0) and the lookup colour (1)",
            min=0.0,
            max=1.0,
            subtype="FACTOR",
        ),
    )

    def __init__(self):
        self._blur = Blur()
        self._default_lut = {}

    def is_identity(self, params):
        return params.strength <= 0.0

    def execute(self, ctx, src, params, mix):
        luma = src
        if params.blur_radius > 0:
            blur = SimpleNamespace(radius=params.blur_radius, sigma=0.0, half_resolution=False)
            luma = self._blur.execute(ctx, src, blur, 1.0)
        dst = ctx.acquire(src, luma)
        return ctx.fullscreen(
            PROGRAM,
            dst,
            samplers={
                "source_tex": src,
                "luma_tex": luma,
                "lut_tex": image_or_table(params.image, self._default_lut, DEFAULT_LUT),
            },
            uniforms={"mix_factor": mix, "strength": params.strength},
        )


def colorizer_reference(img, lut, blur_radius, strength):
    """Reference of the whole COLORIZER layer, numpy-ready, in float64: ``img`` (h, w, 4) with
    non-finite components read as 0, its rgb blended towards ``lut_lookup`` of the lookup
    coordinates by ``strength``; alpha kept. ``lut``: (H, W, C), e.g. ``DEFAULT_LUT``."""
    import numpy as np

    from .blur import gaussian_reference

    h, w = img.shape[:2]
    c = np.nan_to_num(np.asarray(img).astype(np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    blurred = gaussian_reference(c, blur_radius) if blur_radius > 0 else c
    y, x = np.mgrid[0:h, 0:w] + 0.5
    lx, ly = lookup_coords(blurred[..., :3] @ np.array(LUMA_WEIGHTS), x, y, w, h)
    out = c.copy()
    out[..., :3] = c[..., :3] * (1 - strength) + lut_lookup(lut, lx, ly)[..., :3] * strength
    return out
