"""Depth of field by lens sampling (engine/frame/lens.py) against the thin lens's geometry."""

import math

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.frame import lens as lens_mod  # noqa: E402
from penumbra.engine.scene.extract import Camera, Lens  # noqa: E402

W, H = 128, 96


def _perspective(lens_mm=50.0, sensor=36.0, near=0.1, far=100.0):
    p = np.zeros((4, 4))
    p[0, 0] = 2.0 * lens_mm / sensor
    p[1, 1] = p[0, 0] * W / H
    p[2, 2], p[2, 3] = -(far + near) / (far - near), -2.0 * far * near / (far - near)
    p[3, 2] = -1.0
    return p


def _ortho(scale=4.0, near=0.1, far=100.0):
    p = np.eye(4)
    p[0, 0] = 2.0 / scale
    p[1, 1] = p[0, 0] * W / H
    p[2, 2], p[2, 3] = -2.0 / (far - near), -(far + near) / (far - near)
    return p


def _pixel(camera, point):
    clip = camera.projection @ camera.view @ np.append(point, 1.0)
    ndc = clip[:3] / clip[3]
    return np.array([(ndc[0] + 1.0) * 0.5 * W, (ndc[1] + 1.0) * 0.5 * H])


@pytest.mark.parametrize("ortho", [False, True])
def test_a_lens_point_keeps_the_focus_plane_and_moves_the_rest_by_the_thin_lens(ortho):
    """From any point o of the aperture, a point at the focus distance projects where the
    lens's centre puts it; one at depth z moves by o (1/f - 1/z) k pixels (o (z/f - 1) k for an
    orthographic camera), so the frame's points spread over the circle of confusion."""
    lens = Lens(radius=0.125, focus=2.0)
    view = np.eye(4)
    view[:3, 3] = (0.3, -0.2, 0.0)  # the camera somewhere off the origin
    camera = Camera(view=view, projection=_ortho() if ortho else _perspective(), is_ortho=ortho, lens=lens)
    kx, ky = lens_mod.coc_scale(camera, W, H)
    for s in range(1, 40):
        ox, oy = lens_mod.lens_offset(s, lens)
        moved = lens_mod.lens_camera(camera, (ox, oy))
        for depth in (0.5, 2.0, 4.0, 30.0):
            p = np.linalg.inv(view) @ np.array([0.4, 0.25, -depth, 1.0])
            shift = _pixel(moved, p[:3]) - _pixel(camera, p[:3])
            spread = (depth / 2.0 - 1.0) if ortho else (1.0 / 2.0 - 1.0 / depth)
            # Moving the eye by +o moves the image of a point beyond focus the same way.
            expected = np.array([ox * kx, oy * ky]) * spread
            np.testing.assert_allclose(shift, expected, atol=1e-6 * max(1.0, np.abs(expected).max()))
        assert np.allclose(moved.position, camera.position + np.linalg.inv(view)[:3, :3] @ [ox, oy, 0.0])
    d = lens_mod.coc_pixels(camera, 4.0, W, H)
    spread = (4.0 / 2.0 - 1.0) if ortho else (1.0 / 2.0 - 1.0 / 4.0)
    assert d == pytest.approx(2.0 * 0.125 * spread * max(kx, ky))
    assert lens_mod.coc_pixels(camera, 2.0, W, H) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("blades", [0, 3, 6])
def test_aperture_points_cover_the_disc_or_polygon_uniformly(blades):
    """Cycles' aperture: a uniform disc, or a uniform regular polygon with corners on the
    radius, turned by the rotation; x divided by the ratio. The frame's points fill it evenly:
    none outside, the mean at the centre, the second moment of the shape."""
    rotation, ratio, radius = 0.3, 2.0, 0.5
    lens = Lens(radius=radius, focus=1.0, blades=blades, rotation=rotation, ratio=ratio)
    pts = np.array([lens_mod.lens_offset(s, lens) for s in range(1, 4097)])
    local = pts.copy()
    local[:, 0] *= ratio
    local /= radius
    r = np.hypot(local[:, 0], local[:, 1])
    if blades == 0:
        assert r.max() <= 1.0 + 1e-12 and r.max() > 0.99
        assert np.mean(r**2) == pytest.approx(0.5, abs=0.01)  # a uniform disc's E[r^2] = 1/2
    else:
        half = math.pi / blades
        # Inside: each point within the edge of the sector it falls in (apothem cos(pi / n)).
        angle = np.arctan2(local[:, 1], local[:, 0]) - rotation
        sector = np.mod(angle + half, 2 * half) - half  # from the axis of its corner's triangle
        assert np.all(r * np.cos(sector) <= math.cos(half) + 1e-9)
        area = blades * math.sin(half) * math.cos(half)
        inertia = blades / 6.0 * math.sin(half) * math.cos(half) * (3.0 * math.cos(half) ** 2 + math.sin(half) ** 2)
        assert np.mean(r**2) == pytest.approx(inertia / area, abs=0.01)
    assert np.abs(local.mean(axis=0)).max() < 0.01
    assert lens_mod.lens_offset(0, lens) == (0.0, 0.0)  # the centred sample: the pinhole


def test_lens_reach_bounds_every_depth_and_stays_finite_at_the_extremes():
    """The pixels the lens samples look beyond the image: the widest circle of confusion's
    radius over the drawn depths, capped where a near surface's blur would make it useless;
    finite for f-stops from 0.1 to 1000, focus at the near plane or at infinity."""
    base = Camera(view=np.eye(4), projection=_perspective(), lens=Lens(radius=0.025, focus=3.0))
    reach = lens_mod.lens_reach(base, (1.0, 20.0), W, H)
    for depth in np.geomspace(1.0, 20.0, 50):
        assert 0.5 * lens_mod.coc_pixels(base, depth, W, H) <= reach + 1e-9
    for radius in (50e-3 / (2 * 0.1), 50e-3 / (2 * 1000.0)):
        for focus in (0.1, 1e30):
            camera = Camera(view=np.eye(4), projection=_perspective(), lens=Lens(radius=radius, focus=focus))
            r = lens_mod.lens_reach(camera, (0.1, 100.0), W, H)
            assert math.isfinite(r) and 0.0 <= r <= max(W, H)
            moved = lens_mod.lens_camera(camera, lens_mod.lens_offset(3, camera.lens))
            assert np.all(np.isfinite(moved.projection)) and np.all(np.isfinite(moved.view))
    assert lens_mod.lens_reach(base, (float("nan"), 1.0), W, H) == max(W, H)
    assert lens_mod.lens_reach(Camera(view=np.eye(4), projection=_perspective()), (1.0, 2.0), W, H) == 0.0
