"""Motion blur by sampling the shutter (Cook, Porter and Carpenter 1984, *Distributed Ray
Tracing*; Haeberli and Akeley 1990, *The Accumulation Buffer*): each sample of a frame is
drawn at its own time in the shutter, and the film's average converges to the image the
shutter integrates, as Cycles' camera rays with their times.

Numpy only. Transforms are read once a frame at the shutter's steps (``Motion``: Blender's
start, centre and end of the shutter, ``render_engine.read_motion``) and interpolated per
sample: translation and scale linearly, rotation along the great arc (quaternion slerp),
piecewise between the steps. A sample's time follows Blender's shutter curve: the frame's N
samples take the N strata of the curve's distribution (its inverse CDF), in a fixed shuffled
order, so any prefix of them spreads over the shutter and all N cover it exactly once.
"""

import functools
import math
from dataclasses import dataclass, field, replace

import numpy as np

# Points of the shutter curve read into its distribution.
CURVE_POINTS = 64


@dataclass
class Motion:
    """What moves during a frame's shutter: ``times`` (the steps, fractions of the shutter in
    [0, 1], increasing), per instance or light ``motion_key`` its world matrices at the steps
    (only those that move), the camera's world -> view matrices at the steps and at the
    frame's own time (``camera_ref``: the time its snapshot and camera were read), and the
    shutter curve's weights at CURVE_POINTS evenly spaced fractions (None: a box)."""

    times: tuple
    instances: dict = field(default_factory=dict)
    lights: dict = field(default_factory=dict)
    camera: list = None
    camera_ref: np.ndarray = None
    curve: tuple = None
    # Deforming meshes (armatures, shape keys, modifiers): per instance ``motion_key`` its
    # ``Shape`` at each step, all of one topology.
    shapes: dict = field(default_factory=dict)

    @property
    def moves(self):
        return bool(self.instances or self.lights or self.camera is not None or self.shapes)


@dataclass(frozen=True)
class Shape:
    """A mesh's surface at one step of the shutter: its vertices' positions and normals (nv, 3)
    and its corners' normals (nc, 3; None where the mesh's normals live on its points), with
    ``corner_vert`` (nc,), the vertex of each corner (its topology)."""

    positions: np.ndarray
    vertex_normals: np.ndarray
    corner_normals: np.ndarray
    corner_vert: np.ndarray


def same_topology(shapes):
    """Whether ``shapes`` (``Shape``, one per step) share one topology."""
    first = shapes[0]
    return all(
        len(s.positions) == len(first.positions) and np.array_equal(s.corner_vert, first.corner_vert)
        for s in shapes[1:]
    )


_SERIAL = [1 << 40]  # serials of deformed geometry (``Geometry.serial``), above any extraction's


def deformed(geometry, shapes, times, u):
    """``geometry`` (the frame's ``Geometry`` of a deforming mesh) with its vertices where they
    are at shutter fraction ``u``, each interpolated linearly between the ``shapes`` at the
    steps around it; None where its vertices are neither the shapes' vertices nor their
    corners (a layout the steps cannot give)."""
    first = shapes[0]
    nv, nc = len(first.positions), len(first.corner_vert)
    count = len(geometry.positions)
    if count not in (nv, nc):
        return None
    t = np.asarray(times, np.float64)
    k = int(np.clip(np.searchsorted(t, u, side="right") - 1, 0, len(t) - 2)) if len(t) > 1 else 0
    f = float(np.clip((u - t[k]) / (t[k + 1] - t[k]), 0.0, 1.0)) if len(t) > 1 and t[k + 1] > t[k] else 0.0
    a, b = shapes[k], shapes[min(k + 1, len(shapes) - 1)]
    by_vertex = count == nv
    if nv == nc:  # either layout has this many vertices: the one nearer the frame's own
        middle = shapes[len(shapes) // 2]
        near_vertex = np.abs(middle.positions - geometry.positions).max()
        near_corner = np.abs(middle.positions[middle.corner_vert] - geometry.positions).max()
        by_vertex = near_vertex <= near_corner

    def layout(shape):
        if by_vertex:
            return shape.positions, shape.vertex_normals
        normals = shape.corner_normals if shape.corner_normals is not None else shape.vertex_normals[shape.corner_vert]
        return shape.positions[shape.corner_vert], normals

    (pa, na), (pb, nb) = layout(a), layout(b)
    positions = (pa + f * (pb - pa)).astype(np.float32)
    normals = na + f * (nb - na)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(length > 1e-20, normals / np.maximum(length, 1e-20), na).astype(np.float32)
    drawn = positions[np.unique(geometry.indices)] if len(geometry.indices) else positions
    bounds = np.array([drawn.min(axis=0), drawn.max(axis=0)], np.float64) if len(drawn) else geometry.bounds
    _SERIAL[0] += 1
    # Its own batches, this frame only: no content key (the store holds the undeformed mesh's).
    return replace(geometry, positions=positions, normals=normals, bounds=bounds, serial=_SERIAL[0], content=None)


def moving_only(matrices):
    """{key: matrices} keeping the keys whose matrices differ between steps."""
    out = {}
    for key, steps in matrices.items():
        first = steps[0]
        if any(not np.array_equal(first, m) for m in steps[1:]):
            out[key] = [np.asarray(m, np.float64) for m in steps]
    return out


def _quaternion(r):
    """The unit quaternion (w, x, y, z) of rotation matrix ``r`` (Shepperd's method)."""
    t = np.trace(r)
    if t > 0.0:
        s = math.sqrt(t + 1.0) * 2.0
        q = (0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s)
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = math.sqrt(max(1.0 + r[0, 0] - r[1, 1] - r[2, 2], 0.0)) * 2.0
        q = ((r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s)
    elif r[1, 1] > r[2, 2]:
        s = math.sqrt(max(1.0 + r[1, 1] - r[0, 0] - r[2, 2], 0.0)) * 2.0
        q = ((r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s)
    else:
        s = math.sqrt(max(1.0 + r[2, 2] - r[0, 0] - r[1, 1], 0.0)) * 2.0
        q = ((r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s)
    q = np.array(q, np.float64)
    n = np.linalg.norm(q)
    return q / n if n > 0.0 and np.isfinite(n) else np.array([1.0, 0.0, 0.0, 0.0])


def _rotation(q):
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _decompose(m):
    """(translation, rotation quaternion, scale) of an affine matrix (a negative determinant
    goes to the x scale)."""
    m = np.asarray(m, np.float64)
    basis = m[:3, :3]
    scale = np.linalg.norm(basis, axis=0)
    if np.linalg.det(basis) < 0.0:
        scale[0] = -scale[0]
    safe = np.where(np.abs(scale) > 1e-30, scale, 1.0)
    return m[:3, 3].copy(), _quaternion(basis / safe), scale


def _slerp(a, b, t):
    d = float(np.dot(a, b))
    if d < 0.0:  # the short way round
        b, d = -b, -d
    if d > 0.9995:
        q = a + t * (b - a)
        return q / np.linalg.norm(q)
    theta = math.acos(min(d, 1.0))
    return (math.sin((1.0 - t) * theta) * a + math.sin(t * theta) * b) / math.sin(theta)


def interpolate(times, matrices, u):
    """The matrix at shutter fraction ``u`` from ``matrices`` at ``times``: translation and
    scale linear, rotation slerped, between the two steps around ``u`` (clamped to the ends)."""
    u = min(max(float(u), times[0]), times[-1])
    k = max(0, min(len(times) - 2, int(np.searchsorted(times, u, side="right")) - 1))
    t0, t1 = times[k], times[k + 1]
    f = 0.0 if t1 <= t0 else (u - t0) / (t1 - t0)
    if f <= 0.0:
        return np.asarray(matrices[k], np.float64)
    if f >= 1.0:
        return np.asarray(matrices[k + 1], np.float64)
    p0, q0, s0 = _decompose(matrices[k])
    p1, q1, s1 = _decompose(matrices[k + 1])
    out = np.eye(4)
    out[:3, :3] = _rotation(_slerp(q0, q1, f)) * ((1.0 - f) * s0 + f * s1)
    out[:3, 3] = (1.0 - f) * p0 + f * p1
    return out


@functools.lru_cache(maxsize=64)
def _order(count):
    """A fixed shuffle of the ``count`` strata, the middle one first (sample 0: the centre
    of the shutter, whose Depth and Normal are the passes')."""
    rng = np.random.default_rng(0x5EED + count)
    rest = [k for k in rng.permutation(count) if k != count // 2]
    return (count // 2, *rest)


def _inverse_cdf(curve, x):
    """The shutter fraction at which the curve's distribution reaches ``x`` in [0, 1]."""
    w = np.maximum(np.nan_to_num(np.asarray(curve, np.float64)), 0.0)
    if w.sum() <= 0.0:
        return x
    grid = np.linspace(0.0, 1.0, len(w))
    cells = 0.5 * (w[1:] + w[:-1]) * np.diff(grid)  # trapezoids
    cdf = np.concatenate([[0.0], np.cumsum(cells)]) / cells.sum()
    return float(np.interp(x, cdf, grid))


def sample_time(s, count, curve=None):
    """Sample ``s``'s fraction of the shutter in [0, 1] for a frame of ``count`` samples:
    stratum ``_order(count)[s]`` of the shutter curve's distribution at its middle."""
    count = max(1, int(count))
    k = _order(count)[s % count]
    return _inverse_cdf(curve, (k + 0.5) / count) if curve is not None else (k + 0.5) / count


def moved(items, steps_by_key, times, u):
    """``items`` (``MeshInstance`` or ``Light``, each with a ``motion_key``) with the matrices
    of those in ``steps_by_key`` (their matrices at ``times``) at shutter fraction ``u``."""
    if not steps_by_key:
        return items
    out = []
    for item in items:
        steps = steps_by_key.get(item.motion_key)
        out.append(item if steps is None else replace(item, matrix=interpolate(times, steps, u)))
    return out


def instances_at(instances, motion, u):
    """``instances`` (``MeshInstance``) with the moving ones' matrices at shutter fraction ``u``."""
    return moved(instances, motion.instances, motion.times, u)


def lights_at(lights, motion, u):
    """``lights`` with the moving ones' matrices at shutter fraction ``u``."""
    return moved(lights, motion.lights, motion.times, u)


def camera_at(camera, motion, u):
    """``camera`` moved as the scene camera moves between its frame's time and ``u``: its view
    composed with the camera's change (so a multiview eye keeps its offset)."""
    if motion.camera is None:
        return camera
    worlds = [np.linalg.inv(v) for v in motion.camera]
    view_u = np.linalg.inv(interpolate(motion.times, worlds, u))
    return replace(camera, view=np.asarray(camera.view, np.float64) @ np.linalg.inv(motion.camera_ref) @ view_u)
