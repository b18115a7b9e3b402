"""Light-space maths and kernels: plain numpy, checked against hand-derived values."""

import numpy as np
import pytest

from conftest import load_penumbra

pen = load_penumbra()
from penumbra.engine import kernels, lightspace  # noqa: E402


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


def test_perspective_fit_covers_points_in_front_only():
    pts = np.array([[0, 0, -2.0], [0.5, 0.5, -6.0], [0, 0, 5.0]])  # the last is behind
    fit = lightspace.fit_perspective((0, 0, 0), (0, 0, -1), np.radians(90), pts, 256)
    assert fit.near <= 2.0 * 0.99 + 1e-12 and fit.far >= 6.0
    ndc = lightspace.transform_points(fit.view_proj, pts[:2])
    assert np.all(np.abs(ndc) <= 1.0)
    assert fit.texel_per_distance == pytest.approx(2.0 / 256)
    assert lightspace.fit_perspective((0, 0, 0), (0, 0, -1), 1.0, pts[2:], 256) is None


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


@pytest.mark.parametrize("radius", [0, 1, 3, 10, 64])
def test_gaussian_weights_normalised_and_match_reference(radius):
    w = kernels.gaussian_1d(radius)
    assert len(w) == 2 * radius + 1
    assert w.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(w, w[::-1])
    if radius:
        sigma = radius / 2.0
        x = np.arange(-radius, radius + 1)
        ref = np.exp(-(x**2) / (2 * sigma**2))
        np.testing.assert_allclose(w, ref / ref.sum(), rtol=1e-12)


def test_pcf_kernel_is_normalised_separable_gaussian():
    k = kernels.pcf_kernel(5)
    assert k.shape == (25, 3)
    assert k[:, 2].sum() == pytest.approx(1.0)
    grid = k[:, 2].reshape(5, 5)
    np.testing.assert_allclose(grid, np.outer(grid.sum(1), grid.sum(0)), rtol=1e-12)
    # Seed 000's hand-made 5x5 table: centre 0.1621, (1, 0) 0.0983, (2, 1) 0.0133.
    assert grid[2, 2] == pytest.approx(0.1621, abs=1e-4)
    assert grid[2, 3] == pytest.approx(0.0983, abs=1e-4)
    assert grid[3, 4] == pytest.approx(0.0133, abs=1e-4)
    assert kernels.pcf_kernel(4).shape == (25, 3)  # even sizes are made odd
    np.testing.assert_allclose(kernels.pcf_kernel(1), [[0, 0, 1]])


def test_jitter_disk_rings_outer_first_and_stratified():
    d = kernels.jitter_disk(size=8, samples=24, seed=3)
    assert d.shape == (8, 8, 24, 2)
    r = np.linalg.norm(d, axis=-1)
    assert r.max() <= 1.0
    rings = r.reshape(8, 8, 3, kernels.RING)
    # Ring 0 (evaluated first) lies outside ring 1, which lies outside ring 2 (equal areas).
    assert np.all(rings[..., 0, :] >= np.sqrt(2 / 3) - 1e-12)
    assert np.all((rings[..., 1, :] >= np.sqrt(1 / 3) - 1e-12) & (rings[..., 1, :] <= np.sqrt(2 / 3) + 1e-12))
    assert np.all(rings[..., 2, :] <= np.sqrt(1 / 3) + 1e-12)
    # Deterministic per seed, different per pixel.
    np.testing.assert_array_equal(d, kernels.jitter_disk(size=8, samples=24, seed=3))
    assert not np.allclose(d[0, 0], d[0, 1])
    # Samples cover the disk evenly: the mean offset is near the centre.
    assert np.abs(d.reshape(-1, 2).mean(axis=0)).max() < 0.02


def test_sun_fit_to_view_covers_visible_receivers_and_their_casters():
    ground = lightspace.box_corners((-1000, -1000, -0.1), (1000, 1000, 0.0))
    caster = lightspace.box_corners((-0.5, -0.5, 1.0), (0.5, 0.5, 2.0))
    far_away = lightspace.box_corners((500, 500, 0), (501, 501, 1))
    view = lightspace.look_at((0, -10, 10), (0, 1, -1))
    cam = lightspace.orthographic(-4, 4, -4, 4, 0.1, 40) @ view
    fit, casters = lightspace.fit_sun_to_view((0.2, 0.1, -1.0), np.stack([ground, caster, far_away]), lightspace.frustum_corners(cam), 1024)
    assert sorted(casters.tolist()) == [0, 1]  # the far box cannot shadow what the camera sees
    whole = lightspace.fit_sun_ortho((0.2, 0.1, -1.0), np.concatenate([ground, caster, far_away]), 1024)
    assert fit.texel < whole.texel / 50  # the view-fitted map is far sharper
    ndc = lightspace.transform_points(fit.view_proj, caster)
    assert np.all(np.abs(ndc) <= 1.0)
