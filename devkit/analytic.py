"""Analytic references: camera rays, plane hits and box shadows computed in numpy."""

import numpy as np


def camera_matrices(scene, depsgraph=None):
    """(view, projection) of the scene camera as numpy arrays, as Penumbra computes them."""
    import bpy

    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    cam = scene.camera.evaluated_get(depsgraph)
    r = scene.render
    w = int(r.resolution_x * r.resolution_percentage / 100)
    h = int(r.resolution_y * r.resolution_percentage / 100)
    proj = np.array(cam.calc_matrix_camera(depsgraph, x=w, y=h, scale_x=r.pixel_aspect_x, scale_y=r.pixel_aspect_y))
    # The depth rows exactly, from the clip distances (float32 loses the far plane at a
    # near/far ratio beyond ~1e7); the view ignores the camera's scale, as Blender's does.
    n, f = float(cam.data.clip_start), float(cam.data.clip_end)
    if cam.data.type == "ORTHO":
        proj[2, 2], proj[2, 3] = -2.0 / (f - n), -(f + n) / (f - n)
    else:
        proj[2, 2], proj[2, 3] = -(f + n) / (f - n), -2.0 * f * n / (f - n)
    view = np.array(cam.matrix_world.normalized().inverted())
    return view, proj, w, h


def plane_hits(view, proj, w, h, z=0.0, axis=2):
    """World point where each pixel centre's ray meets the plane {p[axis] = z}, and its view
    depth. Arrays are (h, w[, 3]) with row 0 at the bottom of the image."""
    # A pixel's ray does not depend on the clip distances: unproject through a well-conditioned
    # depth row (near 1, far 2), not one whose near/far ratio is 1e8.
    proj = np.array(proj, dtype=np.float64)
    proj[2, 2], proj[2, 3] = (-3.0, -4.0) if proj[3, 3] == 0.0 else (-2.0, -3.0)
    inv = np.linalg.inv(proj @ view)
    xs = (np.arange(w) + 0.5) / w * 2 - 1
    ys = (np.arange(h) + 0.5) / h * 2 - 1
    X, Y = np.meshgrid(xs, ys)

    def unproject(zn):
        p = np.stack([X, Y, np.full_like(X, zn), np.ones_like(X)], axis=-1) @ inv.T
        return p[..., :3] / p[..., 3:4]

    o = unproject(-1.0)
    d = unproject(1.0) - o
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (z - o[..., axis]) / d[..., axis]
    p = o + t[..., None] * d
    depth = -(p @ view[:3, :3].T + view[:3, 3])[..., 2]
    return p, depth


def ray_hits_box(origins, direction, lo, hi):
    """Whether rays ``origins + s * direction`` (s > 0) hit the box [lo, hi] (slab test)."""
    o = np.asarray(origins, float)
    d = np.asarray(direction, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t1 = (np.asarray(lo) - o) * inv
        t2 = (np.asarray(hi) - o) * inv
    tmin = np.nanmax(np.minimum(t1, t2), axis=-1)
    tmax = np.nanmin(np.maximum(t1, t2), axis=-1)
    return (tmax >= np.maximum(tmin, 0.0)) & (tmax > 0)


def iou(a, b):
    a = np.asarray(a, bool)
    b = np.asarray(b, bool)
    union = (a | b).sum()
    return float((a & b).sum() / union) if union else 1.0
