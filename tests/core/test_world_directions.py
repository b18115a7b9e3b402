"""The world's directions (``engine/frame/world/directions.py``), in numpy: what they estimate
converges to the integrals they stand for, their probabilities are densities, and extreme
worlds stay finite."""

import math

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.frame.world import directions as ws  # noqa: E402
from penumbra.engine.scene.extract import Light  # noqa: E402
from penumbra.engine.scene.materials import World, equirect_sh  # noqa: E402


def _grid(h=64, w=128):
    """Directions of an equirectangular grid (h, w, 3) as Blender maps it, and each texel's
    solid angle (h, w)."""
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(w) + 0.5) / w
    lat = (v - 0.5) * math.pi
    lon = (0.5 - u) * 2.0 * math.pi
    cl = np.cos(lat)[:, None]
    d = np.stack(
        [np.cos(lon)[None, :] * cl, np.sin(lon)[None, :] * cl, np.broadcast_to(np.sin(lat)[:, None], (h, w))], -1
    )
    edges = np.sin((np.arange(h + 1) / h - 0.5) * math.pi)
    return d, np.broadcast_to((2.0 * math.pi / w) * np.diff(edges)[:, None], (h, w))


def _sun_sky(h=64, w=128, peak=50.0):
    d, _ = _grid(h, w)
    sun = np.array([0.3, -0.4, 0.866])
    sun /= np.linalg.norm(sun)
    return 0.2 * (d[..., 2:3] > 0.0) + peak * (d @ sun > 0.995)[..., None] * np.array([1.0, 0.9, 0.8])


def _estimate(dist, normal, n=1 << 14):
    d = dist.directions(ws.sequence_points(0, n))
    return (dist.radiance(d) * np.maximum(d @ normal, 0.0)[:, None] / dist.pdf(d)[:, None]).mean(0)


def test_a_constant_world_gives_pi_times_its_radiance_on_any_facing():
    world = World.constant((0.5, 0.6, 0.7))
    dist = ws.WorldDistribution(world.sh)
    for normal in ([0, 0, 1], [1, 0, 0], [0.6, -0.8, 0.0]):
        np.testing.assert_allclose(
            _estimate(dist, np.array(normal, float)), np.array([0.5, 0.6, 0.7]) * math.pi, rtol=2e-3
        )


@pytest.mark.parametrize("rotation_z", [0.0, 70.0])
def test_an_image_world_estimates_its_irradiance_and_its_pdf_is_a_density(rotation_z):
    """With a sun blob 250x the sky, drawn by luminance (and turned by a Mapping rotation), the
    estimate of the irradiance on a tilted facing is within 1 % of the image's exact sum."""
    c, s = math.cos(math.radians(rotation_z)), math.sin(math.radians(rotation_z))
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    env = _sun_sky()
    dist = ws.WorldDistribution(equirect_sh(env, rotation), env, rotation=rotation)
    d, solid = _grid()
    world_d = d.reshape(-1, 3) @ rotation  # the image's directions in the world
    np.testing.assert_allclose((dist.pdf(world_d) * solid.ravel()).sum(), 1.0, rtol=1e-9)
    normal = np.array([0.0, 0.6, 0.8])
    exact = (env.reshape(-1, 3) * np.maximum(world_d @ normal, 0.0)[:, None] * solid.reshape(-1, 1)).sum(0)
    np.testing.assert_allclose(_estimate(dist, normal), exact, rtol=0.01)
    # Directions gather where the image is bright: the sun's texels get their share of its
    # luminance of the directions drawn by luminance (the rest are uniform over the sphere).
    drawn = dist.directions(ws.sequence_points(0, 4096))
    r, col = dist._texel(drawn)
    flux = (env @ [0.2126, 0.7152, 0.0722]) * solid
    share = (1.0 - ws.UNIFORM_SHARE) * flux[env[..., 0] > 10.0].sum() / flux.sum()
    assert abs((env[r, col, 0] > 10.0).mean() - share) < 0.03, share


def test_a_constant_world_direction_carries_its_radiance_over_its_probability():
    """Drawn uniformly (p = 1 / 4 pi), each of K directions carries L 4 pi / K: what the lit
    pass weighs the world ratio's sums with; never negative."""
    lights = ws.world_lights(World.constant((1.0, 0.9, 0.8)), 0, 4)
    for light in lights:
        np.testing.assert_allclose(light.color, np.array([1.0, 0.9, 0.8]) * 4.0 * np.pi / 4, rtol=1e-9)
        assert light.world and light.type == "SUN" and light.use_shadow


def test_portal_cones_gather_directions_and_keep_a_density():
    """A window portal: three quarters of the directions fall in its cone, the density still
    integrates to 1 over the sphere, and the directions carry the world's whole light."""
    matrix = np.eye(4)
    matrix[:3, 3] = (0.0, 2.5, 1.4)
    cones = ws.portal_cones([(matrix, 1.6, 1.4)], np.array([-2.0, -2.5, 0.0]), np.array([2.0, 2.5, 2.8]))
    assert len(cones) == 1 and 0.0 < cones[0][1] < 1.0
    dist = ws.WorldDistribution(World.constant((1.0, 1.0, 1.0)).sh, cones=cones)
    d, solid = _grid(256, 512)
    np.testing.assert_allclose((dist.pdf(d.reshape(-1, 3)) * solid.ravel()).sum(), 1.0, rtol=2e-3)
    drawn = dist.directions(ws.sequence_points(0, 2048))
    axis, cos_max = cones[0]
    assert (drawn @ axis >= cos_max).mean() > 0.75
    lights = ws.world_lights(World.constant((1.0, 1.0, 1.0)), 0, 4, cones=cones)
    drawn = np.array([light.direction for light in lights])
    expected = 1.0 / (dist.pdf(-drawn) * 4)  # a sun's direction is where it shines: away from d
    np.testing.assert_allclose([light.color[0] for light in lights], expected, rtol=1e-9)


@pytest.mark.parametrize(
    "env",
    [np.zeros((1, 1, 3)), np.full((1, 1, 3), 1e6), np.full((2, 4, 3), np.nan), np.full((64, 128, 3), np.inf)],
    ids=["black 1x1", "1e6 1x1", "NaN", "inf"],
)
def test_extreme_images_give_finite_directions(env):
    clean = np.nan_to_num(env, nan=0.0, posinf=0.0)
    world = World(sh=equirect_sh(clean), background=None, env=env)
    for light in ws.world_lights(world, 0, 8):
        assert np.all(np.isfinite(light.color)) and np.all(light.color >= 0.0)
        assert np.all(np.isfinite(light.matrix)) and abs(np.linalg.norm(light.direction) - 1.0) < 1e-9


def test_a_black_world_or_the_setting_off_samples_nothing():
    from types import SimpleNamespace

    on = SimpleNamespace(world_shadows=True)
    assert not ws.needs_directions(World.constant((0.0, 0.0, 0.0)), on)
    assert not ws.needs_directions(World.constant((1.0, 1.0, 1.0)), SimpleNamespace(world_shadows=False))
    assert not ws.needs_directions(None, on)
    assert ws.needs_directions(World.constant((1e-3, 0.0, 0.0)), on)


def test_portal_cones_at_their_extremes():
    """A zero-size portal, a portal at the box's centre (its +Z half-space), a non-finite
    portal matrix and a non-finite box: every cone is a valid cone or is left out."""
    lo, hi = np.array([-1.0, -1.0, 0.0]), np.array([1.0, 1.0, 2.0])
    point = np.eye(4)
    point[:3, 3] = (0.0, 3.0, 1.0)
    centred = np.eye(4)
    centred[:3, 3] = (0.0, 0.0, 1.0)
    broken = np.full((4, 4), np.nan)
    cones = ws.portal_cones([(point, 0.0, 0.0), (centred, 1.0, 1.0), (broken, 1.0, 1.0)], lo, hi)
    assert len(cones) == 2
    for axis, cos_max in cones:
        assert abs(np.linalg.norm(axis) - 1.0) < 1e-12 and 0.0 <= cos_max < 1.0
    np.testing.assert_allclose(cones[1][0], (0.0, 0.0, 1.0))
    assert cones[1][1] == pytest.approx(0.0, abs=1e-12)  # a whole half-space
    assert ws.portal_cones([(point, 1.0, 1.0)], lo, np.array([np.inf, 1.0, 2.0])) == []
    dist = ws.WorldDistribution(World.constant((1.0, 1.0, 1.0)).sh, cones=cones)
    d = dist.directions(ws.sequence_points(0, 256))
    assert np.all(np.isfinite(d)) and np.all(np.isfinite(dist.pdf(d))) and np.all(dist.pdf(d) > 0.0)


def test_directions_follow_the_worlds_share_at_its_extremes():
    """``light_share`` and ``directions_per_sample``: a world alone takes every direction, one
    under a lamp far brighter than it, none for a black world or a setting of 0; NaN and
    infinite lamps or a lamp at the centre give a share in [0, 1], never NaN."""
    sky = World.constant((0.5, 0.5, 0.5))
    black = World.constant((0.0, 0.0, 0.0))

    def lamp(kind, power, position=(0.0, 0.0, 3.0)):
        matrix = np.eye(4)
        matrix[:3, 3] = position
        return Light(type=kind, color=np.full(3, power), matrix=matrix, radius=0.0, angle=0.0, use_shadow=True)

    centre = np.zeros(3)
    assert ws.light_share(sky, [], centre) == 1.0
    assert ws.light_share(black, [lamp("SUN", 3.0)], centre) == 0.0
    bright = ws.light_share(sky, [lamp("SUN", 1e4)], centre)
    assert 0.0 < bright < 1e-3
    for extreme in (
        lamp("POINT", np.inf),
        lamp("SPOT", np.nan),
        lamp("POINT", 100.0, (0.0, 0.0, 0.0)),
        lamp("AREA", 1.0),
    ):
        share = ws.light_share(sky, [extreme], centre)
        assert 0.0 <= share <= 1.0, share
    assert [ws.directions_per_sample(s, 4) for s in (1.0, 0.5, 0.25, 0.1, 1e-9, 0.0)] == [4, 4, 2, 1, 1, 1]
    assert ws.directions_per_sample(0.7, 0) == 0
    assert ws.directions_per_sample(0.3, 16) == 10


def test_a_world_under_the_noise_threshold_is_negligible():
    """``world_negligible``: a world whose whole light is under the noise a frame accepts
    (sqrt of its radiance below the Noise Threshold, Cycles' error units for a pixel it alone
    lights) takes no directions and no occlusion; one above it does, however bright the lamps
    (they do not enter the rule). Constant colours, NaN and infinite worlds are read safely."""
    for radiance, threshold, negligible in (
        (0.0, 0.01, True),
        (0.5e-4, 0.01, True),  # sqrt 0.007 < 0.01
        (2e-4, 0.01, False),  # sqrt 0.014
        (0.05, 0.01, False),  # the demo's dim world
        (0.5e-6, 0.0, True),  # without adaptive sampling: NEGLIGIBLE_ERROR (0.001)
        (2e-6, 0.0, False),
    ):
        world = World.constant((radiance, radiance, radiance))
        assert ws.world_negligible(world, threshold) is negligible, (radiance, threshold)
        assert ws.world_negligible((radiance, radiance, radiance), threshold) is negligible, (radiance, threshold)
    assert ws.world_negligible(None)
    # Non-finite SH light is read as ``light_share`` reads it (no light to shadow), never NaN.
    assert ws.world_negligible(World.constant((np.inf, 0.0, 0.0)), 0.01)
    assert ws.world_negligible(World.constant((np.nan, np.nan, np.nan)), 0.01)
    assert not ws.world_negligible(World.constant((np.inf, 1.0, 1.0)), 0.01)


def test_the_worlds_sun_takes_the_light_above_the_threshold():
    """World > Sun (``world.sun.with_sun``): the image's radiance above the threshold becomes a
    sun of that irradiance, shining from the extracted light's direction (the Mapping rotation
    followed), the rest stays in the SH light and the directions' image, capped at the
    threshold: the two add up to the image's whole light, and neither is below zero. No texel
    above it, or a threshold of 0, extracts nothing."""
    from penumbra.engine.frame.world import sun as world_sun
    from penumbra.engine.scene.materials import WorldSun, equirect_sh

    h, w = 32, 64
    env = np.full((h, w, 3), 0.5)
    env[20, 40] = (400.0, 300.0, 200.0)  # a sun, one texel
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 degrees about z
    for rotation in (None, turn):
        world = World(sh=equirect_sh(env, rotation), background=None, env=env, rotation=rotation, sun=WorldSun(10.0))
        out, light = world_sun.with_sun(world)
        d, omega = world_sun._directions(h, w)
        expected = (env[20, 40] - 10.0) * omega[20, 40]
        np.testing.assert_allclose(light.color, expected, rtol=1e-12)
        towards = d[20, 40] @ (rotation if rotation is not None else np.eye(3))
        np.testing.assert_allclose(light.matrix[:3, 2], towards, atol=1e-12)  # -Z shines from it
        assert light.type == "SUN" and light.use_shadow and light.angle == pytest.approx(0.0092)
        assert out.env.max() <= 10.0 and out.env.min() >= 0.0
        whole = (env * omega[..., None]).sum(axis=(0, 1))
        np.testing.assert_allclose((out.env * omega[..., None]).sum(axis=(0, 1)) + light.color, whole, rtol=1e-12)
        np.testing.assert_allclose(out.sh, equirect_sh(out.env, rotation), rtol=1e-12)
    dim = World(sh=equirect_sh(env * 0.01), background=None, env=env * 0.01, sun=WorldSun(10.0))
    assert world_sun.with_sun(dim) == (dim, None)
    off = World(sh=equirect_sh(env), background=None, env=env, sun=None)
    assert world_sun.with_sun(off) == (off, None)
