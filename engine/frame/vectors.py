"""Blender's Vector pass, as Cycles writes it: per pixel, in pixels, the offset from the surface
seen there to where it was at the previous frame (xy), and from where it will be at the next
frame to here (zw): both the negated screen motion, Cycles' signs (which Blender's Vector Blur
node reads).
The surface's point comes from the centred sample's Position pass and the draw that covers the
pixel (``features/passes.py`` DRAW); it moves with its object's transform and the camera moves
with its own, each read at the neighbouring frames (``render_engine.read_vectors``). No bpy, no gpu."""

from dataclasses import dataclass

import numpy as np


@dataclass
class Neighbours:
    """The scene at the previous and next frames: {``motion_key``: world matrix} of each
    instance, and the camera's view-projection (4x4) at each."""

    before: dict
    after: dict
    camera_before: np.ndarray
    camera_after: np.ndarray


def raster(view_proj, points, width, height):
    """Pixel coordinates (x right, y up from the bottom row) of world ``points`` (n, 3)."""
    p = np.c_[points, np.ones(len(points))] @ np.asarray(view_proj, np.float64).T
    w = np.where(np.abs(p[:, 3]) > 1e-30, p[:, 3], 1e-30)
    return np.stack(((p[:, 0] / w * 0.5 + 0.5) * width, (p[:, 1] / w * 0.5 + 0.5) * height), axis=-1)


def vector_pass(position, draw_numbers, draws, camera_now, neighbours, width, height):
    """The Vector pass (height, width, 4) from ``position`` (height, width, 3: world points),
    ``draw_numbers`` (each pixel's draw number + 1; 0: no surface), ``draws`` ([(motion key,
    world matrix)] by number), the camera's view-projection ``camera_now`` and the
    ``Neighbours``. An instance not found at a neighbouring frame stands still there."""
    out = np.zeros((height, width, 4), np.float32)
    numbers = np.rint(np.asarray(draw_numbers)).astype(np.int64)
    for number in np.unique(numbers):
        if number <= 0 or number > len(draws):
            continue
        mask = numbers == number
        key, matrix = draws[number - 1]
        matrix = np.asarray(matrix, np.float64)
        try:
            to_object = np.linalg.inv(matrix)
        except np.linalg.LinAlgError:
            continue
        points = np.asarray(position, np.float64)[mask]
        local = np.c_[points, np.ones(len(points))] @ to_object.T
        before = local @ np.asarray(neighbours.before.get(key, matrix), np.float64).T
        after = local @ np.asarray(neighbours.after.get(key, matrix), np.float64).T
        now = raster(camera_now, points, width, height)
        then = raster(neighbours.camera_before, before[:, :3], width, height)
        next_ = raster(neighbours.camera_after, after[:, :3], width, height)
        vectors = np.c_[then - now, now - next_]
        out[mask] = np.where(np.isfinite(vectors), vectors, 0.0)
    return out
