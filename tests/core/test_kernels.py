"""Filter kernels and sample sequences: plain numpy, checked against hand-derived values."""

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.shadows import kernels  # noqa: E402


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
    # sigma = 5 / 5 = one texel: weights exp(-(dx^2 + dy^2) / 2), normalised (hand-derived:
    # centre 1 / (1 + 2 e^-0.5 + 2 e^-2)^2 = 0.1621).
    g = np.exp(-(np.arange(-2, 3) ** 2) / 2.0)
    np.testing.assert_allclose(grid, np.outer(g, g) / g.sum() ** 2, rtol=1e-12)
    assert grid[2, 2] == pytest.approx(0.1621, abs=1e-4)
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
