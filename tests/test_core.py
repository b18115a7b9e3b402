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
    view, proj, texel = lightspace.fit_sun_ortho(d, pts, 1024)
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
        assert b[2] == pytest.approx(a[2] * s, rel=0.2)
        ndc_a = lightspace.transform_points(a[1] @ a[0], pts)
        ndc_b = lightspace.transform_points(b[1] @ b[0], pts * s)
        assert np.all(np.abs(ndc_b) <= 1.0)
        np.testing.assert_allclose(ndc_b[:, 2], ndc_a[:, 2], atol=0.05)


def test_sun_fit_empty_and_nonfinite():
    assert lightspace.fit_sun_ortho((0, 0, -1), np.zeros((0, 3)), 512) is None
    assert lightspace.fit_sun_ortho((0, 0, -1), [[np.nan, 0, 0]], 512) is None
    one = lightspace.fit_sun_ortho((0, 0, -1), [[1, 2, 3]], 1)
    assert one is not None and all(np.all(np.isfinite(m)) for m in one[:2])


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
