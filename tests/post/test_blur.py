"""BLUR on the GPU against its numpy reference (``blur.gaussian_reference``)."""

import numpy as np
import pytest

from devkit.post import layer, run_layers


@pytest.mark.parametrize("radius", [1, 5, 20])
def test_blur_matches_gaussian_convolution(penumbra, gpu_call, radius):
    from penumbra.engine.post.blur import gaussian_reference

    rng = np.random.default_rng(radius)
    img = rng.uniform(0, 4, (37, 53, 4)).astype(np.float32)  # HDR values, odd sizes
    img[18, 26] = (50.0, 0.0, 10.0, 1.0)  # an HDR impulse
    out, stats = run_layers(gpu_call, img, [layer("BLUR", radius=radius, sigma=0.0)])
    np.testing.assert_allclose(out, gaussian_reference(img, radius), rtol=1e-5, atol=1e-5)
    assert stats.post_passes == 2


def test_blur_preserves_energy_of_an_impulse(penumbra, gpu_call):
    img = np.zeros((64, 64, 4), np.float32)
    img[32, 32] = 1000.0
    out, _ = run_layers(gpu_call, img, [layer("BLUR", radius=8, sigma=0.0)])
    assert out[..., 0].sum() == pytest.approx(1000.0, rel=1e-5)


def test_nan_and_inf_do_not_spread_through_blur(penumbra, gpu_call):
    img = np.ones((32, 32, 4), np.float32)
    img[10, 10] = np.nan
    img[20, 20] = np.inf
    out, _ = run_layers(gpu_call, img, [layer("BLUR", radius=6, sigma=0.0)])
    assert np.all(np.isfinite(out))
    assert out[0, 0, 0] == pytest.approx(1.0)
