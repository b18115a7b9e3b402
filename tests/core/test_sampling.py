"""Sample sequences (engine/frame/sampling.py): pixel offsets cover the filter and are weighted by
it, soft lights move over their own extent, and one sample is the single-sample frame."""

import math

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.frame import sampling  # noqa: E402
from penumbra.engine.scene.extract import Light  # noqa: E402


def _light(kind, **kw):
    m = np.eye(4)
    m[:3, 3] = (1.0, 2.0, 3.0)
    return Light(type=kind, color=np.ones(3), matrix=m, radius=kw.pop("radius", 0.0), **kw)


def test_first_sample_is_centred_and_offsets_fill_the_pixel():
    """The gathering film: sample 0 at the pixel's centre, the others uniform over the pixel
    (Halton (2, 3), centred), each weighing the window's total over the pixels it reaches; no
    filter, no jitter; a filter wider than the gather reaches draws offsets from the filter."""
    assert sampling.pixel_offset(0, 1.5)[:2] == (0.0, 0.0)
    offsets = np.array([sampling.pixel_offset(s, 1.5)[:2] for s in range(1, 1025)])
    assert np.all(offsets >= -0.5) and np.all(offsets < 0.5)
    # Low discrepancy: every quarter of the pixel gets a quarter of the points, +-2.
    quadrants = np.histogram2d(offsets[:, 0], offsets[:, 1], bins=2, range=[[-0.5, 0.5], [-0.5, 0.5]])[0]
    assert np.all(np.abs(quadrants - 256) <= 2)
    assert all(sampling.pixel_offset(s, 0.0) == (0.0, 0.0, 1.0) for s in range(5))  # no filter: no jitter
    wide = 2.0 * sampling.GATHER_REACH_MAX
    assert not sampling.gathers(wide) and sampling.pixel_offset(3, wide)[2] == 1.0


def test_a_samples_taps_are_the_filter_at_their_distance():
    """One sample's contribution to a film pixel is the Blackman-Harris window at the
    distance between the pixel's centre and the point the sample pixel shaded, separable in
    x and y (``sample_taps``), and the taps' weights sum to the sample's weight in the film."""
    assert sampling.blackman_harris(0.0, 1.5) == pytest.approx(1.0)
    assert sampling.blackman_harris(0.75, 1.5) == pytest.approx(0.0, abs=1e-4)
    assert sampling.blackman_harris(2.0, 1.5) == 0.0
    width = sampling.filter_width(1.5)
    assert sampling.gather_reach(1.5) == 1 and sampling.gather_reach(0.3) == 0 and sampling.gather_reach(2.0) == 2
    for s in range(12):
        dx, dy, weight = sampling.pixel_offset(s, 1.5)
        taps = sampling.sample_taps(s, 1.5)
        assert sum(w for _x, _y, w in taps) == pytest.approx(weight)
        for x, y, w in taps:
            assert abs(x) < 1.5 + 1e-9 and abs(y) < 1.5 + 1e-9
            assert w == pytest.approx(sampling.blackman_harris(x, width) * sampling.blackman_harris(y, width))
            assert (x + dx) == pytest.approx(round(x + dx)) and (y + dy) == pytest.approx(round(y + dy))


def test_jittered_projection_moves_the_image_by_whole_pixels_in_clip_space():
    proj = np.array([[1.2, 0, 0.1, 0], [0, 2.0, 0, 0], [0, 0, -1.01, -0.2], [0, 0, -1, 0]])
    point = np.array([0.3, -0.2, -5.0, 1.0])
    a = proj @ point
    b = sampling.jittered_projection(proj, 0.5, -0.25, 200, 100) @ point
    ndc_a, ndc_b = a[:2] / a[3], b[:2] / b[3]
    np.testing.assert_allclose((ndc_b - ndc_a) * np.array([100, 50]), [0.5, -0.25], atol=1e-12)


@pytest.mark.parametrize("kind", ["SPOT", "POINT", "AREA", "SUN"])
def test_soft_lights_move_within_their_extent_and_hard_lights_never(kind):
    extra = {"SPOT": {"radius": 0.5}, "POINT": {"radius": 0.5}, "SUN": {"angle": math.radians(10)}}.get(kind, {})
    if kind == "AREA":
        extra = {"size_x": 2.0, "size_y": 1.0, "size": 2.0, "shape": "RECTANGLE"}
    light = _light(kind, **extra)
    n = 64
    samples = [sampling.light_at_sample(light, 3, s, n) for s in range(n)]
    assert all(s.penumbra_scale == pytest.approx(1 / 8) and s.sampled for s in samples)
    if kind == "SUN":
        cos = [float(s.direction @ light.direction) for s in samples]
        assert min(cos) >= math.cos(math.radians(5)) - 1e-9 and min(cos) < math.cos(math.radians(3))
    else:
        offsets = np.array([s.position - light.position for s in samples])
        if kind == "AREA":
            assert np.all(np.abs(offsets[:, 0]) <= 1.0 + 1e-9) and np.all(np.abs(offsets[:, 1]) <= 0.5 + 1e-9)
            assert np.allclose(offsets[:, 2], 0.0)  # on the light's plane
            assert np.abs(offsets[:, 0]).max() > 0.8
        else:
            r = np.linalg.norm(offsets, axis=1)
            assert r.max() <= 0.5 + 1e-9 and r.max() > 0.4
        assert abs(offsets.mean(axis=0)).max() < 0.05  # centred on the light
        if kind == "AREA":  # stratified: each quarter of the rectangle gets 16 of the 64 points, +-3
            quarters = np.histogram2d(offsets[:, 0], offsets[:, 1], bins=2, range=[[-1, 1], [-0.5, 0.5]])[0]
            assert np.all(np.abs(quarters - 16) <= 3), quarters
    hard = _light(kind)
    assert all(sampling.light_at_sample(hard, 3, s, n) is hard for s in range(4))
    assert sampling.light_at_sample(light, 3, 0, 1) is light  # one sample: the light itself


def test_sequences_are_deterministic_and_differ_between_lights():
    light = _light("SPOT", radius=1.0)
    a = [sampling.light_at_sample(light, 0, s, 16).position for s in range(1, 8)]
    b = [sampling.light_at_sample(light, 0, s, 16).position for s in range(1, 8)]
    c = [sampling.light_at_sample(light, 1, s, 16).position for s in range(1, 8)]
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)


def test_only_lights_whose_penumbra_reaches_a_texel_move_between_samples():
    from penumbra.engine.shadows import lightspace
    from penumbra.engine.shadows import planning as shadows

    def plan_for(fits):
        plan = shadows.ShadowPlan()
        for i, fit in enumerate(fits):
            if fit is not None:
                plan.lights[i] = shadows.LightShadow("SINGLE", [len(plan.tiles)])
                plan.tiles.append(shadows.Tile(fit, np.arange(1)))
        return plan

    ortho = lightspace.Fit(np.eye(4), np.eye(4), near=0.0, far=10.0, texel=0.01)  # 10 m deep, 1 cm texels
    persp = lightspace.Fit(np.eye(4), np.eye(4), near=2.0, far=10.0, texel_per_distance=0.001)
    tiny_sun = _light("SUN", angle=math.radians(0.01))  # 2 tan(0.005 deg) * 10 m = 1.7 mm < 1 cm
    sun = _light("SUN", angle=math.radians(1))  # 17 cm: 17 texels
    spot = _light("SPOT", radius=0.1)  # 2 * 0.1 / (0.001 * 2) = 100 texels
    unshadowed_spot = _light("SPOT", radius=0.1)
    area = _light("AREA", size_x=1.0, size_y=1.0, size=1.0)  # unshadowed: its irradiance still moves
    assert sampling.penumbra_texels(tiny_sun, ortho) < 1 < sampling.penumbra_texels(sun, ortho)
    assert sampling.penumbra_texels(spot, persp) == pytest.approx(100.0)
    lights = [tiny_sun, sun, spot, unshadowed_spot, area]
    assert sampling.sampled_lights(lights, plan_for([ortho, ortho, persp, None, None])) == {1, 2, 4}
    # With jittered maps every shadowed light with an extent is sampled, however small.
    assert sampling.sampled_lights(lights, plan_for([ortho, ortho, persp, None, None]), every=True) == {0, 1, 2, 4}


# --- adaptive sampling ------------------------------------------------------------------------


def test_automatic_min_samples_follow_cycles():
    """Cycles: threshold 0.1 -> 32, 0.01 -> 64, 0.001 -> 128 samples before the first check."""
    assert [sampling.auto_min_samples(t) for t in (0.1, 0.01, 0.001)] == [32, 64, 128]


def test_adaptive_settings_off_cases_and_check_schedule():
    settings = sampling.adaptive_settings
    assert settings(False, 0.01, 8, 0.0, 64) is None  # off
    assert settings(True, 0.0, 8, 0.0, 64) is None  # threshold 0: off too
    # Automatic Min Samples 64: no noise check before the last sample, but pixels settle
    # after the pilot sample; an explicit Min Samples above 1, or a one-sample frame, no settling.
    for count in (16, 64):
        only = settings(True, 0.01, 0, 0.0, count)
        assert only.threshold == 0.0 and only.settle == 0.01 and not any(only.checks_at(n) for n in range(1, 65))
    assert settings(True, 0.01, 0, 0.0, 1) is None
    assert settings(True, 0.01, 8, 0.0, 8) is None  # Min Samples 8: no settling, no check before the end
    assert settings(True, 0.01, 1, 0.0, 8).settle == 0.01
    assert settings(True, 0.01, 8, 0.0, 64).settle == 0.0
    limited = settings(True, 0.01, 4, 2.5, 4)  # the time limit alone
    assert limited.threshold == 0.0 and limited.settle == 0.0 and limited.time_limit == 2.5
    assert not limited.checks_at(8)
    a = settings(True, 0.01, 6, 0.0, 64)  # checks on multiples of the step from Min Samples on
    assert a.min_samples == 8 and [n for n in range(1, 21) if a.checks_at(n)] == [8, 12, 16, 20]
    endless = settings(True, 0.1, 0, 0.0, 0)  # the viewport refining without end
    assert endless.min_samples == 32
    assert settings(True, 0.01, 1, 0.0, 64).min_samples == sampling.ADAPTIVE_STEP


def test_the_progressive_light_points_are_stratified_at_every_power_of_two():
    """Adaptive frames may stop a pixel after any multiple of 4 samples: the first 2^k points of
    a light's progressive sequence fall one in each elementary interval of area 2^-k (every
    2^a x 2^(k-a) grid), a (0, k, 2)-net, for each light's own digital shift."""
    for light_index in (0, 5):
        points = np.array([sampling._light_point_progressive(s, light_index, 2) for s in range(64)])
        for k in range(1, 7):
            first = points[: 2**k]
            for a in range(k + 1):
                cells = np.floor(first[:, 0] * 2**a) * 2 ** (k - a) + np.floor(first[:, 1] * 2 ** (k - a))
                assert len(np.unique(cells)) == 2**k, (light_index, k, a)
    a = [sampling._light_point_progressive(s, 0, 2) for s in range(8)]
    b = [sampling._light_point_progressive(s, 1, 2) for s in range(8)]
    assert not np.allclose(a, b)  # lights do not move in step


def test_progressive_points_keep_an_area_light_on_its_surface_and_centred_early():
    """The first 16 of 64 progressive points are stratified along each side, so their mean is
    within half a stratum (side / 32) of the light's centre; the first 16 of the shuffled set
    of 64 (which only the whole set stratifies) need not be."""
    light = _light("AREA", size_x=2.0, size_y=1.0, shape="RECTANGLE")
    centre = light.position

    def offsets(progressive):
        return np.array(
            [sampling.light_at_sample(light, 3, s, 64, progressive=progressive).position - centre for s in range(16)]
        )

    early = offsets(True)
    assert np.all(np.abs(early[:, 0]) <= 1.0 + 1e-9) and np.all(np.abs(early[:, 1]) <= 0.5 + 1e-9)
    assert abs(early[:, 0].mean()) <= 2.0 / 32 and abs(early[:, 1].mean()) <= 1.0 / 32
    assert np.linalg.norm(early.mean(axis=0)) < np.linalg.norm(offsets(False).mean(axis=0))


def test_map_jitter_is_stratified_over_the_texel_and_leaves_sample_zero_alone():
    for n in (4, 16, 64, 256):
        shifts = np.array([sampling.map_jitter(s, 2, n) for s in range(n)])
        assert tuple(shifts[0]) == (0.0, 0.0)
        assert np.all(shifts >= -0.5) and np.all(shifts < 0.5)
        # One point per 1/n strip of the texel along x, and the quarters evenly filled.
        strips = np.floor((shifts[:, 0] + 0.5) * n + 1e-9).astype(int)
        assert sorted(strips) == list(range(n))
        quarters = np.histogram2d(shifts[:, 0], shifts[:, 1], bins=2, range=[[-0.5, 0.5], [-0.5, 0.5]])[0]
        assert np.all(np.abs(quarters - n / 4) <= max(1, n // 16)), (n, quarters)
    assert sampling.map_jitter(0, 0, 1) == (0.0, 0.0) and sampling.map_jitter(3, 0, 1) == (0.0, 0.0)
    a = [sampling.map_jitter(s, 0, 16) for s in range(16)]
    assert a == [sampling.map_jitter(s, 0, 16) for s in range(16)]  # a function of (s, N, light)
    assert a != [sampling.map_jitter(s, 1, 16) for s in range(16)]


def test_jittered_lights_carry_their_shift_and_offsets_shrinking_as_one_over_root_n():
    hard = _light("SUN")
    sun = _light("SUN", angle=math.radians(0.526))
    for light in (hard, sun):
        first = sampling.light_at_sample(light, 0, 0, 16, jitter=True)
        later = sampling.light_at_sample(light, 0, 5, 16, jitter=True)
        assert first.jittered and later.jittered and first.sampled and later.sampled
        assert first.map_jitter == (0.0, 0.0) and later.map_jitter == sampling.map_jitter(5, 0, 16)
        assert later.offset_scale == pytest.approx(0.25) and later.bias_scale == light.bias_scale
    spot = sampling.light_at_sample(_light("SPOT", radius=0.02), 0, 5, 16, jitter=True)
    assert spot.jittered and spot.bias_scale == 1.0 and spot.offset_scale == pytest.approx(0.25)
    assert sampling.light_at_sample(hard, 0, 5, 16) is hard  # no jitter: a hard light never changes
    assert sampling.light_at_sample(hard, 0, 0, 1, jitter=True) is hard  # one sample: the light itself
    # Sun points: stratified in the disc's area (Vogel's spiral), within the angle.
    cos = [float(sampling.light_at_sample(sun, 0, s, 64, jitter=True).direction @ sun.direction) for s in range(64)]
    assert min(cos) >= math.cos(math.radians(0.263)) - 1e-12


@pytest.mark.parametrize("kind", ["POINT", "SPOT"])
def test_point_and_spot_lights_are_sampled_as_spheres_seen_as_uniform_discs(kind):
    """From any direction, the sampled points' projection across it is uniform on the disc of
    the sphere's radius (as Cycles samples a sphere light's visible disc): the fraction
    inside radius rho is rho^2, within the stratified set's precision."""
    light = _light(kind, radius=0.5)
    n = 1024
    offsets = np.array([sampling.light_at_sample(light, 0, s, n).position - light.position for s in range(n)])
    assert np.linalg.norm(offsets, axis=1).max() <= 0.5 + 1e-9
    rng = np.random.default_rng(1)
    for axis in rng.normal(size=(4, 3)):
        axis /= np.linalg.norm(axis)
        across = offsets - np.outer(offsets @ axis, axis)
        rho = np.linalg.norm(across, axis=1) / 0.5
        for q in (0.25, 0.5, 0.75, 0.9):
            assert abs(np.mean(rho <= q) - q * q) < 0.03, (axis, q)
    assert sampling._ball_radius(0.0) == 0.0 and sampling._ball_radius(1.0) == pytest.approx(1.0)


def test_a_shifted_fit_moves_the_texel_grid_by_that_many_texels():
    from penumbra.engine.shadows import lightspace

    view = lightspace.look_at(np.array([0.0, 0.0, 5.0]), np.array([0.0, 0.0, -1.0]))
    for proj in (lightspace.orthographic(-2, 2, -2, 2, 1, 9), lightspace.perspective(1.0, 1.0, 1.0, 9.0)):
        fit = lightspace.Fit(view, proj, 1.0, 9.0, texel=0.01)
        moved = lightspace.shifted(fit, (0.25, -0.5), 512)
        p = np.array([0.3, -0.2, 1.0, 1.0])
        a, b = fit.view_proj @ p, moved.view_proj @ p
        texels = (b[:2] / b[3] - a[:2] / a[3]) * 0.5 * 512
        np.testing.assert_allclose(texels, [0.25, -0.5], atol=1e-9)
        assert (moved.near, moved.far, moved.texel) == (fit.near, fit.far, fit.texel)


def test_widened_projection_keeps_every_offset_of_the_filter_inside():
    """A pixel centre on the frame's border moved outward by the filter's whole reach lands on
    the edge of the widened frustum's clip square; with no reach nothing changes."""
    proj = np.array([[1.2, 0, 0.1, 0], [0, 2.0, 0, 0], [0, 0, -1.01, -0.2], [0, 0, -1, 0]])
    width, height, reach = 64, 36, 1.5
    wide, size = sampling.widened_projection(proj, reach, width, height)
    assert size == (width + 3.0, height + 3.0)
    for px, py, edge in ((-reach, -reach, -1.0), (width + reach, height + reach, 1.0)):
        ndc = np.array([2.0 * px / width - 1.0, 2.0 * py / height - 1.0])  # of the original frame
        z = -3.0
        # The view point at depth z seen at that NDC position through ``proj``.
        xy = np.linalg.solve(proj[:2, :2], ndc * -z - proj[:2, 2] * z)
        clip = wide @ np.array([*xy, z, 1.0])
        assert clip[:2] / clip[3] == pytest.approx((edge, edge))
    assert sampling.widened_projection(proj, 0.0, width, height)[0] == pytest.approx(proj)


def test_filter_reach_at_its_extremes():
    from penumbra.engine.frame.features.settling import MAX_FLAG_REACH, flag_reach

    assert sampling.filter_width(0.0) == 0.0 and sampling.filter_width(10.0) == 20.0
    assert [flag_reach(f) for f in (0.0, 0.5, 1.0, 1.5, 2.0, 10.0)] == [1, 1, 1, 2, 2, MAX_FLAG_REACH]
    offsets = np.array([sampling.pixel_offset(s, 10.0)[:2] for s in range(1, 257)])
    assert np.all(np.isfinite(offsets)) and np.all(np.abs(offsets) < 10.0)  # within the reach
    assert all(np.isfinite(sampling.pixel_offset(s, 4.4)[2]) for s in range(8))  # the widest gather


@pytest.mark.parametrize("ior", [0.0, -1.0, 1.0, 1.5, 1e6, math.inf, math.nan])
@pytest.mark.parametrize("level", [0.0, -1.0, 0.5, 1e6])
def test_dielectric_f0_is_finite_and_in_range_at_the_extremes(ior, level):
    from penumbra.engine.scene.materials import dielectric_f0

    f0 = dielectric_f0(ior, level, (2.0, -1.0, math.inf))
    assert len(f0) == 4 and all(math.isfinite(v) and 0.0 <= v <= 1.0 for v in f0)
    if ior == 1.0 or level <= 0.0:
        assert f0 == (0.0, 0.0, 0.0, 0.0)  # no specular: IOR 1 or level 0
    if ior == 1.5 and level == 0.5:
        assert f0 == pytest.approx((0.08, 0.0, 1.0, 0.04))
