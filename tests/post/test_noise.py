"""NOISE on the GPU against its numpy reference (``noise.grain_reference``)."""

import numpy as np

from devkit.post import hdr_image, layer, run_layers, run_stack


def test_noise_is_deterministic_per_frame_and_matches_reference(penumbra, gpu_call):
    from penumbra.engine.post.noise import apply_reference, grain_reference

    img = hdr_image(40, 50, 8)
    grain = layer("NOISE", amount=0.2, size=1, monochrome=False, seed=3)
    (a, stats), (b, _), (c, _), (d, _) = run_stack(gpu_call, img, [grain], frames=[7, 7, 8, -5])
    np.testing.assert_array_equal(a, b)  # the same frame gives identical pixels
    assert np.mean(a[..., :3] != c[..., :3]) > 0.99  # another frame gives other grain
    assert stats.post_passes == 1
    for out, frame in ((a, 7), (c, 8), (d, -5)):
        ref = apply_reference(img, 0.2, grain_reference(50, 40, frame, 1, 3, False))
        # One float32 addition: measured 1.6e-6 absolute on a 34.0 pixel, i.e. half an ulp.
        np.testing.assert_allclose(out, ref, rtol=1e-7, atol=1e-6)
    np.testing.assert_array_equal(a[..., 3], img[..., 3])


def test_noise_grain_is_zero_mean_and_uniform(penumbra, gpu_call):
    h = w = 256
    amount = 0.3
    img = np.full((h, w, 4), 0.5, np.float32)
    runs = run_stack(gpu_call, img, [layer("NOISE", amount=amount, size=1, monochrome=False)], frames=[1, 2])
    n = h * w
    sigma_mean = amount / np.sqrt(3 * n)  # standard deviation of the mean of n uniform draws
    for out, _ in runs:
        g = out[..., :3].astype(np.float64) - 0.5
        assert np.all(np.abs(g) <= amount + 1e-6)
        # 5 sigma = 0.0029 for amount 0.3; the measured channel means lie within 2.3 sigma.
        assert np.all(np.abs(g.mean(axis=(0, 1))) < 5 * sigma_mean)
        np.testing.assert_allclose(g.var(axis=(0, 1)), amount**2 / 3, rtol=0.03)
        hist, _ = np.histogram(g[..., 0], bins=10, range=(-amount, amount))
        assert hist.min() > 0.9 * n / 10 and hist.max() < 1.1 * n / 10
        corr = np.corrcoef(g[..., 0].ravel(), g[..., 1].ravel())[0, 1]
        assert abs(corr) < 0.02  # colour grain: channels independent
        neighbour = np.corrcoef(g[:, :-1, 0].ravel(), g[:, 1:, 0].ravel())[0, 1]
        assert abs(neighbour) < 0.02


def test_noise_size_monochrome_and_seed(penumbra, gpu_call):
    img = np.full((24, 30, 4), 1.0, np.float32)
    big, _ = run_layers(gpu_call, img, [layer("NOISE", amount=0.5, size=4, monochrome=True)])
    g = big[..., :3] - 1.0
    np.testing.assert_array_equal(g[..., 0], g[..., 1])  # monochrome: one value for R, G, B
    np.testing.assert_array_equal(g[..., 0], g[..., 2])
    per_cell = g[::4, ::4, 0]  # 6 x 8 cells, the last column of cells 2 pixels wide
    np.testing.assert_array_equal(g[..., 0], np.repeat(np.repeat(per_cell, 4, 0), 4, 1)[:24, :30])
    assert len(np.unique(per_cell)) == per_cell.size  # and the cells differ
    seeds = [
        run_layers(gpu_call, img, [layer("NOISE", amount=0.5, size=1, monochrome=True, seed=s)])[0] for s in (0, 1)
    ]
    assert np.mean(seeds[0] != seeds[1]) > 0.7  # alpha (untouched) is a quarter of the values


def test_noise_never_takes_light_below_zero(penumbra, gpu_call):
    """Grain on black and on a dark ramp: no channel goes below zero, black stays black, and
    the grain is still zero-mean where the image is darker than it (no brightening)."""
    h, w = 128, 128
    img = np.zeros((h, w, 4), np.float32)
    img[..., 3] = 1.0
    img[:, w // 2 :, :3] = 0.02  # right half: darker than the grain's amount
    out, _ = run_stack(gpu_call, img, [layer("NOISE", amount=0.3, size=1, monochrome=False)], frames=[5])[0]
    assert float(out[..., :3].min()) >= 0.0
    np.testing.assert_array_equal(out[:, : w // 2, :3], 0.0)
    dark = out[:, w // 2 :, :3].astype(np.float64)
    # Grain of amplitude 0.02 (the channel's own value): uniform in (0, 0.04), mean 0.02 within
    # 5 sigma of the mean of its draws.
    assert dark.max() <= 0.04 + 1e-7
    assert abs(dark.mean() - 0.02) < 5 * 0.02 / np.sqrt(3 * dark.size)


def test_noise_extremes(penumbra, gpu_call):
    from penumbra.engine.post.noise import apply_reference, grain_reference

    img = hdr_image(16, 16, 9)
    same, stats = run_layers(gpu_call, img, [layer("NOISE", amount=0.0, monochrome=False)])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0
    loud, _ = run_stack(gpu_call, img, [layer("NOISE", amount=10.0, size=1, monochrome=False)], frames=[42])[0]
    np.testing.assert_allclose(loud, apply_reference(img, 10.0, grain_reference(16, 16, 42)), atol=1e-5)
    one_cell, _ = run_layers(gpu_call, img * 0 + 1, [layer("NOISE", amount=0.5, size=10000, monochrome=False)])
    assert len(np.unique(one_cell[..., 0])) == 1  # grain larger than the image: one value
    pixel = np.array([[[1.0, 1.0, 1.0, 1.0]]], np.float32)
    out, _ = run_stack(gpu_call, pixel, [layer("NOISE", amount=0.25, monochrome=False)], frames=[3])[0]
    np.testing.assert_allclose(out[0, 0, :3], 1.0 + 0.25 * grain_reference(1, 1, 3)[0, 0], atol=1e-7)
