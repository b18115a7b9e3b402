"""Light-space maths: look-at, projections, fitting, texel snapping.

Plain numpy, no bpy and no gpu, so every function here is unit-tested against hand-derived
values. Matrices are 4x4 float64, column-vector convention (``clip = P @ V @ world``), the same
as Blender's ``mathutils`` and OpenGL.
"""

import itertools
import math

import numpy as np

from ..counts import ceil_count
from . import light_bins
from .vectors import cross


# Maps clip-space xyz in [-1, 1] to texture space [0, 1]: the "bias matrix" of projective shadow
# texturing (Segal et al. 1992, "Fast Shadows and Lighting Effects Using Texture Mapping";
# Everitt, Rege and Cebenoyan 2001, "Hardware Shadow Mapping").
def from_origin(origin):
    """The 4x4 translation by ``origin``: a world -> X matrix times it takes positions relative
    to ``origin`` (the frame origin the GPU works around; see ``Renderer.render``)."""
    t = np.eye(4)
    t[:3, 3] = origin
    return t


BIAS_MATRIX = np.array(
    [
        [0.5, 0.0, 0.0, 0.5],
        [0.0, 0.5, 0.0, 0.5],
        [0.0, 0.0, 0.5, 0.5],
        [0.0, 0.0, 0.0, 1.0],
    ]
)


def normalize(v, fallback=(0.0, 0.0, -1.0)):
    """Unit vector along ``v``; ``fallback`` when ``v`` is zero or not finite."""
    v = np.asarray(v, dtype=np.float64)
    flat = v.ravel()
    n = math.sqrt(float(flat @ flat))  # np.linalg.norm's value, without its dispatch
    if not math.isfinite(n) or n < 1e-30:
        return np.asarray(fallback, dtype=np.float64)
    return v / n


def look_at(eye, forward):
    """World-to-view matrix for a viewer at ``eye`` looking along ``forward`` (-Z in view space).

    The up vector is chosen from the world axis least aligned with ``forward``, so a light
    pointing exactly along +-Z or +-Y never produces a degenerate (zero) basis.
    """
    f = normalize(forward)
    axes = np.eye(3)
    up = axes[int(np.argmin(np.abs(axes @ f)))]
    right = normalize(cross(f, up))
    true_up = cross(right, f)
    view = np.eye(4)
    view[0, :3] = right
    view[1, :3] = true_up
    view[2, :3] = -f
    eye = np.asarray(eye, dtype=np.float64)
    view[:3, 3] = -view[:3, :3] @ eye
    return view


def orthographic(left, right, bottom, top, near, far):
    """OpenGL orthographic projection (view-space z in [-far, -near] maps to NDC [-1, 1])."""
    m = np.eye(4)
    m[0, 0] = 2.0 / (right - left)
    m[1, 1] = 2.0 / (top - bottom)
    m[2, 2] = -2.0 / (far - near)
    m[0, 3] = -(right + left) / (right - left)
    m[1, 3] = -(top + bottom) / (top - bottom)
    m[2, 3] = -(far + near) / (far - near)
    return m


def perspective(fov_y, aspect, near, far):
    """OpenGL perspective projection, ``fov_y`` in radians."""
    f = 1.0 / np.tan(fov_y / 2.0)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def transform_points(matrix, points):
    """Apply a 4x4 affine/projective matrix to (N, 3) points, with the perspective divide."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    h = pts @ matrix[:3, :3].T + matrix[:3, 3]
    w = pts @ matrix[3, :3] + matrix[3, 3]
    if np.allclose(matrix[3], (0.0, 0.0, 0.0, 1.0)):
        return h
    return h / w[:, None]


def box_corners(lo, hi):
    """The eight corners of an axis-aligned box."""
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    idx = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=bool)
    return np.where(idx, hi, lo)


def normal_matrix(model):
    """3x3 matrix that transforms normals for ``model``.

    The cofactor matrix equals ``det * inverse(M).T``: it is defined even for singular
    (zero-scale) matrices, and multiplying by ``sign(det)`` keeps normals outward under
    negative scale. Callers normalise after transforming.
    """
    a = np.asarray(model, dtype=np.float64)[:3, :3]
    cof = np.empty((3, 3))
    cof[:, 0] = cross(a[:, 1], a[:, 2])
    cof[:, 1] = cross(a[:, 2], a[:, 0])
    cof[:, 2] = cross(a[:, 0], a[:, 1])
    det = float(np.linalg.det(a))
    sign = -1.0 if det < 0.0 else 1.0
    return cof * sign


class Fit:
    """A fitted light view: ``view`` (world -> light view), ``proj`` (view -> clip), the linear
    depth range [near, far] along the view axis, and the world size of one texel: constant for
    orthographic maps (``texel``), proportional to distance for perspective ones
    (``texel_per_distance``). ``pivot``: the view depth (z) a sun's map is sheared about
    (``sheared``): the middle of the receivers' depth range."""

    __slots__ = ("view", "proj", "near", "far", "texel", "texel_per_distance", "pivot")

    def __init__(self, view, proj, near, far, texel=0.0, texel_per_distance=0.0, pivot=0.0):
        self.view, self.proj, self.near, self.far = view, proj, float(near), float(far)
        self.texel, self.texel_per_distance = float(texel), float(texel_per_distance)
        self.pivot = float(pivot)

    @property
    def view_proj(self):
        return self.proj @ self.view

    @property
    def orthographic(self):
        """True when clip w is 1 everywhere: window depth is then linear in view distance, and
        ``proj`` maps [near, far] to it exactly."""
        return bool(np.array_equal(self.proj[3], (0.0, 0.0, 0.0, 1.0)))


def shifted(fit, texels, size):
    """``fit`` with its texel grid moved by ``texels`` (x, y) of a map ``size`` texels wide: a
    translation of clip space, exact for orthographic and perspective maps alike. The depth
    range and texel size are unchanged."""
    shift = np.eye(4)
    shift[0, 3] = 2.0 * float(texels[0]) / size
    shift[1, 3] = 2.0 * float(texels[1]) / size
    return Fit(fit.view, shift @ fit.proj, fit.near, fit.far, fit.texel, fit.texel_per_distance, fit.pivot)


def sheared(fit, direction):
    """A sun's orthographic ``fit`` made to project along ``direction`` instead of its view's
    axis: the map's x and y slide with view depth z by the direction's slope, x - kx (z - pivot),
    so every point of a ray along ``direction`` lands on one texel (the oblique projection of a
    sampled sun, derived from the frame's centred fit instead of fitted again; cf. Heckbert and
    Herf 1997, who shear a light's projection per sample point). Depth stays the view's z, which
    grows along the ray as long as the direction points into the map, so the depth test is
    unchanged; the view matrix stays a rotation (normals and the light's axis read from it).
    The map covers every receiver and caster of the sampled direction only when ``fit`` was
    fitted with a ``cone`` at least the direction's slope (``fit_sun_to_view``). Returns ``fit``
    itself for its own direction (so an unmoved map is reused)."""
    v = fit.view[:3, :3] @ np.asarray(direction, dtype=np.float64)
    if not np.all(np.isfinite(v)) or v[2] >= -1e-6:
        return fit  # not into the map: no oblique projection of it exists
    kx, ky = float(v[0] / v[2]), float(v[1] / v[2])
    if kx == 0.0 and ky == 0.0:
        return fit
    shear = np.eye(4)
    shear[0, 2], shear[1, 2] = -kx, -ky
    shear[0, 3], shear[1, 3] = kx * fit.pivot, ky * fit.pivot
    return Fit(fit.view, fit.proj @ shear, fit.near, fit.far, fit.texel, fit.texel_per_distance, fit.pivot)


def moved(fit, offset):
    """A perspective ``fit`` with its eye moved by ``offset`` (world), its axes, window and
    depth range kept: the off-axis map of a point of a light that the frame planned at its
    centre (``planning.FrameShare.reaches``: the plan then holds every point within the
    light's reach). Returns ``fit`` itself for no move (so an unmoved map is reused)."""
    offset = np.asarray(offset, dtype=np.float64)
    if not np.any(offset) or not np.all(np.isfinite(offset)):
        return fit
    view = np.array(fit.view, dtype=np.float64)
    view[:3, 3] -= view[:3, :3] @ offset
    return Fit(view, fit.proj, fit.near, fit.far, fit.texel, fit.texel_per_distance, fit.pivot)


def dilated_boxes(corners, radius):
    """(n, 8, 3) corners of each box's axis-aligned bounds grown by ``radius``: they hold every
    point of the box moved by up to ``radius``."""
    boxes = np.asarray(corners, dtype=np.float64).reshape(-1, 8, 3)
    if len(boxes) == 0:
        return boxes
    lo, hi = boxes.min(axis=1) - radius, boxes.max(axis=1) + radius
    return np.stack([box_corners(a, b) for a, b in zip(lo, hi, strict=True)])


_CUBE = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])


def dilated_receivers(receivers, radius):
    """``Receivers`` grown by ``radius``: boxes as ``dilated_boxes``, each convex piece as the
    hull of a cube of that half-size around each of its points."""
    pieces = [(np.asarray(p, np.float64)[:, None, :] + radius * _CUBE).reshape(-1, 3) for p in receivers.pieces]
    return Receivers(dilated_boxes(receivers.whole, radius), pieces)


def fit_sun_ortho(direction, points, map_size, padding_texels=2.0):
    """Fit an orthographic light frustum for a sun shining along ``direction`` around ``points``.

    Returns a ``Fit`` (or ``None`` without finite points). See ``_ortho_fit``."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) == 0:
        return None
    view = look_at((0.0, 0.0, 0.0), direction)
    ls = transform_points(view, pts)
    return _ortho_fit(view, ls.min(axis=0), ls.max(axis=0), float(np.abs(ls).max()), map_size, padding_texels)


def _ortho_fit(view, lo, hi, scale, map_size, padding_texels=2.0):
    """Orthographic fit of the light-space box [lo, hi]. Its x/y extent is quantised to steps
    of 2^(1/4) (at most 19% wasted per axis) and its origin snapped to whole texels, so small
    changes of the fitted set or of the camera do not move texel boundaries (no shimmering).
    The depth range covers the box with a margin so casters behind receivers are kept."""
    map_size = max(1, int(map_size))
    scale = max(float(scale), 1e-30)
    extent = float(max(hi[0] - lo[0], hi[1] - lo[1]))
    extent = max(extent, scale * 1e-6, 1e-30)
    extent = 2.0 ** (np.ceil(np.log2(extent) * 4.0) / 4.0)
    texel = extent / max(map_size - 2.0 * padding_texels, 1.0)
    half = 0.5 * texel * map_size
    cx = np.floor(0.5 * (lo[0] + hi[0]) / texel) * texel
    cy = np.floor(0.5 * (lo[1] + hi[1]) / texel) * texel
    depth = float(hi[2] - lo[2])
    margin = max(depth * 0.01, texel * 4.0, scale * 1e-6)
    near = -hi[2] - margin
    far = -lo[2] + margin
    proj = orthographic(cx - half, cx + half, cy - half, cy + half, near, far)
    return Fit(view, proj, near, far, texel=texel)


def frustum_corners(view_proj):
    """World-space corners (8, 3) of the clip volume of ``view_proj``."""
    inv = np.linalg.inv(view_proj)
    ndc = box_corners((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))
    h = np.concatenate([ndc, np.ones((8, 1))], axis=1) @ inv.T
    return h[:, :3] / h[:, 3:4]


def hull_planes(corners):
    """The face planes (rows n, d meaning n . x <= d, unit n) of the convex hexahedron with
    ``corners`` (8, 3) in ``box_corners`` order: a box, a view frustum or a slice of one.
    Degenerate faces are left out."""
    c = np.asarray(corners, dtype=np.float64).reshape(8, 3)
    centre = c.mean(axis=0)
    rows = []
    for face in ((0, 2, 6, 4), (1, 5, 7, 3), (0, 4, 5, 1), (2, 3, 7, 6), (0, 1, 3, 2), (4, 6, 7, 5)):
        p = c[list(face)]
        n = cross(p[2] - p[0], p[3] - p[1])  # the quad's diagonals: robust for thin faces
        length = float(np.linalg.norm(n))
        if not np.isfinite(length) or length <= 0.0:
            continue
        n /= length
        d = float(n @ p.mean(axis=0))
        if n @ centre > d:
            n, d = -n, -d
        rows.append((*n, d))
    return np.array(rows, dtype=np.float64).reshape(-1, 4)


def _classify(boxes, planes):
    """For boxes (n, 8, 3): (wholly inside the convex region ``planes``, wholly outside one of
    its planes), with a tolerance relative to the region's and each box's scale."""
    s = np.einsum("nkj,pj->nkp", boxes, planes[:, :3]) - planes[None, None, :, 3]
    scale = max(float(np.abs(planes[:, 3]).max()), 1e-300)  # relative: a 0.1 mm scene as a 1 km one
    tol = 1e-9 * np.maximum(scale, np.abs(boxes).max(axis=(1, 2)))[:, None, None]
    return np.all(s <= tol, axis=(1, 2)), np.any(np.all(s > tol, axis=1), axis=1)


def _cut(planes, points):
    """The vertices of the bounding box of ``points`` cut by the convex region ``planes``."""
    return _cuts([(planes, points)])[0]


def _cuts(jobs):
    """``_cut(planes, points)`` of every (planes, points) of ``jobs``, the polytopes of as many
    planes intersected together (``light_bins.polytope_vertices_many``: the same bits as one
    at a time, a fraction of the calls)."""
    groups = {}
    for n, (planes, points) in enumerate(jobs):
        lo, hi = points.min(axis=0), points.max(axis=0)
        scale = max(float(np.abs(planes[:, 3]).max()), float(np.abs(points).max()), 1e-300)
        stacked = np.concatenate([planes, light_bins.box_planes(lo, hi)])
        groups.setdefault(len(stacked), []).append((n, stacked, 1e-6 * scale))
    out = [None] * len(jobs)
    for group in groups.values():
        found = light_bins.polytope_vertices_many(np.stack([g[1] for g in group]), [g[2] for g in group])
        for (n, _planes, _tolerance), vertices in zip(group, found, strict=True):
            out[n] = vertices
    return out


def clipped_points(boxes, planes, per_box=False):
    """The part of each box (``boxes`` (N, 8, 3) corners; each taken as its world bounds) inside
    the convex region ``planes``: boxes wholly inside give their corners, boxes crossing it
    the vertices of box ∩ region. Returns (points (k, 3), seen (N,) bool: the box reaches into
    the region); with ``per_box`` the points are a list of one array per box (empty if unseen)."""
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 8, 3)
    seen = np.zeros(len(boxes), dtype=bool)
    parts = [np.zeros((0, 3))] * len(boxes)
    if len(boxes) and len(planes):
        inside, outside = _classify(boxes, planes)
        for i in np.nonzero(inside)[0]:
            parts[i] = boxes[i]
        seen |= inside
        crossing = np.nonzero(~inside & ~outside)[0]
        for i, v in zip(crossing, _cuts([(planes, boxes[i]) for i in crossing]), strict=True):
            if len(v):
                seen[i] = True
                parts[i] = v
    if per_box:
        return parts, seen
    return (np.concatenate(parts) if parts else np.zeros((0, 3))), seen


def off_center_perspective(left, right, bottom, top, near, far):
    """OpenGL perspective projection of the window [left, right] x [bottom, top] given in
    tangent units (x / -z, y / -z), view-space z in [-far, -near] mapped to NDC [-1, 1]."""
    m = np.zeros((4, 4))
    m[0, 0] = 2.0 / (right - left)
    m[0, 2] = (right + left) / (right - left)
    m[1, 1] = 2.0 / (top - bottom)
    m[1, 2] = (top + bottom) / (top - bottom)
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


class Receivers:
    """What the camera sees, as world points of convex pieces: ``whole`` (m, 8, 3) the boxes
    wholly inside the view frustum, ``pieces`` the vertices of each box that crosses it, cut to
    it. Built once per frame (``visible_receivers``) and shared by every light's fit."""

    __slots__ = ("whole", "pieces")

    def __init__(self, whole, pieces):
        self.whole, self.pieces = whole, pieces


def visible_receivers(corners, view_proj):
    """``Receivers`` of the boxes ``corners`` (N, 8, 3) inside the camera's ``view_proj``."""
    boxes = np.asarray(corners, dtype=np.float64).reshape(-1, 8, 3)
    if len(boxes) == 0:
        return Receivers(boxes, [])
    planes = light_bins.frustum_planes(view_proj)
    inside, outside = _classify(boxes, planes)
    crossing = ~inside & ~outside
    return Receivers(boxes[inside], pieces_in(planes, boxes[crossing]) if crossing.any() else [])


def window(points, view, near):
    """(lo, hi) of the tangent-space window (x / -z, y / -z) of world ``points`` (all in front
    of the near plane)."""
    q = points @ view[:3, :3].T + view[:3, 3]
    uv = q[:, :2] / np.maximum(-q[:, 2:3], near)
    return uv.min(axis=0), uv.max(axis=0)


def pieces_in(planes, boxes, pieces=()):
    """The parts of ``boxes`` (n, 8, 3) and of the convex ``pieces`` (point arrays) inside
    the convex region ``planes``, as a list of point arrays."""
    return pieces_in_many([planes], [boxes], pieces)[0]


def pieces_in_many(regions, boxes, pieces=()):
    """``pieces_in(regions[m], boxes[m], pieces)`` for every m: the parts of each region's
    boxes and of the ``pieces`` they all share, the boxes and pieces that cross a region cut
    by it all together (``_cuts``). A list of lists of point arrays, in ``pieces_in``'s order."""
    outs, jobs, slots = [], [], []
    for m, (planes, region_boxes) in enumerate(zip(regions, boxes, strict=True)):
        out, crossing = [], ()
        if len(region_boxes):
            inside, outside = _classify(region_boxes, planes)
            if inside.any():
                out.append(region_boxes[inside].reshape(-1, 3))
            crossing = region_boxes[~inside & ~outside]
        # Each piece wholly outside one of the planes (skipped), wholly inside them all (taken
        # whole), or cut; the crossing boxes (8 corners each) all at once, the same products.
        tests = []
        for p in pieces:
            side = p @ planes[:, :3].T - planes[:, 3]
            tests.append((bool(np.any(np.all(side > 0.0, axis=0))), bool(np.all(side <= 0.0))))
        if len(crossing):
            side = crossing @ planes[:, :3].T - planes[:, 3]
            tests += zip(np.any(np.all(side > 0.0, axis=1), axis=1).tolist(), np.all(side <= 0.0, axis=(1, 2)).tolist())
        for p, (away, within) in zip(itertools.chain(pieces, crossing), tests, strict=True):
            if away:
                continue
            if within:
                out.append(p)
            else:
                slots.append((m, len(out)))
                out.append(None)
                jobs.append((planes, p))
        outs.append(out)
    for (m, slot), v in zip(slots, _cuts(jobs), strict=True):
        outs[m][slot] = v if len(v) else None
    return [[v for v in out if v is not None] for out in outs]


FLAT = 1e-6  # a box this thin relative to its longest edge is a flat (planar) mesh's
MAX_FLAT_TESTS = 16  # flat boxes tested for casting nothing (the largest: grounds and walls)


def flat_boxes(boxes):
    """(N,) bool: the boxes (N, 8, 3) one of whose edges is at most FLAT of their longest: the
    bounds of a planar mesh (a ground, a wall, a card)."""
    lengths = np.linalg.norm(boxes[:, [1, 2, 4]] - boxes[:, [0]], axis=2)  # the edges from corner 0
    return lengths.min(axis=1) <= FLAT * lengths.max(axis=1)


def flat_casters_without_shadow(boxes, direction=None, position=None):
    """(N,) bool: flat boxes (planar meshes: grounds, walls, cards) that cannot shadow anything
    under a sun shining along ``direction`` (or a light at ``position``), because no other box
    reaches behind their plane (the side away from the light) or the light grazes them
    edge-on. A planar mesh never shadows itself, so such a box is left out of the light's
    maps: it costs nothing to draw and does not widen the map. Only the MAX_FLAT_TESTS
    largest flat boxes are tested. (``FlatCasters`` keeps what the test needs of the boxes
    for every light: a caller testing several lights over the same boxes makes one.)"""
    return FlatCasters(boxes).free(direction, position)


class FlatCasters:
    """``flat_casters_without_shadow`` over one set of boxes (N, 8, 3), for any number of
    lights: the flat boxes tested, their planes, and for each side of a plane whether another
    box reaches beyond it there, found once (a light only picks the side it shines from). A
    frame's samples fit a map to a new direction of the world, or to a light at a new point
    of itself, every sample; the boxes, and so this, stay the frame's."""

    def __init__(self, boxes):
        boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 8, 3)
        self.boxes = boxes
        self.count = n_boxes = len(boxes)
        self._reaches = {}  # (candidate, side) -> another box reaches beyond its plane on that side
        if n_boxes == 0:
            self.candidates = np.zeros(0, dtype=np.intp)
            return
        edges = boxes[:, [1, 2, 4]] - boxes[:, [0]]  # the box's three edges from corner 0
        lengths = np.linalg.norm(edges, axis=2)
        self._longest = longest = lengths.max(axis=1)
        thin = lengths.argmin(axis=1)
        rows = np.arange(n_boxes)
        a, b = edges[rows, (thin + 1) % 3], edges[rows, (thin + 2) % 3]
        self._normal = normal = cross(a, b)
        self._area = area = np.linalg.norm(normal, axis=1)
        flat = flat_boxes(boxes) & (area > 1e-12 * longest**2) & np.isfinite(area)
        candidates = np.nonzero(flat)[0]
        self.candidates = candidates[np.argsort(-area[candidates])][:MAX_FLAT_TESTS]

    def _plane(self, i):
        n = self._normal[i] / self._area[i]
        return n, float(n @ self.boxes[i, 0])

    def _reach(self, i, side):
        """Whether a box other than ``i`` reaches beyond box ``i``'s plane on ``side`` (1.0:
        along its normal, -1.0: against it), by more than the test's tolerance."""
        key = (int(i), side)
        found = self._reaches.get(key)
        if found is None:
            boxes = self.boxes
            n, d = self._plane(i)
            reach = side * (boxes @ n - d)  # > 0: behind the plane, where it could shadow
            reach[i] = 0.0
            tolerance = 1e-5 * max(float(np.abs(boxes[i]).max()), self._longest[i])
            found = self._reaches[key] = bool((reach.max(axis=1) > tolerance).any())
        return found

    def free(self, direction=None, position=None):
        """``flat_casters_without_shadow`` of these boxes under a sun along ``direction`` or a
        light at ``position``."""
        free = np.zeros(self.count, dtype=bool)
        if self.count == 0:
            return free
        light = normalize(direction) if position is None else None
        for i in self.candidates:
            n, d = self._plane(i)
            if light is not None:
                s = float(n @ light)
                grazing = abs(s) <= 1e-9
            else:
                s = d - float(n @ np.asarray(position, dtype=np.float64))  # > 0: the light below the plane
                grazing = abs(s) <= 1e-9 * max(1.0, abs(d))
            if grazing:
                free[i] = True  # edge-on to the light: its shadow has no area
                continue
            free[i] = not self._reach(i, 1.0 if s > 0.0 else -1.0)
        return free


MAX_EXACT_CROPS = 32  # receivers cut exactly to a sun map's rectangle (the largest first)


def pixel_footprint(projection, is_ortho, width, height):
    """(per_depth, constant): a screen pixel at view depth z is ``per_depth * z + constant``
    wide in the world (the finer of its two sides); (0, 0) for a degenerate projection."""
    p = np.asarray(projection, dtype=np.float64)
    sx, sy = abs(float(p[0, 0])) * max(int(width), 1), abs(float(p[1, 1])) * max(int(height), 1)
    scale = max(sx, sy)
    if not math.isfinite(scale) or scale <= 0.0:
        return 0.0, 0.0
    return (0.0, 2.0 / scale) if is_ortho else (2.0 / scale, 0.0)


def max_filter_radius(map_size):
    """The widest disk kernel (texels) of a map of ``map_size``: a quarter of it, at least 32
    texels (``programs.max_filter_radius``, which the shaders read, is this). Maps are fitted
    to their casters, so a penumbra may span a good part of one; a cap in texels would make
    larger maps draw narrower penumbrae."""
    return max(32.0, float(map_size) / 4.0)


def _rect_planes(view, lo, hi):
    """World planes of the light-space prism lo <= (x, y) <= hi of an orthographic ``view``."""
    rows = []
    for axis in (0, 1):
        n, o = view[axis, :3], view[axis, 3]
        rows.append((*n, hi[axis] - o))
        rows.append((*(-n), o - lo[axis]))
    return np.array(rows, dtype=np.float64)


def _receivers_in_rect(parts, view, lo, hi):
    """Light-space points of the receivers (``parts``: per box, its points inside the view)
    that lie over the rectangle [lo, hi] (x, y). Boxes wholly over it or off it are decided by
    their points; the MAX_EXACT_CROPS largest that straddle it are cut exactly (a ground
    plane's far reaches drop out), the rest count whole (conservative)."""
    out, straddle = [], []
    for p in parts:
        if len(p) == 0:
            continue
        q = p @ view[:3, :3].T + view[:3, 3]
        over = np.all((q[:, :2] >= lo[:2]) & (q[:, :2] <= hi[:2]), axis=1)
        if over.all():
            out.append(q)
        elif (q[:, 0].max() >= lo[0]) & (q[:, 0].min() <= hi[0]) & (q[:, 1].max() >= lo[1]) & (q[:, 1].min() <= hi[1]):
            straddle.append((float(np.ptp(p, axis=0).max()), p, q))
    straddle.sort(key=lambda t: -t[0])
    rect = _rect_planes(view, lo, hi)
    for k, (_size, p, q) in enumerate(straddle):
        if k >= MAX_EXACT_CROPS:
            out.append(q)
            continue
        # The box's visible part is convex: cut the hull of its points by the prism. Its
        # points' bounds are a box containing that part, so clip that box (exact for a
        # ground plane, whose visible part is a polygon in its plane).
        cut, _seen = clipped_points(box_corners(p.min(axis=0), p.max(axis=0))[None], rect)
        if len(cut):
            out.append(cut @ view[:3, :3].T + view[:3, 3])
    return np.concatenate(out) if out else np.zeros((0, 3))


def view_parts(corners, view_corners):
    """The parts of the boxes ``corners`` (N, 8, 3) inside the camera frustum ``view_corners``
    (``clipped_points`` per box: (parts, seen)): the receivers ``fit_sun_to_view`` fits every
    sun to, the same whatever the sun's direction, so a frame computes them once."""
    boxes = np.asarray(corners, dtype=np.float64).reshape(-1, 8, 3)
    return clipped_points(boxes, hull_planes(view_corners), per_box=True)


def fit_sun_to_view(
    direction, corners, view_corners, map_size, soft=0.0, flat_free=None, parts=None, cone=0.0, kept=None
):
    """Tight sun fit (a loose box wastes the map's texels; cf. Lauritzen, Salvi and Lefohn 2011,
    "Sample Distribution Shadow Maps"): the map covers only the receivers
    the camera can see that some caster can shadow, and every caster that can shadow them.
    ``corners``: (N, 8, 3) world box corners of all geometry; ``view_corners``: the 8 world
    corners of the camera frustum (or of the slice of it a cascade covers); ``soft``: the
    tangent of the half-angle the filter spreads shadows over (PCSS of a sun's angle; 0 for a
    fixed kernel); ``parts``: ``view_parts(corners, view_corners)`` when the caller has them.
    ``cone``: the tangent of the largest angle between ``direction`` and the directions the
    map will be ``sheared`` to (a sampled sun's half-angle): every receiver and caster is then
    taken as sliding by ``cone`` x its depth from the fit's pivot, so one fit holds the map
    of every direction in the cone. Returns ``(Fit, caster indices)``, or ``None`` when
    nothing the camera sees can be shadowed. ``kept``: (a dict kept between navigation
    frames, this map's slot in it): the fit an earlier frame made for the slot is taken again
    while its rectangle and depth range hold this one's and it is at most twice as wide (its
    casters those that reach its rectangle), so a moving view keeps the map.

    Receivers: the part of every box inside the frustum (box ∩ frustum, exact for a ground
    plane under a perspective camera). Casters: every box except flat ones that shadow
    nothing (``flat_casters_without_shadow``: a ground with everything standing on it). The
    map covers the receivers' light-space rectangle cut to the casters' footprints in it (a
    receiver outside every caster's footprint cannot be in shadow), widened by how far a
    penumbra reaches out of a footprint (``soft`` x the receivers' depth span there); its
    depth range is that of the receivers over the rectangle."""
    boxes = np.asarray(corners, dtype=np.float64).reshape(-1, 8, 3)
    if len(boxes) == 0:
        return None
    view = look_at((0.0, 0.0, 0.0), direction)
    parts, seen = view_parts(boxes, view_corners) if parts is None else parts
    if not seen.any():
        return None
    rls = np.concatenate([p for p in parts if len(p)]) @ view[:3, :3].T + view[:3, 3]
    lo, hi = rls.min(axis=0), rls.max(axis=0)
    ls = boxes @ view[:3, :3].T + view[:3, 3]
    blo, bhi = ls.min(axis=1), ls.max(axis=1)
    pivot = 0.5 * float(lo[2] + hi[2])
    cone = float(cone) if math.isfinite(cone) and cone > 0.0 else 0.0
    if cone:  # what a sheared map sees of them: each slides by cone x its depth from the pivot
        slide = cone * float(np.abs(rls[:, 2] - pivot).max())
        lo[:2] -= slide
        hi[:2] += slide
        box_slide = cone * np.maximum(np.abs(blo[:, 2] - pivot), np.abs(bhi[:, 2] - pivot))
        blo[:, :2] -= box_slide[:, None]
        bhi[:, :2] += box_slide[:, None]
    # ``flat_free``: the caller's flat_casters_without_shadow for this sun (one per sun, shared by its cascades).
    can_cast = ~(flat_casters_without_shadow(boxes, direction) if flat_free is None else flat_free)
    # Casters: boxes whose footprint overlaps the receivers' rectangle, at any depth towards
    # the light and not wholly behind the receivers. The depth range stays the receivers':
    # casters nearer the light than its near plane are flattened onto it by the depth pass
    # ("pancaking", shadow_depth.vert), where they still occlude everything in the region, so
    # a tall caster does not stretch the range and cost depth precision.
    overlap = np.all((blo[:, :2] <= hi[:2]) & (bhi[:, :2] >= lo[:2]), axis=1) & (bhi[:, 2] >= lo[2])
    casters = np.nonzero(overlap & can_cast)[0]
    if len(casters) == 0:
        return None
    seen_lo, seen_hi = lo[:2].copy(), hi[:2].copy()
    lo[:2] = np.maximum(lo[:2], blo[casters, :2].min(axis=0))
    hi[:2] = np.minimum(hi[:2], bhi[casters, :2].max(axis=0))
    inside = _receivers_in_rect(parts, view, lo, hi)
    if len(inside) == 0:
        return None
    if soft > 0.0:
        reach = float(soft) * float(inside[:, 2].max() - inside[:, 2].min())
        lo[:2] = np.maximum(seen_lo, lo[:2] - reach)
        hi[:2] = np.minimum(seen_hi, hi[:2] + reach)
        inside = _receivers_in_rect(parts, view, lo, hi)
        if len(inside) == 0:
            return None
        casters = casters[np.all((blo[casters, :2] <= hi[:2]) & (bhi[casters, :2] >= lo[:2]), axis=1)]
    lo[2], hi[2] = inside[:, 2].min(), inside[:, 2].max()
    if soft > 0.0:
        # PCSS reads the blocker's depth: casters nearer the light than the receivers keep
        # their true depth up to the distance where the penumbra reaches the widest kernel
        # (beyond it the kernel is capped anyway); only casters farther still are pancaked.
        texel = float(max(hi[0] - lo[0], hi[1] - lo[1])) / max(int(map_size) - 4, 1)
        reach = max_filter_radius(map_size) * texel / float(soft)
        hi[2] = max(hi[2], min(float(bhi[casters, 2].max()), hi[2] + reach))
    if kept is not None:
        store, slot = kept
        old = store.get(slot)
        if (
            old is not None
            and np.all(old[0] <= lo)
            and np.all(old[1] >= hi)
            and max(old[1][0] - old[0][0], old[1][1] - old[0][1]) <= 2.0 * max(hi[0] - lo[0], hi[1] - lo[1])
        ):
            lo, hi = old[0].copy(), old[1].copy()
            reach = np.all((blo[:, :2] <= hi[:2]) & (bhi[:, :2] >= lo[:2]), axis=1) & (bhi[:, 2] >= lo[2])
            casters = np.nonzero(reach & can_cast)[0]
        if len(store) >= 1024:
            store.clear()
        store[slot] = (lo.copy(), hi.copy())
    scale = float(np.abs(np.concatenate([lo, hi])).max())
    fit = _ortho_fit(view, lo, hi, scale, map_size)
    fit.pivot = pivot
    return fit, casters


MAX_CASCADES = 4
CASCADE_RATIO = 20.0  # farthest / nearest depth one cascade covers when chosen automatically
CASCADE_LAMBDA = 1.0  # practical split scheme: weight of the logarithmic split (the range
# is the visible geometry's, so logarithmic splits give every cascade the same depth ratio)


def view_depth_range(projection, view, corners, is_ortho):
    """(near, far) view depths of the geometry the camera can see: the camera's clip range
    narrowed to the depth range of the boxes (``corners`` (N, 8, 3)) that overlap the view
    frustum. None when nothing is seen."""
    clip = clip_range(projection, is_ortho)
    if clip is None:
        return None
    boxes = np.asarray(corners, dtype=np.float64).reshape(-1, 8, 3)
    if len(boxes) == 0:
        return None
    points, _seen = clipped_points(boxes, light_bins.frustum_planes(projection @ view))
    if len(points) == 0:
        return None
    depth = -(points @ view[2, :3] + view[2, 3])  # view depth of every visible vertex
    near = max(clip[0], float(depth.min()))
    far = min(clip[1], float(depth.max()))
    if not (far > near > 0.0 or (is_ortho and far > near)):
        return None
    return near, far


def box_depth_range(projection, view, corners, is_ortho):
    """A quick, wider ``view_depth_range``: the boxes' depth range within the clip range,
    without clipping them to the view frustum (a few numpy operations for 10,000 boxes)."""
    clip = clip_range(projection, is_ortho)
    boxes = np.asarray(corners, dtype=np.float64).reshape(-1, 3)
    if clip is None or len(boxes) == 0:
        return None
    depth = -(boxes @ view[2, :3] + view[2, 3])
    near, far = max(clip[0], float(depth.min())), min(clip[1], float(depth.max()))
    if not (far > near > 0.0 or (is_ortho and far > near)):
        return None
    return near, far


def clip_range(projection, is_ortho):
    """The (near, far) clip distances of an OpenGL projection matrix."""
    p22, p23 = np.float64(projection[2, 2]), np.float64(projection[2, 3])  # numpy: a zero divisor gives inf
    with np.errstate(divide="ignore", invalid="ignore"):
        if is_ortho:
            near, far = (p23 + 1.0) / p22, (p23 - 1.0) / p22
        else:
            near, far = p23 / (p22 - 1.0), p23 / (p22 + 1.0)
    if not (np.isfinite(near) and np.isfinite(far) and far > near):
        return None
    return near, far


DEPTH_FIT_MARGIN = 1e-3  # relative widening of the visible depth range the lit pass rasterises


def depth_fitted(projection, is_ortho, depth_range):
    """``projection`` with its depth row mapping the visible geometry's depth range
    (``view_depth_range``, widened by DEPTH_FIT_MARGIN) instead of the whole clip range: x and
    y are unchanged, and nothing lies between the two near planes or the two far planes, so
    what is clipped is unchanged too, while the depth buffer's precision goes to what is
    there (a clip range of 1e-6 .. 100 leaves float32 depth two values for a 10 m scene).
    The projection as it is when the range is unknown or the matrix is not a plain one."""
    p = np.asarray(projection, np.float64)
    clip = clip_range(p, is_ortho)
    if depth_range is None or clip is None or p[2, 0] != 0.0 or p[2, 1] != 0.0:
        return projection
    near, far = float(depth_range[0]), float(depth_range[1])
    if is_ortho:
        pad = DEPTH_FIT_MARGIN * max(far - near, abs(near), abs(far), 1e-30)
        near, far = max(clip[0], near - pad), min(clip[1], far + pad)
    else:
        near, far = max(clip[0], near * (1.0 - DEPTH_FIT_MARGIN)), min(clip[1], far * (1.0 + DEPTH_FIT_MARGIN))
    if not (far > near and (is_ortho or near > 0.0)) or (near, far) == clip:
        return projection
    out = p.copy()
    if is_ortho:
        out[2, 2], out[2, 3] = -2.0 / (far - near), -(far + near) / (far - near)
    else:
        out[2, 2], out[2, 3] = -(far + near) / (far - near), -2.0 * far * near / (far - near)
    return out


def cascade_count(near, far, requested=0):
    """How many cascades: ``requested`` (1-4), or with 0 enough for each to span at most
    CASCADE_RATIO in depth (1 for most scenes, up to 4 for a long view over a large ground)."""
    if requested:
        return int(min(max(requested, 1), MAX_CASCADES))
    if not (near > 0.0 and far > near):
        return 1
    return ceil_count(math.log(far / near) / math.log(CASCADE_RATIO) - 1e-9, 1, MAX_CASCADES)


def cascade_splits(near, far, count, lam=CASCADE_LAMBDA):
    """``count + 1`` view depths from ``near`` to ``far``: the practical split scheme, a blend
    of logarithmic (weight ``lam``) and uniform splits."""
    i = np.arange(count + 1) / count
    uniform = near + (far - near) * i
    log = near * (far / near) ** i if near > 0.0 else uniform
    out = lam * log + (1.0 - lam) * uniform
    out[0], out[-1] = near, far
    return out


def slice_corners(view_corners, near_clip, far_clip, a, b):
    """The 8 world corners of the part of the view frustum between view depths ``a`` and
    ``b`` (``view_corners``: the frustum's corners, near face first, from ``frustum_corners``;
    its near and far planes at ``near_clip``, ``far_clip``). Depth is linear along each
    corner's ray from the near face to the far face."""
    vc = np.asarray(view_corners, dtype=np.float64)
    # frustum_corners orders corners by box_corners: z = -1 (near) first for each (x, y).
    near_face, far_face = vc[vc_index(False)], vc[vc_index(True)]
    span = far_clip - near_clip
    ta, tb = (a - near_clip) / span, (b - near_clip) / span
    return np.concatenate([near_face + (far_face - near_face) * ta, near_face + (far_face - near_face) * tb])


def vc_index(far):
    """Indices of the near (or far) face's corners in ``frustum_corners``' order."""
    ndc = box_corners((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))
    return np.nonzero(ndc[:, 2] > 0 if far else ndc[:, 2] < 0)[0]


# Cube-map faces: +X, -X, +Y, -Y, +Z, -Z. The GLSL face selection (cube_face) uses this order.
CUBE_FORWARDS = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64)


def cube_face(direction):
    """Index into CUBE_FORWARDS of the face that sees ``direction`` (its major axis)."""
    d = np.asarray(direction, dtype=np.float64)
    axis = int(np.argmax(np.abs(d)))
    return 2 * axis + (0 if d[axis] >= 0.0 else 1)


def boxes_in_frustum(view_proj, corners):
    """For (N, 8, 3) box corners, whether each box may intersect the clip volume of
    ``view_proj`` (conservative: a box is out only when all its corners are beyond one plane)."""
    c = np.asarray(corners, dtype=np.float64)
    if c.size == 0:
        return np.zeros(0, dtype=bool)
    h = c @ view_proj[:3, :3].T + view_proj[:3, 3]
    w = c @ view_proj[3, :3] + view_proj[3, 3]
    out = np.zeros(c.shape[0], dtype=bool)
    for axis in range(3):
        out |= np.all(h[..., axis] > w, axis=1)
        out |= np.all(h[..., axis] < -w, axis=1)
    return ~out


def finite_inverse(m):
    """The inverse of the 4x4 ``m`` (float64), or None where it is singular or not finite."""
    try:
        inv = np.linalg.inv(np.asarray(m, np.float64))
    except np.linalg.LinAlgError:
        return None
    return inv if np.all(np.isfinite(inv)) else None
