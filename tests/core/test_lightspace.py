"""Light-space maths: plain numpy, checked against hand-derived values."""

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.shadows import light_bins, lightspace  # noqa: E402


@pytest.mark.parametrize(
    "forward",
    [(0, 0, -1), (0, 0, 1), (0, 1, 0), (0, -1, 0), (1, 0, 0), (0.3, -0.2, -0.9), (1e-12, 0, -1)],
)
def test_look_at_is_orthonormal_for_every_direction(forward):
    v = lightspace.look_at((1.0, 2.0, 3.0), forward)
    r = v[:3, :3]
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0)
    f = np.asarray(forward, float) / np.linalg.norm(forward)
    np.testing.assert_allclose(r @ f, (0, 0, -1), atol=1e-12)  # forward maps to -Z
    np.testing.assert_allclose(v @ (1, 2, 3, 1), (0, 0, 0, 1), atol=1e-12)  # eye maps to origin


def test_look_at_zero_direction_falls_back():
    v = lightspace.look_at((0, 0, 0), (0, 0, 0))
    assert np.all(np.isfinite(v))


def test_orthographic_maps_box_to_ndc_cube():
    p = lightspace.orthographic(-2, 4, -1, 3, 0.5, 10.5)
    corners = np.array([[-2, -1, -0.5], [4, 3, -10.5]])
    ndc = lightspace.transform_points(p, corners)
    np.testing.assert_allclose(ndc, [[-1, -1, -1], [1, 1, 1]], atol=1e-12)


def test_perspective_matches_definition():
    p = lightspace.perspective(np.radians(90), 2.0, 1.0, 100.0)
    # A point on the near plane at the top edge maps to y = 1, z = -1.
    ndc = lightspace.transform_points(p, [[0, 1, -1], [0, 0, -100]])
    np.testing.assert_allclose(ndc[0], [0, 1, -1], atol=1e-12)
    np.testing.assert_allclose(ndc[1][2], 1.0, atol=1e-12)


def test_bias_matrix_maps_ndc_to_unit_cube():
    np.testing.assert_allclose(lightspace.BIAS_MATRIX @ (-1, -1, -1, 1), (0, 0, 0, 1))
    np.testing.assert_allclose(lightspace.BIAS_MATRIX @ (1, 1, 1, 1), (1, 1, 1, 1))


@pytest.mark.parametrize(
    "m",
    [
        np.diag([2.0, 3.0, 0.5, 1.0]),
        np.diag([-1.0, 1.0, 1.0, 1.0]),
        np.array([[1, 0.5, 0, 0], [0, 1, 0.2, 0], [0.1, 0, 2, 0], [0, 0, 0, 1.0]]),
    ],
)
def test_normal_matrix_is_inverse_transpose_up_to_positive_scale(m):
    n = lightspace.normal_matrix(m)
    ref = np.linalg.inv(m[:3, :3]).T
    c = n @ np.linalg.inv(ref)  # must be c * identity with c > 0
    assert c[0, 0] > 0
    np.testing.assert_allclose(c, c[0, 0] * np.eye(3), atol=1e-9 * abs(c[0, 0]))


def test_normal_matrix_is_finite_for_zero_scale():
    n = lightspace.normal_matrix(np.diag([0.0, 1.0, 1.0, 1.0]))
    assert np.all(np.isfinite(n))
    # The x-axis normal of a surface flattened in x survives; others collapse to zero.
    np.testing.assert_allclose(n @ (1, 0, 0), (1, 0, 0))


def test_sun_fit_contains_points_and_is_texel_snapped():
    rng = np.random.default_rng(1)
    pts = rng.uniform(-5, 5, (200, 3))
    d = np.array([0.3, -0.4, -0.8])
    fit = lightspace.fit_sun_ortho(d, pts, 1024)
    view, proj, texel = fit.view, fit.proj, fit.texel
    ndc = lightspace.transform_points(proj @ view, pts)
    assert np.all(np.abs(ndc) <= 1.0)
    # Frustum edges lie on whole texels of light space: moving the points by less than a
    # texel keeps the projection's offset on the same grid.
    left = (-1 - proj[0, 3]) / proj[0, 0]
    assert abs(left / texel - round(left / texel)) < 1e-6
    width = 2 / proj[0, 0]
    assert width / texel == pytest.approx(1024)


def test_sun_fit_scale_invariant():
    """The same scene at 1e-3 and 1e4 scale gets the same fit, scaled (no fixed epsilons)."""
    pts = np.array([[-1, -1, 0], [1, 1, 0], [0.2, 0.1, 2.0]])
    d = (0.2, 0.1, -1.0)
    a = lightspace.fit_sun_ortho(d, pts, 512)
    for s in (1e-3, 1e4):
        b = lightspace.fit_sun_ortho(d, pts * s, 512)
        assert b.texel == pytest.approx(a.texel * s, rel=0.2)
        ndc_a = lightspace.transform_points(a.view_proj, pts)
        ndc_b = lightspace.transform_points(b.view_proj, pts * s)
        assert np.all(np.abs(ndc_b) <= 1.0)
        np.testing.assert_allclose(ndc_b[:, 2], ndc_a[:, 2], atol=0.05)


def test_sun_fit_empty_and_nonfinite():
    assert lightspace.fit_sun_ortho((0, 0, -1), np.zeros((0, 3)), 512) is None
    assert lightspace.fit_sun_ortho((0, 0, -1), [[np.nan, 0, 0]], 512) is None
    one = lightspace.fit_sun_ortho((0, 0, -1), [[1, 2, 3]], 1)
    assert one is not None and np.all(np.isfinite(one.view_proj)) and one.far > one.near


def test_perspective_tile_covers_the_casters_in_front_only():
    """The fit spot and cube-face maps use: near/far bracket every caster in the cone, all their
    corners project inside the map, and a light with every caster behind it gets no tile."""
    from penumbra.engine.shadows.planning import Boxes, Eye, perspective_tile

    boxes = [((-0.5, -0.5, -2.5), (0.5, 0.5, -2.0)), ((0.0, 0.0, -6.5), (1.0, 1.0, -6.0)), ((0, 0, 4), (1, 1, 5))]
    corners = np.stack([lightspace.box_corners(np.array(lo, float), np.array(hi, float)) for lo, hi in boxes])
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    tile = perspective_tile(Eye(np.zeros(3), np.array([0, 0, -1.0]), np.radians(90)), Boxes(corners, lo, hi), 256)
    assert list(tile.casters) == [0, 1]  # the box behind the light casts nothing into the cone
    assert tile.fit.near <= 2.0 and tile.fit.far >= 6.5
    ndc = lightspace.transform_points(tile.fit.view_proj, corners[:2].reshape(-1, 3))
    assert np.all(np.abs(ndc) <= 1.0 + 1e-9)
    assert tile.fit.texel_per_distance == pytest.approx(2.0 / 256)
    behind = perspective_tile(Eye(np.zeros(3), np.array([0, 0, 1.0]), 0.5), Boxes(corners[:2], lo[:2], hi[:2]), 256)
    assert behind is None


@pytest.mark.parametrize("face", range(6))
def test_cube_faces_cover_their_axis(face):
    fwd = lightspace.CUBE_FORWARDS[face]
    assert lightspace.cube_face(fwd * 3 + 0.1) == face
    view = lightspace.look_at((1, 2, 3), fwd)
    ndc = lightspace.transform_points(lightspace.perspective(np.pi / 2, 1, 0.1, 10) @ view, [(1, 2, 3) + fwd * 2])
    np.testing.assert_allclose(ndc[0, :2], 0, atol=1e-12)


def test_boxes_in_frustum_is_conservative():
    vp = lightspace.orthographic(-1, 1, -1, 1, 0.1, 10)
    inside = lightspace.box_corners((-0.5, -0.5, -2), (0.5, 0.5, -1))
    straddle = lightspace.box_corners((0.9, -0.1, -2), (3, 0.1, -1))
    outside = lightspace.box_corners((2, 2, -2), (3, 3, -1))
    behind = lightspace.box_corners((-0.5, -0.5, 1), (0.5, 0.5, 2))
    got = lightspace.boxes_in_frustum(vp, np.stack([inside, straddle, outside, behind]))
    assert got.tolist() == [True, True, False, False]


def test_sun_fit_to_view_covers_visible_receivers_and_their_casters():
    ground = lightspace.box_corners((-1000, -1000, -0.1), (1000, 1000, 0.0))
    caster = lightspace.box_corners((-0.5, -0.5, 1.0), (0.5, 0.5, 2.0))
    far_away = lightspace.box_corners((500, 500, 0), (501, 501, 1))
    view = lightspace.look_at((0, -10, 10), (0, 1, -1))
    cam = lightspace.orthographic(-4, 4, -4, 4, 0.1, 40) @ view
    fit, casters = lightspace.fit_sun_to_view(
        (0.2, 0.1, -1.0), np.stack([ground, caster, far_away]), lightspace.frustum_corners(cam), 1024
    )
    assert sorted(casters.tolist()) == [0, 1]  # the far box cannot shadow what the camera sees
    whole = lightspace.fit_sun_ortho((0.2, 0.1, -1.0), np.concatenate([ground, caster, far_away]), 1024)
    assert fit.texel < whole.texel / 50  # the view-fitted map is far sharper
    ndc = lightspace.transform_points(fit.view_proj, caster)
    assert np.all(np.abs(ndc) <= 1.0)


def _flat(lo, hi):
    return lightspace.box_corners(lo, hi)


def test_flat_ground_with_everything_on_it_casts_nothing():
    ground = _flat((-100, -100, 0), (100, 100, 0))
    standing = lightspace.box_corners((-1, -1, 0), (1, 1, 2))
    below = lightspace.box_corners((-1, -1, -3), (1, 1, -1))
    sun = (0.3, 0.2, -1.0)
    free = lightspace.flat_casters_without_shadow(np.stack([ground, standing]), sun)
    assert free.tolist() == [True, False]  # a solid box is never dropped
    # Something below the ground (a basement): the ground can shadow it.
    free = lightspace.flat_casters_without_shadow(np.stack([ground, standing, below]), sun)
    assert free.tolist() == [False, False, False]
    # A light from below shines at the ground's other side: now "behind" is above it.
    free = lightspace.flat_casters_without_shadow(np.stack([ground, standing]), (0.0, 0.0, 1.0))
    assert free.tolist() == [False, False]
    assert lightspace.flat_casters_without_shadow(np.stack([ground, below]), (0.0, 0.0, 1.0)).tolist() == [
        True,
        False,
    ]
    # Edge-on to the light, a wall's shadow has no area.
    wall = _flat((0, -5, 0), (0, 5, 3))
    assert lightspace.flat_casters_without_shadow(np.stack([wall, standing]), (0.0, 1.0, 0.0)).tolist() == [
        True,
        False,
    ]
    # A rotated flat box (its corners no longer axis-aligned) is still recognised.
    rot = np.array([[0.8, -0.6, 0.0], [0.6, 0.8, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
        [[1, 0, 0], [0, 0.6, -0.8], [0, 0.8, 0.6]]
    )
    tilted = ground @ rot.T
    free = lightspace.flat_casters_without_shadow(np.stack([tilted, standing + (0, 0, 200)]), -rot[:, 2])
    assert free.tolist() == [True, False]


def _flat_test_reference(boxes, direction=None, position=None):
    """The flat-caster test written for one light, as it was before a table kept its sides."""
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 8, 3)
    free = np.zeros(len(boxes), dtype=bool)
    edges = boxes[:, [1, 2, 4]] - boxes[:, [0]]
    lengths = np.linalg.norm(edges, axis=2)
    longest, thin, rows = lengths.max(axis=1), lengths.argmin(axis=1), np.arange(len(boxes))
    normal = np.cross(edges[rows, (thin + 1) % 3], edges[rows, (thin + 2) % 3])
    area = np.linalg.norm(normal, axis=1)
    flat = lightspace.flat_boxes(boxes) & (area > 1e-12 * longest**2) & np.isfinite(area)
    candidates = np.nonzero(flat)[0]
    candidates = candidates[np.argsort(-area[candidates])][: lightspace.MAX_FLAT_TESTS]
    light = lightspace.normalize(direction) if position is None else None
    for i in candidates:
        n = normal[i] / area[i]
        d = float(n @ boxes[i, 0])
        if light is not None:
            s = float(n @ light)
            grazing = abs(s) <= 1e-9
        else:
            s = d - float(n @ np.asarray(position, dtype=np.float64))
            grazing = abs(s) <= 1e-9 * max(1.0, abs(d))
        if grazing:
            free[i] = True
            continue
        reach = np.sign(s) * (boxes @ n - d)
        reach[i] = 0.0
        tolerance = 1e-5 * max(float(np.abs(boxes[i]).max()), longest[i])
        free[i] = not bool((reach.max(axis=1) > tolerance).any())
    return free


def test_one_flat_caster_table_answers_every_light_as_a_test_of_its_own():
    """A frame's samples each fit a map to a new direction of the world (or a light at a new
    point of itself) over the same boxes: ``FlatCasters`` keeps each flat box's two sides and
    answers every light exactly as a test made for that light alone."""
    rng = np.random.default_rng(7)
    boxes = []
    for k in range(40):  # grounds, walls and cards at random tilts and scales, and solids
        lo = rng.uniform(-5, 5, 3)
        size = rng.uniform(0.1, 4.0, 3)
        if k % 2 == 0:
            size[k % 3] = 0.0  # flat
        corners = lightspace.box_corners(lo, lo + size)
        if k % 4 == 0:
            q, _r = np.linalg.qr(rng.normal(size=(3, 3)))
            corners = corners @ q.T
        boxes.append(corners * 10.0 ** rng.integers(-3, 4))
    boxes.append(_flat((-100, -100, 0), (100, 100, 0)))
    boxes = np.stack(boxes)
    table = lightspace.FlatCasters(boxes)
    directions = [*rng.normal(size=(60, 3)), (0.0, 0.0, -1.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)]
    for direction in directions:
        expected = _flat_test_reference(boxes, direction)
        np.testing.assert_array_equal(table.free(direction), expected)
        np.testing.assert_array_equal(lightspace.flat_casters_without_shadow(boxes, direction), expected)
    for position in [*rng.uniform(-20, 20, size=(60, 3)), (0.0, 0.0, 0.0), (3.0, 3.0, 0.0)]:
        np.testing.assert_array_equal(table.free(position=position), _flat_test_reference(boxes, position=position))
    assert any(table.free((0.0, 0.0, -1.0))) and not all(table.free((0.0, 0.0, -1.0)))
    assert len(table._reaches) <= 2 * lightspace.MAX_FLAT_TESTS  # each side of each plane found once
    assert lightspace.FlatCasters(np.zeros((0, 8, 3))).free((0, 0, -1)).shape == (0,)


def test_hull_planes_and_clipped_points_of_a_box_crossing_a_frustum():
    cam = lightspace.orthographic(-1, 1, -1, 1, 1.0, 10.0)  # the box x, y in [-1, 1], z in [-10, -1]
    corners = lightspace.frustum_corners(cam)
    planes = lightspace.hull_planes(corners)
    assert planes.shape == (6, 4)
    np.testing.assert_allclose(np.linalg.norm(planes[:, :3], axis=1), 1.0)
    assert np.all(corners @ planes[:, :3].T <= planes[:, 3] + 1e-9)  # every corner inside every plane
    crossing = lightspace.box_corners((0.5, -3, -5), (4, 3, -4))
    inside = lightspace.box_corners((-0.5, -0.5, -3), (0.5, 0.5, -2))
    outside = lightspace.box_corners((5, 5, -3), (6, 6, -2))
    points, seen = lightspace.clipped_points(np.stack([crossing, inside, outside]), planes)
    assert seen.tolist() == [True, True, False]
    lo, hi = points.min(axis=0), points.max(axis=0)
    np.testing.assert_allclose(lo, (-0.5, -1.0, -5.0), atol=1e-9)  # the crossing box cut at x = 1, |y| = 1
    np.testing.assert_allclose(hi, (1.0, 1.0, -2.0), atol=1e-9)


def test_sun_fit_crops_to_the_casters_footprint_and_skips_a_flat_ground():
    ground = _flat((-1000, -1000, 0), (1000, 1000, 0))
    caster = lightspace.box_corners((-0.1, -0.1, 0.0), (0.1, 0.1, 0.3))
    view = lightspace.look_at((0, -10, 3), (0, 1, -0.1))  # looking out to the horizon
    cam = lightspace.perspective(np.radians(50), 1.5, 0.1, 500.0) @ view
    fit, casters = lightspace.fit_sun_to_view(
        (0.2, 0.5, -1.0), np.stack([ground, caster]), lightspace.frustum_corners(cam), 1024
    )
    assert casters.tolist() == [1]  # the flat ground is not drawn into the map
    assert fit.texel < 0.5 / 1024 * 2  # the map spans about the 0.2 x 0.4 m footprint, not the ground
    ndc = lightspace.transform_points(fit.view_proj, caster)
    assert np.all(np.abs(ndc[:, :2]) <= 1.0)
    # Nothing the camera sees can be shadowed (the caster is out of view and its shadow too).
    away = caster + (300.0, -300.0, 0.0)
    assert (
        lightspace.fit_sun_to_view((0.2, 0.5, -1.0), np.stack([ground, away]), lightspace.frustum_corners(cam), 1024)
        is None
    )


def test_off_center_perspective_maps_its_window_to_the_unit_square():
    m = lightspace.off_center_perspective(-0.2, 0.6, 0.1, 0.3, 0.5, 20.0)
    for u, v, z in [(-0.2, 0.1, 0.5), (0.6, 0.3, 20.0), (0.2, 0.2, 3.0)]:
        ndc = lightspace.transform_points(m, [(u * z, v * z, -z)])[0]
        expected = (2 * (u + 0.2) / 0.8 - 1, 2 * (v - 0.1) / 0.2 - 1)
        np.testing.assert_allclose(ndc[:2], expected, atol=1e-12)
    np.testing.assert_allclose(
        lightspace.transform_points(m, [(0, 0.2 * 0.5, -0.5), (0, 0.2 * 20, -20.0)])[:, 2], (-1, 1)
    )
    t = np.tan(np.radians(30))
    np.testing.assert_allclose(
        lightspace.off_center_perspective(-t, t, -t, t, 0.1, 9.0), lightspace.perspective(np.radians(60), 1.0, 0.1, 9.0)
    )


def test_local_light_maps_crop_to_what_the_camera_sees_and_the_casters_can_shadow():
    """A point light 5 m over a 2 km flat ground with a 20 cm box: the ground casts nothing, so
    the downward face covers the box's window (and its shadow in view), not the whole face."""
    from penumbra.engine.shadows.planning import Boxes, Crop, Eye, perspective_tile

    ground = _flat((-1000, -1000, 0), (1000, 1000, 0))
    box = lightspace.box_corners((0.4, -0.1, 0.0), (0.6, 0.1, 0.2))
    corners = np.stack([ground, box])
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    light = np.array([0.0, 0.0, 5.0])
    view = lightspace.look_at((3, -6, 4), (-3, 6, -4))
    cam = lightspace.perspective(np.radians(40), 1.5, 0.1, 100.0) @ view
    receivers = lightspace.visible_receivers(corners, cam)
    flat_free = lightspace.flat_casters_without_shadow(corners, position=light)
    assert flat_free.tolist() == [True, False]
    down = np.array([0.0, 0.0, -1.0])
    eye, boxes = Eye(light, down, np.pi / 2), Boxes(corners, lo, hi)
    full = perspective_tile(eye, boxes, 1024)
    tile = perspective_tile(eye, boxes, 1024, crop=Crop(receivers, flat_free))
    assert tile.casters.tolist() == [1]
    assert tile.fit.texel_per_distance < full.fit.texel_per_distance / 20  # the box spans ~0.05 of the 2.0 face
    ndc = lightspace.transform_points(tile.fit.view_proj, box)
    assert np.all(np.abs(ndc[:, :2]) <= 1.0)
    # Its shadow on the ground (along the rays from the light through the box) is in the map.
    shadow = light + (box - light) * (5.0 / (5.0 - box[:, 2:3]))
    assert np.all(np.abs(lightspace.transform_points(tile.fit.view_proj, shadow)[:, :2]) <= 1.0)
    assert np.all(lightspace.transform_points(tile.fit.view_proj, shadow)[:, 2] <= 1.0)  # before the far plane
    # Only the ground in reach: nothing to shadow, no map; the box out of view: no map either.
    assert perspective_tile(eye, Boxes(corners[:1], lo[:1], hi[:1]), 1024, crop=Crop(receivers, flat_free[:1])) is None
    away = lightspace.visible_receivers(
        corners, lightspace.perspective(np.radians(40), 1.5, 0.1, 100.0) @ lightspace.look_at((300, 0, 4), (1, 0, -0.2))
    )
    assert perspective_tile(eye, boxes, 1024, crop=Crop(away, flat_free)) is None


def _ground_and_boxes(rng, half, centres, sizes, count=8):
    """(count + 1, 8, 3): a flat ground 2 ``half`` wide and ``count`` boxes, their centres
    uniform in the box ``centres`` and their half sizes in ``sizes``."""
    boxes = [_flat((-half, -half, 0), (half, half, 0))] + [
        lightspace.box_corners(c - s, c + s)
        for c, s in zip(rng.uniform(*centres, (count, 3)), rng.uniform(*sizes, (count, 3)), strict=True)
    ]
    return np.stack(boxes)


@pytest.mark.parametrize("seed", range(5))
def test_a_sheared_sun_map_holds_what_each_sampled_direction_fits(seed):
    """A sun fitted once with a cone (``fit_sun_to_view(cone=)``) and ``sheared`` to a direction
    inside it: every point of a ray along that direction lands on one map position, and every
    receiver the camera sees and every caster that the direction's own fit holds lands inside
    the sheared map (x, y and depth), so a sample can shear the frame's map instead of fitting."""
    from penumbra.engine.frame.sampling import concentric_disk

    rng = np.random.default_rng(seed)
    corners = _ground_and_boxes(rng, 30.0, ((-6, -6, 0.5), (6, 6, 3.0)), (0.2, 1.5))
    view = lightspace.look_at((0, -14, 7), (0, 1, -0.5))
    frustum = lightspace.frustum_corners(lightspace.perspective(np.radians(50), 1.5, 0.1, 60.0) @ view)
    sun = lightspace.normalize(rng.uniform((-0.6, -0.6, -1.0), (0.6, 0.6, -0.4)))
    angle = np.radians(rng.uniform(0.5, 12.0))
    cone = np.tan(0.5 * angle)
    centre, _ = lightspace.fit_sun_to_view(sun, corners, frustum, 1024, cone=cone)
    u = lightspace.normalize(np.cross(sun, (0.3, 0.1, 0.9)))
    v = np.cross(sun, u)
    for x, y in [concentric_disk(*p) for p in rng.uniform(0, 1, (6, 2))] + [(1.0, 0.0), (0.0, -1.0)]:
        d = lightspace.normalize(sun + cone * (x * u + y * v))
        fit = lightspace.sheared(centre, d)
        p = rng.uniform((-5, -5, 0), (5, 5, 3), (20, 3))
        a = lightspace.transform_points(fit.view_proj, p)
        b = lightspace.transform_points(fit.view_proj, p - 7.0 * d)  # farther up the same ray
        np.testing.assert_allclose(a[:, :2], b[:, :2], atol=1e-9)
        assert np.all(b[:, 2] < a[:, 2])  # nearer the light: smaller depth
        own = lightspace.fit_sun_to_view(d, corners, frustum, 1024)
        if own is None:
            continue
        own_fit, own_casters = own
        # What the direction's own map spans on its receivers (its rectangle at the receivers'
        # depths), and its casters' corners below the near plane, must lie in the sheared map.
        parts, _seen = lightspace.view_parts(corners, frustum)
        seen = np.concatenate([q for q in parts if len(q)])
        inside_own = np.all(np.abs(lightspace.transform_points(own_fit.view_proj, seen)[:, :2]) <= 1.0, axis=1)
        got = lightspace.transform_points(fit.view_proj, seen[inside_own])
        assert np.all(np.abs(got[:, :2]) <= 1.0 + 1e-9), f"direction {d}: receivers outside the sheared map"
        assert np.all(got[:, 2] <= 1.0 + 1e-9), f"direction {d}: receivers beyond the sheared map's far plane"


@pytest.mark.parametrize("seed", range(5))
def test_a_moved_local_map_holds_what_each_point_of_the_light_plans(seed):
    """A spot's map planned once over the scene grown by the light's reach
    (``lightspace.dilated_boxes`` and ``dilated_receivers``, as a plan with ``FrameShare.reaches``
    does) and ``moved`` to a point of the light: every visible receiver the point's own map
    holds lands inside the moved map (x, y and depth), and its casters are among the planned
    ones, so a sample can move the frame's map instead of planning its own."""
    from penumbra.engine.shadows.planning import Boxes, Crop, Eye, perspective_tile

    rng = np.random.default_rng(seed)
    corners = _ground_and_boxes(rng, 20.0, ((-4, -4, 0.3), (4, 4, 2.0)), (0.1, 0.8))
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    view = lightspace.look_at((0, -12, 6), (0, 1, -0.5))
    receivers = lightspace.visible_receivers(corners, lightspace.perspective(np.radians(50), 1.5, 0.1, 60.0) @ view)
    position = rng.uniform((-3, -3, 5), (3, 3, 7))
    forward = lightspace.normalize(rng.uniform((-0.4, -0.4, -1.0), (0.4, 0.4, -1.0)))
    fov, size, reach = np.radians(rng.uniform(40, 100)), 1024, rng.uniform(0.1, 1.0)
    free = lightspace.flat_casters_without_shadow(corners, position=position)
    grown = lightspace.dilated_boxes(corners, reach)
    planned = perspective_tile(
        Eye(position, forward, fov),
        Boxes(grown, grown.min(axis=1), grown.max(axis=1)),
        size,
        crop=Crop(lightspace.dilated_receivers(receivers, reach), free),
    )
    assert planned is not None
    for _ in range(8):
        offset = rng.normal(size=3)
        offset *= reach * rng.uniform(0.0, 1.0) ** (1 / 3) / np.linalg.norm(offset)
        own = perspective_tile(
            Eye(position + offset, forward, fov), Boxes(corners, lo, hi), size, crop=Crop(receivers, free)
        )
        if own is None:
            continue
        fit = lightspace.moved(planned.fit, offset)
        assert set(own.casters.tolist()) <= set(planned.casters.tolist())
        held = (
            own.held
            if own.held is not None
            else np.concatenate(
                lightspace.pieces_in(light_bins.frustum_planes(own.fit.view_proj), receivers.whole, receivers.pieces)
            )
        )
        ndc = lightspace.transform_points(fit.view_proj, held)
        assert np.all(np.abs(ndc) <= 1.0 + 1e-6), f"offset {offset}: {np.abs(ndc).max(axis=0)}"
