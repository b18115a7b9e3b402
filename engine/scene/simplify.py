"""Levels of detail: a mesh's triangles merged where the frame cannot show them apart.

With Blender's Render › Simplify switched on, its Penumbra › Merge Below (``simplify_pixels``,
2 px by default; 0 draws every triangle) sets a cell size in pixels. Each
instance gets the coarsest level whose cells, at the instance's nearest point to the camera,
are at most that many pixels across. A level clusters the mesh on a grid of ``2**level`` cells
along its longest side and puts each cluster's vertex where the planes of its triangles meet
best (Lindstrom's out-of-core simplification: the sum of the triangles' plane quadrics,
minimised inside the cell), so flat and gently curved parts keep their surface while the
triangle count drops. A vertex never leaves its cell: no surface point moves further than a
cell's diagonal, and measured errors are far smaller (``python -m tools.bench perf --sections
instances``). The same level draws the instance in the lit pass and into every shadow map, so a
surface and its shadow agree.

Only what needs no more than positions and normals is simplified: meshes whose materials read
UVs, colour attributes or tangents, or use alpha, are drawn whole, as are meshes that cross the
camera's near plane and levels that would keep most of the triangles."""

import math

import numpy as np

from ..store import Kind
from .geometry import Geometry, content_key

MIN_LEVEL = 2  # 4 cells along the longest side: the coarsest level
MAX_LEVEL = 12  # 4096 cells: finer ones keep nearly every triangle of real meshes
MIN_TRIANGLES = 2048  # smaller meshes are drawn whole (their draw costs more than their triangles)
WORTH = 0.7  # a level keeping more than this fraction of the triangles is not used
_LEVELS = Kind("levels")  # (content digest, level) -> (Geometry or None,): final renders extract anew


def level_for(extent, stretch, nearest_depth, footprint, pixels):
    """The coarsest level whose cell (``extent`` / 2**level in the mesh, times the model's
    largest ``stretch``) is at most ``pixels`` pixels wide at view depth ``nearest_depth``
    (``footprint`` = (per_depth, constant) of ``lightspace.pixel_footprint``); None when even
    MAX_LEVEL is coarser than that, or nothing is known (off, behind the near plane, degenerate)."""
    per_depth, constant = footprint
    pixel = per_depth * nearest_depth + constant
    world = extent * stretch
    if not (pixels > 0.0 and pixel > 0.0 and world > 0.0 and math.isfinite(world) and math.isfinite(pixel)):
        return None
    level = max(MIN_LEVEL, math.ceil(math.log2(world / (pixels * pixel))))
    return level if level <= MAX_LEVEL else None


def simplified(geo, level):
    """``geo`` (a ``geometry.Geometry``) clustered at ``level``, remembered by content; None when
    the level would keep more than WORTH of the triangles or none at all."""
    # An extracted mesh kept in the store is named by its content already (``Geometry.content``).
    digest = geo.content if geo.content is not None else getattr(geo, "_simplify_digest", None)
    if digest is None:
        ranges = np.asarray(geo.ranges, np.int64).reshape(-1, 3)
        digest = geo._simplify_digest = content_key(geo.indices, geo.positions, geo.normals, ranges)
    key = (digest, level)
    held = _LEVELS.get(key)
    if held is None:
        lod = cluster(geo, level)
        if lod is not None:  # its batches are kept by it in final renders (``frame/batches.py``)
            lod.content = digest + int(level).to_bytes(4, "little", signed=True)
        held = _LEVELS.put(key, (lod,), 64 if lod is None else lod.nbytes)
    return held[0]


def cluster(geo, level):
    """The clustering of ``simplified`` (not remembered)."""

    tris = np.asarray(geo.indices, np.int64)
    if len(tris) == 0:
        return None
    lo, hi = np.asarray(geo.bounds[0], np.float64), np.asarray(geo.bounds[1], np.float64)
    extent = float(np.max(hi - lo))
    if not (math.isfinite(extent) and extent > 0.0):
        return None
    cells = 2**level
    cell = extent / cells
    p = np.asarray(geo.positions, np.float64)
    g = np.clip(np.floor((p - lo) / cell), 0, cells - 1).astype(np.int64)
    # A cluster is a cell and a sixth of the directions (the largest component of the normal
    # at the vertex's position, and its sign): the two sides of a part thinner than a cell
    # stay apart, while the corners of one position (flat shading) stay together.
    same, distinct = _positions(p)
    nrm = np.stack([np.bincount(same, geo.normals[:, k], distinct) for k in range(3)], axis=1)[same]
    axis = np.argmax(np.abs(nrm), axis=1)
    side = axis * 2 + (np.take_along_axis(nrm, axis[:, None], axis=1)[:, 0] > 0.0)
    cluster_of, keys = _compact(((g[:, 0] * cells + g[:, 1]) * cells + g[:, 2]) * 6 + side)
    cell_index = keys // 6
    count = len(cell_index)
    corner = cluster_of[tris]  # (t, 3) clusters of each triangle's corners
    kept = (corner[:, 0] != corner[:, 1]) & (corner[:, 1] != corner[:, 2]) & (corner[:, 0] != corner[:, 2])
    if not kept.any() or kept.sum() > WORTH * len(tris):  # nothing, or too much, would be left
        return None

    x, n, unit, length = _quadric_points(p, tris, corner, cluster_of, count)
    cmin = lo + np.stack([cell_index // (cells * cells), cell_index // cells % cells, cell_index % cells], 1) * cell
    x = np.clip(x, np.maximum(cmin, lo), np.minimum(cmin + cell, hi))

    face_material = np.repeat([m for m, _f, _c in geo.ranges], [c for _m, _f, c in geo.ranges])
    new, mats = corner[kept], face_material[kept]
    # A triangle turned over by the merge (both sides of a part thinner than a cell meeting in
    # the same cells) is dropped: the side facing the other way keeps the part's outline.
    pa, pb, pc = x[new[:, 0]], x[new[:, 1]], x[new[:, 2]]
    upright = np.einsum("ij,ij->i", np.cross(pb - pa, pc - pa), n[kept]) > 0.0
    new, mats = new[upright], mats[upright]
    if len(new) == 0:
        return None
    # A triangle met twice (same corners, same turn) is drawn once.
    rolled = np.take_along_axis(new, (np.argmin(new, axis=1)[:, None] + np.arange(3)[None]) % 3, axis=1)
    _u, first = np.unique(rolled, axis=0, return_index=True)
    first.sort()
    new, mats = new[first], mats[first]
    if len(new) > WORTH * len(tris):
        return None
    order = np.argsort(mats, kind="stable")
    new, mats = new[order], mats[order]
    values, starts, counts = np.unique(mats, return_index=True, return_counts=True)
    ranges = [(int(m), int(s), int(k)) for m, s, k in zip(values, starts, counts, strict=True)]

    positions, normals, indices = _shaded(
        x, new, cluster_of, count, geo.normals, _flat(unit, geo.normals, tris, length)
    )
    return Geometry(
        np.ascontiguousarray(positions, np.float32),
        np.ascontiguousarray(normals, np.float32),
        np.ascontiguousarray(indices, np.int32),
        ranges,
        np.array([lo, hi]),
        smooth=geo.smooth,
    )


def _quadric_points(p, tris, corner, cluster_of, count):
    """Where each of ``count`` clusters puts its vertex: the point of least squared distance
    to the planes of its corners' triangles (Lindstrom's quadrics, see the module). ``p``: the
    vertices, ``tris`` their triangles, ``corner`` the clusters of each triangle's corners and
    ``cluster_of`` each vertex's. Returns (points, the triangles' normals scaled by twice their
    area, their unit normals, that length)."""
    # Plane quadrics of the triangles (weighted by area), summed per cluster of each corner.
    a, b, c = p[tris[:, 0]], p[tris[:, 1]], p[tris[:, 2]]
    n = np.cross(b - a, c - a)
    length = np.linalg.norm(n, axis=1)
    unit = n / np.where(length > 0.0, length, 1.0)[:, None]
    plane = np.concatenate([unit, -np.einsum("ij,ij->i", unit, a)[:, None]], axis=1)
    plane *= np.sqrt(0.5 * length)[:, None]
    rows, cols = np.triu_indices(4)
    quadric = np.zeros((count, 10))  # the upper triangle of each cluster's 4x4 quadric
    for k, (row, col) in enumerate(zip(rows, cols, strict=True)):
        q = plane[:, row] * plane[:, col]
        for j in range(3):
            quadric[:, k] += np.bincount(corner[:, j], q, count)
    full = np.zeros((count, 4, 4))
    full[:, rows, cols] = quadric
    full[:, cols, rows] = quadric
    weight = np.bincount(cluster_of, minlength=count).astype(np.float64)
    mean = np.stack([np.bincount(cluster_of, p[:, k], count) for k in range(3)], axis=1) / weight[:, None]
    # Minimise x^T A x + 2 b.x, pulled slightly towards the cluster's mean so that flat or
    # straight clusters (a singular A) stay put; then kept inside the cell and the bounds.
    big_a, small_b = full[:, :3, :3], full[:, :3, 3]
    reg = (1e-3 * np.trace(big_a, axis1=1, axis2=2) / 3.0 + 1e-300)[:, None, None] * np.eye(3)
    rhs = np.einsum("nij,nj->ni", reg, mean) - small_b
    x = np.linalg.solve(big_a + reg, rhs[..., None])[..., 0]
    return np.where(np.isfinite(x), x, mean), n, unit, length


def _shaded(x, new, cluster_of, count, vertex_normals, flat):
    """(positions, normals, indices) of the triangles ``new`` over the cluster points ``x``:
    each triangle on three vertices of its own normal when ``flat``, else the clusters'
    vertices with the mean of their original ``vertex_normals``."""
    if flat:
        # Flat shading: every triangle its own normal, on its own three vertices.
        pa, pb, pc = x[new[:, 0]], x[new[:, 1]], x[new[:, 2]]
        fn = np.cross(pb - pa, pc - pa)
        fn /= np.maximum(np.linalg.norm(fn, axis=1), 1e-300)[:, None]
        positions = np.stack([pa, pb, pc], axis=1).reshape(-1, 3)
        normals = np.repeat(fn, 3, axis=0)
        indices = np.arange(len(positions)).reshape(-1, 3)
    else:
        # Smooth shading: the cluster's original normals averaged.
        nsum = np.stack([np.bincount(cluster_of, vertex_normals[:, k], count) for k in range(3)], axis=1)
        norm = np.linalg.norm(nsum, axis=1)
        normals = np.where(norm[:, None] > 1e-12, nsum / np.where(norm > 0.0, norm, 1.0)[:, None], (0.0, 0.0, 1.0))
        used = np.zeros(count, bool)
        used[new.ravel()] = True
        remap = np.cumsum(used) - 1
        positions, normals, indices = x[used], normals[used], remap[new]
    return positions, normals, indices


def _positions(p):
    """(index of each row of ``p`` among its distinct rows, how many distinct rows): the rows
    sorted by their float32 bits (equal floats, equal bits; -0 and 0 apart, which only splits
    a position in two)."""
    bits = np.ascontiguousarray(p, np.float32).view(np.uint32).astype(np.uint64)
    order = np.lexsort((bits[:, 2], (bits[:, 0] << np.uint64(32)) | bits[:, 1]))
    ordered = bits[order]
    new = np.ones(len(p), bool)
    new[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    index = np.empty(len(p), np.int64)
    index[order] = np.cumsum(new) - 1
    return index, int(new.sum())


def _compact(keys):
    """(index of each key among the distinct keys, the distinct keys)."""
    distinct, inverse = np.unique(keys, return_inverse=True)
    return inverse.ravel(), distinct


def _flat(unit, normals, tris, length):
    """Whether the mesh is shaded flat: every corner's normal is its triangle's (to within
    0.1 degree: a smooth sphere of a million triangles still differs by more)."""
    ok = length > 0.0
    if not ok.any():
        return True
    vertex_normals = np.asarray(normals, np.float64)[tris[ok]]  # (t, 3, 3)
    return bool(np.all(np.einsum("tj,tkj->tk", unit[ok], vertex_normals) > 1.0 - 1.5e-6))
