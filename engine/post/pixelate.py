"""PIXELATE: replace the image by square cells of one colour each.

Cells are ``size`` pixels wide, anchored at the bottom-left pixel (0, 0); cells at the
right and top edges may be partial. Every channel, alpha included, is resampled.

CENTER takes one pixel per cell: along each axis, with ``n`` the number of the cell's pixels
that exist (``size`` for whole cells), the pixel at ``origin + n // 2`` -- the exact
centre for odd ``n``, the upper/right one of the two middle pixels for even ``n``. One pass.

AVERAGE is the mean of the pixels of the cell that exist. Three passes, each O(1) work per
pixel on average whatever the cell size: row sums per cell into a compact grid at the
bottom-left of a target, column sums of those, then every pixel reads its cell's mean.

A cell larger than the image is one cell covering it; sizes are clamped to the image's
larger side, which gives the same result.
"""

from ..enums import Enum
from ..settings import Param
from .base import PostEffect, post_program

SAMPLING = Enum(
    "pixelate sampling",
    "SAMPLING",
    (
        ("CENTER", "Center", "Each cell takes the colour of its centre pixel (sharp, cheap)", 0),
        ("AVERAGE", "Average", "Each cell takes the mean colour of its pixels (smooth, less shimmer)", 1),
    ),
)

# The shader's passes, selected by the PIXELATE_PASS define (see pixelate.frag.glsl).
PASS = Enum(
    "pixelate pass",
    "PASS",
    (
        ("CENTER", "Center", "Each pixel takes its cell's centre pixel", 0),
        ("ROWS", "Rows", "Row means of each cell into a compact grid", 1),
        ("COLUMNS", "Columns", "Column means of the row means", 2),
        ("EXPAND", "Expand", "Each pixel takes its cell's mean", 3),
    ),
)

PROGRAM = post_program(
    "post_pixelate",
    "post/pixelate.frag.glsl",
    push_constants=(("INT", "cell_size"),),
    samplers=(("FLOAT_2D", "input_tex"),),
    defines=PASS.defines(),
)


class Pixelate(PostEffect):
    id = "PIXELATE"
    label = "Pixelate"
    icon = "MESH_GRID"
    description = "Mosaic of square cells of one colour"
    params = (
        Param(
            "size", "INT", 8, "Cell width in pixels; 1 leaves the image unchanged", min=1, soft_max=64, unit="PIXELS"
        ),
        Param("sampling", "ENUM", "AVERAGE", "How a cell's colour is chosen", enum=SAMPLING),
    )

    def is_identity(self, params):
        return params.size <= 1

    def execute(self, ctx, src, params, mix):
        size = min(params.size, max(ctx.width, ctx.height))

        def run(pass_id, target, input_tex, mix_factor):
            return ctx.fullscreen(
                PROGRAM,
                target,
                defines={"PIXELATE_PASS": PASS.define(pass_id)},
                samplers={"source_tex": src, "input_tex": input_tex},
                uniforms={"mix_factor": mix_factor, "cell_size": size},
            )

        if params.sampling == "CENTER":
            return run("CENTER", ctx.acquire(src), src, mix)
        rows = ctx.acquire(src)
        run("ROWS", rows, src, 1.0)
        cells = ctx.acquire(src, rows.texture)
        run("COLUMNS", cells, rows.texture, 1.0)
        return run("EXPAND", ctx.acquire(src, cells.texture), cells.texture, mix)


def pixelate_reference(img, size, sampling):
    """Reference of the PIXELATE layer, numpy-ready, in float64: cells anchored at (0, 0);
    CENTER: the pixel at origin + n // 2 of the n that exist; AVERAGE: the mean. Non-finite
    components read as 0."""
    import numpy as np

    h, w = img.shape[:2]
    clean = np.where(np.isfinite(img), img, 0.0).astype(np.float64)
    out = np.empty_like(clean)
    for y0 in range(0, h, size):
        for x0 in range(0, w, size):
            cell = clean[y0 : y0 + size, x0 : x0 + size]
            if sampling == "CENTER":
                value = cell[cell.shape[0] // 2, cell.shape[1] // 2]
            else:
                value = cell.mean(axis=(0, 1))
            out[y0 : y0 + size, x0 : x0 + size] = value
    return out
