"""Light binning (engine/shadows/light_bins.py): a light's screen rectangle contains every visible
point it can light (checked by sampling), and lights that reach nothing visible get none."""

import math

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.scene.extract import Light  # noqa: E402
from penumbra.engine.shadows import light_bins, lightspace  # noqa: E402

W, H = 320, 180


def _camera_vp(eye=(0.0, -12.0, 9.0), target=(0.0, 0.0, 0.0)):
    view = lightspace.look_at(eye, np.subtract(target, eye))
    return lightspace.perspective(math.radians(50), W / H, 0.1, 100.0) @ view


def _light(kind, position, direction, spot_size=math.radians(45)):
    m = np.eye(4)
    m[:3, 3] = position
    z = -lightspace.normalize(direction)  # lights look along their local -Z
    x = lightspace.normalize(np.cross((0.3, 0.2, 1.0), z))
    m[:3, 0], m[:3, 1], m[:3, 2] = x, np.cross(z, x), z
    return Light(type=kind, color=np.ones(3), matrix=m, radius=0.1, spot_size=spot_size)


def _lit_by(light, points):
    """Points the light can deliver light to (spot cone, area half-space, everything else)."""
    d = points - light.position
    if light.type == "AREA":
        return d @ light.direction > 0
    if light.type == "SPOT":
        cos = (d @ light.direction) / np.linalg.norm(d, axis=1)
        return cos > math.cos(light.spot_size / 2)
    return np.ones(len(points), bool)


def _pixels(vp, points):
    clip = np.c_[points, np.ones(len(points))] @ vp.T
    ok = clip[:, 3] > 0
    ndc = clip[:, :3] / clip[:, 3:]
    inside = ok & np.all(np.abs(ndc) <= 1, axis=1)
    return (ndc[:, 0] * 0.5 + 0.5) * W, (ndc[:, 1] * 0.5 + 0.5) * H, inside


@pytest.mark.parametrize("seed", range(6))
def test_every_visible_lit_point_falls_inside_its_lights_rectangle(seed):
    rng = np.random.default_rng(seed)
    lo, hi = np.array([-8.0, -8.0, 0.0]), np.array([8.0, 8.0, 3.0])
    lights = [
        _light("SPOT", rng.uniform(-6, 6, 3) + (0, 0, 5), rng.normal(size=3) + (0, 0, -2), rng.uniform(0.2, 3.1))
        for _ in range(6)
    ] + [_light("AREA", rng.uniform(-6, 6, 3) + (0, 0, 2), rng.normal(size=3)), _light("SUN", (0, 0, 9), (0, 0, -1))]
    vp = _camera_vp(eye=rng.uniform(-4, 4, 3) + (0, -12, 8))
    rects = light_bins.screen_rects(lights, vp, lo, hi, W, H)
    points = rng.uniform(lo, hi, size=(40000, 3))
    px, py, visible = _pixels(vp, points)
    for light, rect in zip(lights, rects):
        reached = visible & _lit_by(light, points)
        if rect is None:
            assert not reached.any(), f"{light.type}: reaches {reached.sum()} visible points but has no rectangle"
            continue
        x0, y0, x1, y1 = rect
        inside = (px >= x0) & (px <= x1) & (py >= y0) & (py <= y1)
        assert inside[reached].all(), f"{light.type}: {np.sum(~inside[reached])} lit points outside {rect}"
    assert rects[-1] is not None  # a sun reaches all of the scene box the camera sees


def test_a_narrow_spot_gets_a_small_rectangle_and_lights_facing_away_none():
    lo, hi = np.array([-10.0, -10.0, 0.0]), np.array([10.0, 10.0, 0.0])  # a flat ground
    vp = _camera_vp(eye=(0.0, 0.0, 20.0), target=(0.0, 0.01, 0.0))
    down = _light("SPOT", (3.0, 0.0, 4.0), (0, 0, -1), spot_size=math.radians(20))
    up = _light("SPOT", (0.0, 0.0, 4.0), (0, 0, 1))
    behind = _light("AREA", (0.0, 0.0, 4.0), (0, 0, 1))
    rect, up_rect, behind_rect = light_bins.screen_rects([down, up, behind], vp, lo, hi, W, H)
    assert up_rect is None and behind_rect is None
    # The 20 degree cone from 4 m lights a disc of radius 4 tan(10 deg) = 0.71 m around x = 3.
    x0, y0, x1, y1 = rect
    assert (x1 - x0) * (y1 - y0) < 0.05 * W * H
    centre = _pixels(vp, np.array([[3.0, 0.0, 0.0]]))
    assert x0 <= centre[0][0] <= x1 and y0 <= centre[1][0] <= y1


def test_bin_masks_set_exactly_the_bits_of_each_lights_bins():
    rects = [(0, 0, W, H), None, (20, 40, 21, 41)] + [None] * 14 + [(300, 170, 320, 180)]
    masks = light_bins.bin_masks(rects, W, H, words=4)
    assert masks.shape == (math.ceil(H / light_bins.BIN_SIZE), math.ceil(W / light_bins.BIN_SIZE), 4)
    bits = masks.astype(np.int64)
    assert np.all(bits[..., 0] & 1)  # light 0: everywhere
    assert not np.any(bits[..., 0] & 2)  # light 1: nowhere
    assert bits[40 // 16, 20 // 16, 0] & 4 and ((bits[..., 0] & 4) > 0).sum() == 1  # one bin only
    # Light 17 (word 1, bit 1): pixels 300..319 x 170..179 touch bins 18-19 x 10-11.
    assert (bits[..., 1] == 2).sum() == 4 and np.all(bits[10:12, 18:20, 1] == 2)
    assert light_bins.word_masks(0, 18, 4) == (0xFFFF, 0b11, 0, 0)


def test_degenerate_inputs_never_drop_a_light_that_may_reach():
    lo, hi = np.array([-1e7, -1e7, 0.0]), np.array([1e7, 1e7, 1.0])  # a huge, thin scene
    vp = _camera_vp(eye=(0.0, -5.0, 3.0))
    spot = _light("SPOT", (0.0, 0.0, 2.0), (0, 0, -1), spot_size=math.pi)  # a 180 degree spot
    nan_spot = _light("SPOT", (0.0, 0.0, 2.0), (0, 0, -1))
    nan_spot.matrix[:3, 2] = np.nan
    rects = light_bins.screen_rects([spot, nan_spot], vp, lo, hi, W, H)
    assert rects[0] is not None and (rects[0][2] - rects[0][0]) * (rects[0][3] - rects[0][1]) > 0.3 * W * H
    assert rects[1] is not None  # unknown reach: kept, conservatively


@pytest.mark.parametrize("seed", range(4))
def test_a_frames_rectangles_hold_every_samples(seed):
    """Rectangles computed once a frame (``draw_list.frame_light_rects``: influence padded by
    ``light_reach``, rectangles by the filter's pixel reach) contain each sample's own, with
    the light at a point of itself and the camera offset by up to that reach."""
    from types import SimpleNamespace

    from penumbra.engine.frame import sampling
    from penumbra.engine.frame.draw_list import frame_light_rects, lights_in_view

    rng = np.random.default_rng(100 + seed)
    lo, hi = np.array([-8.0, -8.0, 0.0]), np.array([8.0, 8.0, 3.0])
    lights = [
        _light("SPOT", rng.uniform(-6, 6, 3) + (0, 0, 5), rng.normal(size=3) + (0, 0, -2), rng.uniform(0.2, 1.5))
        for _ in range(4)
    ] + [_light("AREA", rng.uniform(-6, 6, 3) + (0, 0, 2), rng.normal(size=3))]
    lights = [
        lt.__class__(**{**lt.__dict__, "radius": 0.8, "size": 2.0, "size_x": 2.0, "size_y": 1.0}) for lt in lights
    ]
    eye = rng.uniform(-4, 4, 3) + (0, -12, 8)
    view = lightspace.look_at(eye, -eye)
    proj = lightspace.perspective(math.radians(50), W / H, 0.1, 100.0)
    camera = SimpleNamespace(projection=proj, view=view)
    draws = [SimpleNamespace(corners=lightspace.box_corners(lo, hi))]
    reach, count = 1.5, 16
    frame = frame_light_rects(lights, draws, camera, W, H, reach)
    stats = SimpleNamespace(lights_out_of_view=0)
    for s in range(1, count):
        dx, dy, _ = sampling.pixel_offset(s, reach)
        jittered = SimpleNamespace(projection=sampling.jittered_projection(proj, dx, dy, W, H), view=view)
        moved = [sampling.light_at_sample(lt, i, s, count) for i, lt in enumerate(lights)]
        own = light_bins.screen_rects(moved, jittered.projection @ view, lo, hi, W, H)
        kept, held = lights_in_view(moved, draws, jittered, W, H, stats, frame)
        position = {id(lt): k for k, lt in enumerate(kept)}
        for light, r in zip(moved, own):
            if r is None:
                continue
            assert id(light) in position, f"{light.type}: reaches {r} in sample {s} but the frame drops it"
            x0, y0, x1, y1 = held[position[id(light)]]
            assert x0 <= r[0] and y0 <= r[1] and x1 >= r[2] and y1 >= r[3], f"sample {s}: {r} not in {held}"
