"""LENS_FLARE: procedural ghosts and a halo from the bright parts of the image, one pass.

The flare ``f`` at the output pixel centre ``x`` (pixels) is defined as follows, with the centre
``C = size / 2``, ``R = |C|`` (the half-diagonal), ``u = x - C`` and ``r = |u| / R``:

* bright pass, per texel: ``B = max(c.rgb - threshold, 0)`` on the NaN-free input; ``B(q)`` is
  its bilinear read at position ``q`` (texel centres at i + 0.5), black outside the image;
* ghost ``i`` (0 <= i < ``ghosts``) reads ``q_i = C + u * (ghost_spacing * i - 1)``: ghost 0 is
  the mirror image through the centre, later ghosts march along the same line. Each is weighted
  by ``w(q) = (1 - min(|q - C| / R, 1)) ** 3``, so sources near the centre flare most. A light at
  ``b`` therefore shows ghost ``i`` centred on ``C + (b - C) / (ghost_spacing * i - 1)``
  (``ghost_positions``), scaled by ``1 / |ghost_spacing * i - 1|``;
* the halo is a ring about the centre: the profile ``ring = t * t * (3 - 2 * t)`` with
  ``t = clamp(1 - |r - halo_radius| / halo_width, 0, 1)`` (radii in units of ``R``; width 0 =
  no halo) times ``B`` at ``q_h = C + u / |u| * (halo_radius * R - |u|)`` (``u / |u|`` read as
  0 at the centre), so a bright area near the centre lights the ring and an off-centre one
  lights arcs of it;
* ``f = intensity * (sum_i w(q_i) B(q_i) + ring * B(q_h)) * T``, where the lens texture ``T``
  is the ``image`` if one is set (RGB, stretched over the frame, bilinear, clamped at its
  borders: a lens-dirt or flare-colour texture multiplying the flare), otherwise the built-in
  radial colour ramp ``LENS_RAMP`` read at ``r`` (texel coordinate ``r * (N - 1)``).

``mode`` merges ``f`` into the input colour ``c`` (alpha is kept):

* ADD: ``c + f`` (the physically plain choice for scene-linear HDR);
* SCREEN: ``1 - (1 - c') * (1 - f')`` with ``c' = max(c, 0)``, ``f' = max(f, 0)``, per channel.
  Screen is a display-range operator: it brightens only where the input is at most 1. Where
  the input exceeds 1 a flare below 1 darkens it (c = 2, f = 0.5 gives 1.5), and where both
  exceed 1 the product turns positive, so the result can go negative (c = f = 3 gives -3).
  Prefer ADD for HDR light sources;
* AVERAGE: ``(c + f) / 2``; where there is no flare this halves the image;
* DIFFERENCE: ``|c - f|``.

A flare that is empty by its parameters (``intensity`` 0, or no ghosts and no halo) skips the
layer in every mode; a flare that is empty because nothing exceeds the threshold still merges
(ADD, SCREEN and DIFFERENCE then return the input, AVERAGE halves it).
"""

import numpy as np

from ..enums import Enum
from ..settings import Param
from .base import PostEffect, image_or_table, post_program

MERGE = Enum(
    "lens flare merge",
    "MERGE",
    (
        ("ADD", "Add", "Input plus flare", 0),
        ("SCREEN", "Screen", "1 - (1 - input)(1 - flare) on values clamped to >= 0; meant for display-range values", 1),
        ("AVERAGE", "Average", "(input + flare) / 2", 2),
        ("DIFFERENCE", "Difference", "|input - flare|", 3),
    ),
)

PROGRAM = post_program(
    "post_lens_flare",
    "post/lens_flare.frag.glsl",
    push_constants=(
        ("FLOAT", "threshold"),
        ("FLOAT", "intensity"),
        ("FLOAT", "ghost_spacing"),
        ("FLOAT", "halo_radius"),
        ("FLOAT", "halo_width"),
        ("INT", "ghosts"),
        ("INT", "merge_mode"),
        ("INT", "lens_image"),  # 1: lens_tex is the user's image, 0: the built-in ramp
    ),
    samplers=(("FLOAT_2D", "lens_tex"),),
    defines=MERGE.defines(),
)

MAX_GHOSTS = 16

# Built-in lens texture: an RGB ramp from the image centre (first entry) to the corners (last),
# the warm-to-violet tint of coated lens ghosts.
LENS_RAMP = np.array(
    [(1.00, 0.92, 0.80), (0.95, 1.00, 0.90), (0.75, 0.90, 1.00), (0.85, 0.70, 1.00)],
    dtype=np.float32,
)


def ghost_positions(bx, by, width, height, ghosts, spacing):
    """Where the ghosts of a light at pixel position (``bx``, ``by``) are centred: a list of
    ``(i, x, y, scale)`` for every ghost ``i`` whose line factor ``spacing * i - 1`` is not 0;
    ``scale`` is the ghost's size relative to the light."""
    cx, cy = width * 0.5, height * 0.5
    out = []
    for i in range(min(int(ghosts), MAX_GHOSTS)):
        k = spacing * i - 1.0
        if k != 0.0:
            out.append((i, cx + (bx - cx) / k, cy + (by - cy) / k, 1.0 / abs(k)))
    return out


def merge(c, f, mode):
    """Reference of the merge modes, numpy-ready (``c``, ``f``: RGB arrays)."""
    c = np.asarray(c, dtype=np.float64)
    f = np.asarray(f, dtype=np.float64)
    if mode == "SCREEN":
        return 1.0 - (1.0 - np.maximum(c, 0.0)) * (1.0 - np.maximum(f, 0.0))
    if mode == "AVERAGE":
        return (c + f) * 0.5
    if mode == "DIFFERENCE":
        return np.abs(c - f)
    return c + f


class LensFlare(PostEffect):
    id = "LENS_FLARE"
    label = "Lens Flare"
    icon = "LIGHT_SUN"
    description = "Ghosts and a halo from the bright parts of the image"
    params = (
        Param("threshold", "FLOAT", 1.0, "Only colour above this value (per channel) flares", min=0.0, soft_max=10.0),
        Param(
            "intensity",
            "FLOAT",
            1.0,
            "Brightness of the flare; 0 turns the layer off",
            min=0.0,
            max=1000.0,
            soft_max=10.0,
        ),
        Param("mode", "ENUM", "ADD", "How the flare is merged into the image", enum=MERGE),
        Param("ghosts", "INT", 4, "Number of ghost images along the line through the centre", min=0, max=MAX_GHOSTS),
        Param(
            "ghost_spacing",
            "FLOAT",
            0.4,
            "Step between ghosts along the line through the centre",
            min=0.0,
            max=16.0,
            soft_max=2.0,
        ),
        Param(
            "halo_radius",
            "FLOAT",
            0.6,
            "Radius of the halo ring (1 = the image corners)",
            min=0.0,
            max=16.0,
            soft_max=1.5,
        ),
        Param("halo_width", "FLOAT", 0.1, "Half-width of the halo ring; 0 = no halo", min=0.0, max=16.0, soft_max=0.5),
        Param(
            "image",
            "IMAGE",
            None,
            "Lens dirt / colour texture multiplying the flare; empty uses a built-in radial ramp",
        ),
    )

    def __init__(self):
        self._ramp = {}

    def is_identity(self, params):
        no_flare = params.ghosts <= 0 and params.halo_width <= 0.0
        return params.intensity <= 0.0 or no_flare

    def execute(self, ctx, src, params, mix):
        return ctx.single_pass(
            PROGRAM,
            src,
            mix,
            samplers={"lens_tex": image_or_table(params.image, self._ramp, LENS_RAMP)},
            uniforms={
                "threshold": params.threshold,
                "intensity": params.intensity,
                "ghost_spacing": params.ghost_spacing,
                "halo_radius": params.halo_radius,
                "halo_width": params.halo_width,
                "ghosts": params.ghosts,
                "merge_mode": MERGE.value(params.mode),
                "lens_image": int(params.image is not None),
            },
        )


def flare_reference(img, params, lens=None):
    """The flare ``f`` of this module's definition, numpy-ready, in float64 (h, w, 3), for the
    input ``img`` (h, w, 4) and a namespace ``params`` holding threshold, intensity, ghosts,
    ghost_spacing, halo_radius and halo_width (the merge ``mode`` is ``merge``'s business).
    ``lens``: the lens image's pixels (H, W, C), or None for ``LENS_RAMP``."""
    import numpy as np

    from .colorizer import lut_lookup
    from .fisheye import bilinear_reference

    p = params
    h, w = img.shape[:2]
    clean = np.nan_to_num(np.asarray(img).astype(np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    bright = np.maximum(clean[..., :3] - p.threshold, 0.0)
    y, x = np.mgrid[0:h, 0:w] + 0.5
    cx, cy = w / 2, h / 2
    diag = np.hypot(cx, cy)
    ux, uy = x - cx, y - cy
    dist = np.hypot(ux, uy)
    r = dist / diag
    f = np.zeros((h, w, 3))
    for i in range(p.ghosts):
        k = p.ghost_spacing * i - 1.0
        qx, qy = cx + ux * k, cy + uy * k
        a = 1.0 - np.clip(np.hypot(qx - cx, qy - cy) / diag, 0.0, 1.0)
        f += (a**3)[..., None] * bilinear_reference(bright, qx, qy, "BLACK")
    if p.halo_width > 0:
        t = np.clip(1.0 - np.abs(r - p.halo_radius) / p.halo_width, 0.0, 1.0)
        ring = t * t * (3.0 - 2.0 * t)
        safe = np.where(dist > 0, dist, 1.0)
        dx, dy = np.where(dist > 0, ux / safe, 0.0), np.where(dist > 0, uy / safe, 0.0)
        along = p.halo_radius * diag - dist
        f += ring[..., None] * bilinear_reference(bright, cx + dx * along, cy + dy * along, "BLACK")
    if lens is None:
        tint = lut_lookup(LENS_RAMP[None], r, np.zeros_like(r))
    else:
        lh, lw = lens.shape[:2]
        tint = bilinear_reference(np.asarray(lens)[..., :3], x / w * lw, y / h * lh, "CLAMP")
    return p.intensity * f * tint
