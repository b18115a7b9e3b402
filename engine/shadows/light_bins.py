"""Which lights can reach which part of the screen: plain numpy, no bpy and no gpu.

The screen is cut into square bins of ``BIN_SIZE`` pixels; each bin lists, as a bit mask, the
lights that can light a visible surface inside it, and the lit pass loops over those lights
only. A pixel outside a spot's cone or behind an area light then costs nothing for that light,
so a frame with many local lights costs what their overlap costs, not their number.

A light's reach is a convex polytope: its influence (a spot's cone, bounded by the square
pyramid around it; the half-space in front of an area light; all space for suns and points)
intersected with the box around everything drawn and with the camera's view frustum. Its
vertices, found by intersecting every three of its planes, project to a screen rectangle; the
bins that rectangle touches get the light's bit. Every step is conservative: a light may be
listed in a bin it does not reach, never left out of one it does.
"""

import functools
import itertools
import math

import numpy as np

from .vectors import cross

BIN_SIZE = 16  # pixels per side of a bin
WORD_BITS = 16  # lights per float channel: sums of distinct powers of two below 2^16 are exact in float32
WIDE_SPOT = math.radians(80.0)  # half-angles above this are bounded by their half-space only


def _unit_planes(planes):
    """Rows (nx, ny, nz, d) meaning n . x <= d, scaled to unit normals (zero rows stay zero)."""
    planes = np.asarray(planes, np.float64).reshape(-1, 4)
    n = np.linalg.norm(planes[:, :3], axis=1, keepdims=True)
    return np.where(n > 0, planes / np.where(n > 0, n, 1.0), 0.0)


def frustum_planes(view_proj):
    """The six planes of a camera's view volume (OpenGL clip space: -w <= x, y, z <= w)."""
    m = np.asarray(view_proj, np.float64)
    rows = []
    for axis in range(3):
        for sign in (1.0, -1.0):
            # sign * clip[axis] <= clip.w  ->  (sign * row_axis - row_w) . (x, 1) <= 0
            r = sign * m[axis] - m[3]
            rows.append((*r[:3], -r[3]))
    return _unit_planes(rows)


# The outward normals of an axis-aligned box's faces, +x, -x, +y, -y, +z, -z (unit already:
# ``_unit_planes`` leaves them as they are, signed zeros included).
_BOX_NORMALS = np.array([sign * np.eye(3)[axis] for axis in range(3) for sign in (1.0, -1.0)])


def box_planes(lo, hi):
    """The six planes of the axis-aligned box [lo, hi]."""
    lo = np.asarray(lo, np.float64)
    hi = np.asarray(hi, np.float64)
    return np.column_stack((_BOX_NORMALS, (hi[0], -lo[0], hi[1], -lo[1], hi[2], -lo[2])))


def influence_planes(light):
    """Half-spaces bounding where ``light`` can deliver light (empty: everywhere)."""
    kind = light.type
    if kind not in ("SPOT", "AREA"):
        return np.zeros((0, 4))
    p, a = light.position, light.direction
    if kind == "AREA":
        return _unit_planes([(*(-a), -(a @ p))])  # emits forward only: (x - p) . a >= 0
    half = 0.5 * light.cone_size
    if half > WIDE_SPOT:
        return _unit_planes([(*(-a), -(a @ p))])
    helper = np.eye(3)[int(np.argmin(np.abs(a)))]
    u = cross(a, helper)
    u /= np.linalg.norm(u)
    v = cross(a, u)
    c, s = math.cos(half), math.sin(half)
    rows = [(-a[0], -a[1], -a[2], -(a @ p))]  # in front of the apex
    for side in (u, -u, v, -v):
        n = side * c - a * s  # the side of the square pyramid circumscribing the cone
        rows.append((*n, n @ p))
    return _unit_planes(rows)


_TRIPLES = {}


def _triples(count):
    """(t, 3) indices of every triple of ``count`` planes (cached per count)."""
    got = _TRIPLES.get(count)
    if got is None:
        got = _TRIPLES[count] = np.array(list(itertools.combinations(range(count), 3)), dtype=np.intp).reshape(-1, 3)
    return got


def polytope_vertices(planes, tolerance):
    """Vertices of {x : n . x <= d for every row}: every triple of planes intersected (Cramer's
    rule, all triples at once), the points inside all of them kept. (k, 3); empty when the
    polytope is empty."""
    planes = np.asarray(planes, dtype=np.float64)
    return polytope_vertices_many(planes[None], (tolerance,))[0]


def polytope_vertices_many(planes, tolerances):
    """``polytope_vertices`` of each of several polytopes of as many planes, (n, p, 4), with
    their ``tolerances``, all their triples intersected at once (the same operations on each
    triple as one polytope at a time, so the same bits): a list of n (k, 3) arrays."""
    planes = np.asarray(planes, dtype=np.float64)
    count, p = planes.shape[:2]
    triples = _triples(p)
    t = len(triples)
    if t == 0 or count == 0:
        return [np.zeros((0, 3)) for _ in range(count)]
    normals = planes[..., :3]
    pairs = cross(normals[:, :, None], normals[:, None, :])  # (n, p, p, 3): every pair's cross product
    i, j, k = triples.T
    c12, c20, c01 = (pairs[:, a, b].reshape(-1, 3) for a, b in ((j, k), (k, i), (i, j)))
    d = planes[:, triples, 3].reshape(-1, 3)  # (n t, 3)
    det = np.einsum("ij,ij->i", normals[:, i].reshape(-1, 3), c12)
    ok = np.abs(det) > 1e-9
    x = (d[ok, 0, None] * c12[ok] + d[ok, 1, None] * c20[ok] + d[ok, 2, None] * c01[ok]) / det[ok, None]
    out, start = [], 0
    for m, end in enumerate(np.cumsum(ok.reshape(count, t).sum(axis=1)).tolist()):
        xm, start = x[start:end], end
        if len(xm) == 0:
            out.append(np.zeros((0, 3)))
            continue
        inside = np.all(xm @ planes[m, :, :3].T - planes[m, :, 3] <= tolerances[m], axis=1)
        out.append(xm[inside])
    return out


def light_reach(light):
    """How far (world units) the points a light is sampled at lie from its centre: a spot's or
    point's radius (its ball), half an area light's diagonal (its own axes carry the object's
    scale); 0 for suns, whose samples turn the direction, which bounds nothing here."""
    if light.type == "AREA":
        m = np.asarray(light.matrix, np.float64)
        half = 0.5 * (np.linalg.norm(m[:3, 0]) * abs(light.size_x) + np.linalg.norm(m[:3, 1]) * abs(light.size_y))
        return float(half) if math.isfinite(half) else math.inf
    if light.type in ("SPOT", "POINT"):
        return max(float(light.radius), 0.0)
    return 0.0


def screen_rects(lights, view_proj, lo, hi, width, height, pads=None, pixel_pad=0):
    """Per light, the pixel rectangle (x0, y0, x1, y1) (end exclusive) it can light, or None
    when it reaches no visible surface. ``lo``/``hi``: the box around everything drawn.
    ``pads``: per light, how far (world units) its sampled points may lie from its centre
    (``light_reach``): every plane of its influence moves out by that much, so the rectangle
    holds what the light reaches from any of them (a plane n . x <= n . p through a point p of
    the light becomes n . x <= n . p + |p' - p| for every p' within the pad). ``pixel_pad``:
    pixels more on every side (the camera's per-sample offsets). Lights without influence
    planes (suns, points, the world's directions) reach the same polytope: it is computed once."""
    vp = np.asarray(view_proj, np.float64)
    frustum = frustum_planes(vp)
    scene = box_planes(lo, hi)
    scale = float(np.max(np.abs(np.concatenate([lo, hi])))) if np.all(np.isfinite([lo, hi])) else 0.0
    full = (0, 0, width, height)
    grow = 1 + max(int(math.ceil(pixel_pad)), 0) if math.isfinite(pixel_pad) else width + height
    everywhere = []  # the rectangle of a light without influence planes, once computed

    def rect_of(planes):
        if not np.all(np.isfinite(planes)):
            return full
        tolerance = 1e-6 * (1.0 + scale + np.abs(planes[:, 3]).max())
        verts = polytope_vertices(planes, tolerance)
        if len(verts) == 0:
            return None
        clip = np.c_[verts, np.ones(len(verts))] @ vp.T
        w = clip[:, 3]
        if np.any(w <= 0) or not np.all(np.isfinite(clip)):
            return full  # numerically at the camera: keep it everywhere
        px = (clip[:, 0] / w * 0.5 + 0.5) * width
        py = (clip[:, 1] / w * 0.5 + 0.5) * height
        x0 = int(np.clip(math.floor(px.min()) - grow, 0, width))
        x1 = int(np.clip(math.ceil(px.max()) + grow, 0, width))
        y0 = int(np.clip(math.floor(py.min()) - grow, 0, height))
        y1 = int(np.clip(math.ceil(py.max()) + grow, 0, height))
        return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None

    rects = []
    for k, light in enumerate(lights):
        influence = influence_planes(light)
        if len(influence) == 0:
            if not everywhere:
                everywhere.append(rect_of(np.concatenate([scene, frustum])))
            rects.append(everywhere[0])
            continue
        if pads is not None and pads[k]:
            influence = influence.copy()
            influence[:, 3] += pads[k]
        rects.append(rect_of(np.concatenate([influence, scene, frustum])))
    return rects


def bin_masks(rects, width, height, words=4):
    """The bins' light masks: (rows, columns, words) float32; bit b of word w set means light
    ``w * WORD_BITS + b`` can reach the bin. ``rects``: per light, from ``screen_rects``."""
    cols, rows = -(-width // BIN_SIZE), -(-height // BIN_SIZE)
    masks = np.zeros((rows, cols, words), np.float64)
    for index, rect in enumerate(rects):
        if rect is None:
            continue
        x0, y0, x1, y1 = rect
        word, bit = divmod(index, WORD_BITS)
        masks[y0 // BIN_SIZE : -(-y1 // BIN_SIZE), x0 // BIN_SIZE : -(-x1 // BIN_SIZE), word] += float(1 << bit)
    return masks.astype(np.float32)


@functools.lru_cache(maxsize=256)
def word_masks(first, count, words=4):
    """Per word, the bits of lights ``first .. first + count - 1`` (a tuple: kept per
    arguments, every sample asks again)."""
    out = []
    for w in range(words):
        bits = 0
        for b in range(WORD_BITS):
            if first <= w * WORD_BITS + b < first + count:
                bits |= 1 << b
        out.append(bits)
    return tuple(out)
