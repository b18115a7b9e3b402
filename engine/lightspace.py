"""Light-space maths: look-at, projections, fitting, texel snapping.

Plain numpy, no bpy and no gpu, so every function here is unit-tested against hand-derived
values. Matrices are 4x4 float64, column-vector convention (``clip = P @ V @ world``), the same
as Blender's ``mathutils`` and OpenGL.
"""

import numpy as np

# Maps clip-space xyz in [-1, 1] to texture space [0, 1] (seed 004's "bias matrix").
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
    n = np.linalg.norm(v)
    if not np.isfinite(n) or n < 1e-30:
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
    right = normalize(np.cross(f, up))
    true_up = np.cross(right, f)
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
    cof[:, 0] = np.cross(a[:, 1], a[:, 2])
    cof[:, 1] = np.cross(a[:, 2], a[:, 0])
    cof[:, 2] = np.cross(a[:, 0], a[:, 1])
    det = float(np.linalg.det(a))
    sign = -1.0 if det < 0.0 else 1.0
    return cof * sign


def fit_sun_ortho(direction, points, map_size, padding_texels=2.0):
    """Fit an orthographic light frustum for a sun shining along ``direction`` around ``points``.

    Returns ``(view, projection, texel_world_size)``. The frustum's x/y extent is snapped to
    whole texels in light space, and its size to a power-of-two-friendly quantum, so moving
    the camera or the fitted set slightly does not make shadow edges shimmer. Depth range
    covers every point with a margin so casters behind the receivers are kept.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) == 0:
        return None
    map_size = max(1, int(map_size))
    view = look_at((0.0, 0.0, 0.0), direction)
    ls = transform_points(view, pts)
    lo = ls.min(axis=0)
    hi = ls.max(axis=0)
    extent = float(max(hi[0] - lo[0], hi[1] - lo[1]))
    scale = float(max(np.abs(ls).max(), 1e-30))
    extent = max(extent, scale * 1e-6, 1e-30)
    # Quantise the extent up to steps of 2^(1/4) (at most 19% wasted per axis) so small
    # changes in the fitted set keep the same texel size; then pad by whole texels.
    extent = 2.0 ** (np.ceil(np.log2(extent) * 4.0) / 4.0)
    texel = extent / max(map_size - 2.0 * padding_texels, 1.0)
    half = 0.5 * texel * map_size
    cx = 0.5 * (lo[0] + hi[0])
    cy = 0.5 * (lo[1] + hi[1])
    cx = np.floor(cx / texel) * texel
    cy = np.floor(cy / texel) * texel
    depth = float(hi[2] - lo[2])
    margin = max(depth * 0.01, texel * 4.0, scale * 1e-6)
    near = -hi[2] - margin
    far = -lo[2] + margin
    proj = orthographic(cx - half, cx + half, cy - half, cy + half, near, far)
    return view, proj, texel
