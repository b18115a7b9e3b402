"""The world's ambient occlusion (``engine/frame/world/occlusion.py``, ``shaders/lib/gtao.glsl``):
screen-space ground-truth ambient occlusion of the world's light in one-sample frames and a
frame's first sample, against the analytic visibility of a floor at the foot of a wall."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.analytic import camera_matrices, plane_hits
from devkit.render import render

ALBEDO = scenes.WHITE_ALBEDO
WORLD = (0.5, 0.5, 0.5)
W, H = 128, 72


def wall_scene(scale=1.0, distance=10.0, ortho=True, strength=1.0, size=(W, H)):
    """A 40 x 40 floor (z = 0) with a wall 40 wide, 1 thick and 40 high standing on it along
    y = 0 (its face towards -y), both white, under a uniform world; a camera looking down at
    45 degrees at the wall, the corner a fifth of the frame above its bottom edge, so it sees
    the floor up to 0.46 m in front of the wall and the wall up to 2.7 m (orthographic, 4 m
    wide; or perspective, 24 mm, from 6 m). Everything (and the ambient occlusion's distance)
    scaled by ``scale``."""
    scene = scenes.empty_scene(*size)
    scenes.set_world(scene, tuple(c * strength for c in WORLD))
    mat = scenes.white()
    scenes.plane(scene, "Floor", size=40.0 * scale, mat=mat)
    scenes.box(scene, "Wall", center=(0, 0.5 * scale, 20.0 * scale), size=(40 * scale, 1 * scale, 40 * scale), mat=mat)
    centre = np.array((0.0, 0.0, 1.13))
    back = 6.0 if not ortho else 10.0
    location = (centre + back * np.array((0.0, -math.sqrt(0.5), math.sqrt(0.5)))) * scale
    cam = scenes.camera(
        scene, tuple(location), (math.radians(45.0), 0.0, 0.0), lens=24.0, ortho_scale=4.0 * scale if ortho else None
    )
    cam.data.clip_start, cam.data.clip_end = 0.1 * scale, 100.0 * scale
    scene.penumbra.world_ao_distance = distance * scale
    return scene


def floor_points(scene):
    """World point of each pixel centre's ray on the floor plane (h, w, 3)."""
    view, proj, w, h = camera_matrices(scene)
    p, _depth = plane_hits(view, proj, w, h, z=0.0)
    return p


def visible_wall_visibility(x, height):
    """Cosine-weighted visibility of a point on the floor ``x`` in front of a wall of height
    ``height`` (infinitely wide): the wall blocks elevations up to atan(height cos(psi) / x)
    in azimuth psi, and the cosine-weighted solid angle below elevation e is sin^2(e) / 2, so
    V = 1 - 1/(2 pi) int sin^2 dpsi = 1/2 + 1/2 / sqrt(1 + (height / x)^2); 1/2 as the wall
    grows without end."""
    return 0.5 + 0.5 / np.sqrt(1.0 + (height / x) ** 2)


def frame(gpu_call, scene, width=W, height=H, samples=1, aux=True):
    """(FrameStats, colour (h, w, 3)) of one frame of ``scene`` through the engine core."""
    from penumbra.engine.scene.extract import camera_from_scene

    def job(engine, depsgraph):
        cam = camera_from_scene(depsgraph, scene, width, height)
        out = engine.render_frame(depsgraph, cam, width, height, aux=aux, samples=(0, samples), sample_count=samples)
        return out.stats, out.color_array()[..., :3].copy()

    return gpu_call(job)


# Measured on both lines (3 slices, 6 steps): the band 3-12 cm from the wall 0.537 (0.523 at
# 4 cm, 0.543 at 9 cm) against 0.5 for an infinite wall and 0.511 for the 2.7 m of wall the
# frame shows; the floor beyond the distance exactly 1.
NEAR_TOLERANCE = 0.06


@pytest.mark.parametrize("size", [(W, H), (W - 1, H - 1)])
def test_floor_at_the_foot_of_a_wall_sees_half_the_world(penumbra, size):
    """A point on a floor at the foot of an infinite wall sees half the cosine-weighted
    hemisphere: radiance albedo * world * 0.5. Floor points 3-12 cm from the wall, which the
    frame shows up to 2.7 m (a wall that high leaves them 0.5 + at most 0.022,
    ``visible_wall_visibility``). Screen-space error on top: 3 slices of 6 steps find the
    highest point of the wall only up to their last step inside the frame, which leaves the
    band's mean within NEAR_TOLERANCE of 1/2 (measured 0.537) and per pixel the noise of three
    slice directions. Floor points beyond the distance (0.2 m) see the whole world, exactly.
    At an odd size too: the half-resolution horizons' last column and row stand for one pixel."""
    scene = wall_scene(size=size)
    color = render(scene)["Combined"][..., :3].mean(axis=-1)
    y = floor_points(scene)[..., 1]
    near = (y > -0.12) & (y < -0.03)
    assert near.sum() > 200
    full = ALBEDO * WORLD[0]
    v = color[near] / full
    expected = visible_wall_visibility(-y[near], 2.7)
    assert np.all(np.isfinite(v)) and np.all(v >= 0.0) and np.all(v <= 1.0 + 1e-6)
    assert abs(v.mean() - 0.5) < NEAR_TOLERANCE, v.mean()
    assert abs(v.mean() - expected.mean()) < 0.04, (v.mean(), expected.mean())

    scene.penumbra.world_ao_distance = 0.2
    color = render(scene)["Combined"][..., :3].mean(axis=-1)
    far = y < -0.25
    assert far.sum() > 500
    np.testing.assert_allclose(color[far] / full, 1.0, rtol=1e-4)
    near = (y > -0.1) & (y < -0.03)
    assert (color[near] / full).mean() < 0.9  # still within reach of the wall


def test_horizons_are_marched_at_half_resolution(penumbra, gpu_call):
    """The horizons are marched once per 2x2 pixels (``WorldAO.march``, odd sizes rounded up),
    and the lit pass upsamples them: the wall scene's floor near the wall still gets its
    occlusion, in every 2x2 block alike (no block left at 1 or stuck at its representative's)."""
    scene = wall_scene(size=(W + 1, H + 1))
    stats, color = frame(gpu_call, scene, W + 1, H + 1)
    assert stats.ao_prepasses == 1 and stats.ao_texels == ((W + 2) // 2) * ((H + 2) // 2)
    y = floor_points(scene)[..., 1]
    v = color.mean(axis=-1) / (ALBEDO * WORLD[0])
    near = (y > -0.12) & (y < -0.03)
    for dy in (0, 1):
        for dx in (0, 1):
            sub = near[dy::2, dx::2]
            assert sub.sum() > 40
            assert abs(v[dy::2, dx::2][sub].mean() - 0.5) < NEAR_TOLERANCE, (dx, dy)


def open_floor(ortho=False, size=(W, H)):
    """A 100 m floor under a uniform world and nothing on it, seen at a grazing angle."""
    scene = scenes.empty_scene(*size)
    scenes.set_world(scene, WORLD)
    scenes.plane(scene, "Floor", size=100.0, mat=scenes.white())
    cam = scenes.camera(scene, (0.0, -6.0, 1.0), (math.radians(80.0), 0.0, 0.0), lens=24.0)
    if ortho:
        cam.data.type = "ORTHO"
        cam.data.ortho_scale = 8.0
    return scene


@pytest.mark.parametrize("ortho", [False, True])
def test_an_open_floor_stays_unoccluded(penumbra, gpu_call, ortho):
    """Nothing on the floor: every floor pixel is albedo * world within 1 % (each slice's arc
    over the unoccluded arc: 1 however few slices, and steps on the plane land on it), whether
    the distance is automatic or 2 m, with one prepass; the row at the floor's far edge
    within 6 %."""
    scene = open_floor(ortho)
    view, proj, w, h = camera_matrices(scene)
    p, depth = plane_hits(view, proj, w, h, z=0.0)
    floor = (depth > 0.0) & np.all(np.abs(p[..., :2]) < 50.0, axis=-1)
    assert floor.sum() > 0.3 * W * H
    # The row next to the floor's far edge (the sky beyond): samples there fall back to the
    # nearest texel, off the slice by up to half a pixel, and keep up to 5 % (measured 4.5 %).
    inner = floor & np.roll(floor, 1, axis=0) & np.roll(floor, -1, axis=0)
    for distance in (0.0, 2.0):
        scene.penumbra.world_ao_distance = distance
        stats, color = frame(gpu_call, scene)
        assert stats.ao_prepasses == 1
        v = color.mean(axis=-1) / (ALBEDO * WORLD[0])
        np.testing.assert_allclose(v[inner], 1.0, rtol=0.01)
        np.testing.assert_allclose(v[floor], 1.0, rtol=0.06)


def box_on_floor(world=WORLD):
    scene = scenes.empty_scene(W, H)
    scenes.set_world(scene, world)
    scenes.box_over_plane(scene, plane_size=40.0, box_center=(0, 0, 0.5), box_size=1.0)
    scenes.light(scene, "Sun", "SUN", 2.0, rotation=(math.radians(30), 0, 0))
    scenes.look_at(scene, (3.0, -4.0, 3.0), (0.0, 0.0, 0.3), lens=30.0)
    return scene


def test_black_world_or_ao_off_cost_nothing(penumbra, gpu_call):
    """A black world, or World > Ambient Occlusion off: no prepass and no occlusion code (the
    lit variant is the one without WORLD_AO), the frame bit for bit the same either way; with
    a world and the setting on, one prepass in a one-sample frame and in a frame of several
    (its first sample), and the floor darkens at the box's foot, nowhere else."""
    scene = box_on_floor(world=(0.0, 0.0, 0.0))
    scene.penumbra.world_ao = True
    on_stats, on = frame(gpu_call, scene)
    scene.penumbra.world_ao = False
    off_stats, off = frame(gpu_call, scene)
    assert on_stats.ao_prepasses == off_stats.ao_prepasses == 0 and on_stats.ao_draws == 0
    assert np.array_equal(on, off)

    scene = box_on_floor()
    scene.penumbra.world_ao = False
    off_stats, off = frame(gpu_call, scene)
    assert off_stats.ao_prepasses == 0
    scene.penumbra.world_ao = True
    on_stats, on = frame(gpu_call, scene)
    assert on_stats.ao_prepasses == 1 and on_stats.ao_draws >= 2
    assert on_stats.passes == off_stats.passes and on_stats.draws == off_stats.draws
    darker = (off - on).mean(axis=-1)
    assert np.all(darker >= -1e-5)  # only ever occludes
    assert darker.max() > 0.1 * ALBEDO * WORLD[0]
    many_stats, _many = frame(gpu_call, scene, samples=4)
    assert many_stats.ao_prepasses == 1


def test_world_ao_sample_decision():
    """``features.world_occlusion.world_ao_sample``: a one-sample frame and sample 0 of several, with the
    setting on and a world that gives light; the WORLD_AO debug view every sample, the other
    lit debug views none."""
    from types import SimpleNamespace

    from penumbra.engine.frame.features.world_occlusion import ao_jitter, world_ao_distance, world_ao_sample

    on, off = SimpleNamespace(world_ao=True), SimpleNamespace(world_ao=False)
    grey = np.array((0.2, 0.2, 0.2))
    assert world_ao_sample(0, False, on, grey) and world_ao_sample(0, True, on, grey)
    assert not world_ao_sample(1, True, on, grey)
    assert not world_ao_sample(0, False, off, grey) and not world_ao_sample(0, False, on, np.zeros(3))
    assert world_ao_sample(5, True, on, grey, "WORLD_AO")
    assert not world_ao_sample(0, False, on, grey, "LIGHT_COST")
    assert ao_jitter(0) == (0.0, 0.0)
    corners = np.array([[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]])
    assert world_ao_distance(SimpleNamespace(world_ao_distance=0.0), corners) == pytest.approx(0.5)
    assert world_ao_distance(SimpleNamespace(world_ao_distance=2.0), corners) == 2.0
    assert world_ao_distance(SimpleNamespace(world_ao_distance=0.0), np.zeros((0, 3))) == 0.0


@pytest.mark.parametrize("scale", [1e-3, 1e4])
def test_same_picture_at_any_scale(penumbra, scale):
    """The wall scene scaled by 1e-3 and 1e4 (the distance with it) gives the picture of scale
    1; and with the automatic distance (a tenth of the scene's size) the same holds."""
    base = render(wall_scene())["Combined"][..., :3]
    scaled = render(wall_scene(scale))["Combined"][..., :3]
    assert np.all(np.isfinite(scaled))
    assert np.abs(scaled - base).mean() < 2e-3 * ALBEDO * WORLD[0], np.abs(scaled - base).mean()
    auto = render(wall_scene(scale, distance=0.0))["Combined"][..., :3]
    auto_base = render(wall_scene(1.0, distance=0.0))["Combined"][..., :3]
    assert np.abs(auto - auto_base).mean() < 2e-3 * ALBEDO * WORLD[0]


def test_extremes_stay_finite(penumbra):
    """A perspective camera on the wall (the band at its foot occluded as with the
    orthographic one), world strength 1e6 (the picture of strength 1, scaled), and a one-pixel
    frame: all finite."""
    scene = wall_scene(ortho=False)
    color = render(scene)["Combined"][..., :3]
    assert np.all(np.isfinite(color))
    y = floor_points(scene)[..., 1]
    near = (y > -0.12) & (y < -0.03)
    assert near.sum() > 50
    assert abs(color.mean(axis=-1)[near].mean() / (ALBEDO * WORLD[0]) - 0.5) < NEAR_TOLERANCE

    strong = render(wall_scene(strength=1e6))["Combined"][..., :3]
    weak = render(wall_scene())["Combined"][..., :3]
    assert np.all(np.isfinite(strong))
    np.testing.assert_allclose(strong / 1e6, weak, rtol=1e-4, atol=1e-6)

    for ortho in (False, True):
        tiny = render(wall_scene(ortho=ortho, size=(1, 1)))["Combined"]
        assert np.all(np.isfinite(tiny)) and tiny[..., :3].max() > 0.0


def test_world_ao_debug_view(penumbra, gpu_call):
    """The WORLD_AO debug view shows the visibility the lit pass used: about 1/2 at the wall's
    foot, 1 on the open floor beyond the distance; every sample occluded; all ones (and no
    prepass) with a black world."""
    from penumbra.engine.scene.extract import camera_from_scene

    scene = wall_scene(distance=0.2)
    scene.penumbra.debug_view = "WORLD_AO"
    y = floor_points(scene)[..., 1]

    def job(engine, depsgraph):
        cam = camera_from_scene(depsgraph, scene, W, H)
        out = engine.render_frame(depsgraph, cam, W, H, samples=(0, 2), sample_count=2)
        return out.stats, out.debug.values.copy(), out.debug.covered.copy()

    stats, values, covered = gpu_call(job)
    assert stats.ao_prepasses == 2 and covered.all()
    np.testing.assert_allclose(values[y < -0.25], 1.0, rtol=1e-5)
    assert 0.5 < values[(y > -0.1) & (y < -0.03)].mean() < 0.9
    scenes.set_world(scene, (0.0, 0.0, 0.0))
    stats, values, covered = gpu_call(job)
    assert stats.ao_prepasses == 0 and np.all(values == 1.0)
