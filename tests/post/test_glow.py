"""GLOW on the GPU against its numpy references (``glow.bright_pass``, ``glow.glow_reference``).

Images are float RGBA, row 0 at the bottom. Tolerances are stated per test; the GPU works in
float32 and the references in float64.
"""

import numpy as np
import pytest

from devkit.post import hdr_image, layer, run_layers


@pytest.mark.parametrize("radius", [0, 3, 12])
@pytest.mark.parametrize("square", [False, True])
def test_glow_matches_reference(penumbra, gpu_call, radius, square):
    from penumbra.engine.post.glow import glow_reference

    img = hdr_image(37, 53, radius)
    params = dict(threshold=1.2, knee=0.5, intensity=0.7, radius=radius, square_samples=square)
    out, stats = run_layers(gpu_call, img, [layer("GLOW", **params)])
    ref = glow_reference(img, 1.2, 0.5, 0.7, radius, square)
    # float32 sums of up to 25 taps of values up to 40 (1600 squared): measured relative error
    # <= 6e-7, absolute <= 9e-5 on squared highlights of ~1e3.
    np.testing.assert_allclose(out, ref, rtol=1e-5, atol=1e-5)
    np.testing.assert_array_equal(out[..., 3], img[..., 3])  # alpha untouched
    assert stats.post_passes == 2


@pytest.mark.parametrize("square", [False, True])
def test_glow_adds_bright_pass_energy_times_intensity(penumbra, gpu_call, square):
    """Away from the edges the blur is normalised: the light added is exactly the bright-pass
    energy times the intensity, spread over the neighbourhood."""
    from penumbra.engine.post.glow import bright_pass

    img = np.zeros((64, 64, 4), np.float32)
    img[32, 32] = (10.0, 5.0, 2.0, 1.0)  # b = 10 -> contribution (10 - 1) / 10 = 0.9
    img[20, 40] = (3.0, 3.0, 3.0, 1.0)
    img[40, 25] = (0.5, 0.5, 0.5, 1.0)  # below threshold - knee: adds nothing
    intensity = 0.8
    glow = layer("GLOW", threshold=1.0, knee=0.5, intensity=intensity, radius=8, square_samples=square)
    out, _ = run_layers(gpu_call, img, [glow])
    bright = bright_pass(img[..., :3], 1.0, 0.5)
    if square:
        bright = bright * bright
    added = (out[..., :3].astype(np.float64) - img[..., :3]).sum(axis=(0, 1))
    np.testing.assert_allclose(added, intensity * bright.sum(axis=(0, 1)), rtol=1e-5)
    if not square:
        np.testing.assert_allclose(bright[32, 32], (9.0, 4.5, 1.8), rtol=1e-6)
    assert out[32, 36, 0] > 0.0 and out[28, 32, 0] > 0.0  # spread in both directions
    assert out[32, 32, 0] < 10.0 + intensity * 9.0  # and not all kept at the centre


def test_glow_bright_pass_threshold_and_knee(penumbra, gpu_call):
    """Radius 0 adds the bright-pass itself: check the curve along an HDR ramp."""
    from penumbra.engine.post.glow import bright_pass

    w = 256
    b = np.linspace(0.0, 3.0, w)
    img = np.zeros((2, w, 4), np.float32)
    img[0, :, :3] = b[:, None] * np.array([1.0, 0.5, 0.25])  # b is the red component
    img[1, :, :3] = b[:, None]
    img[..., 3] = 1.0
    threshold, knee_fraction, intensity = 1.5, 0.4, 2.0
    knee = threshold * knee_fraction  # 0.6: the soft region is [0.9, 2.1]
    soft, _ = run_layers(
        gpu_call, img, [layer("GLOW", threshold=threshold, knee=knee_fraction, intensity=intensity, radius=0)]
    )
    hard, _ = run_layers(gpu_call, img, [layer("GLOW", threshold=threshold, knee=0.0, intensity=intensity, radius=0)])
    added = (soft[..., :3] - img[..., :3]) / intensity
    added_hard = (hard[..., :3] - img[..., :3]) / intensity
    np.testing.assert_allclose(added, bright_pass(img[..., :3], threshold, knee), atol=2e-6)
    lo, hi = b <= threshold - knee, b >= threshold + knee
    assert np.all(added[:, lo] == 0.0)
    expected_hi = img[:, hi, :3] * ((b[hi] - threshold) / b[hi])[None, :, None]
    np.testing.assert_allclose(added[:, hi], expected_hi, atol=2e-6)
    knee_zone = ~lo & ~hi
    assert np.all(added[:, knee_zone, 0] > 0.0)
    assert np.all(np.diff(added[1, :, 0]) >= -1e-6)  # the curve is monotonic in b
    # At the threshold the quadratic knee gives knee / 4 (value, not fraction) of light.
    np.testing.assert_allclose(bright_pass(np.array([1.5, 0.0, 0.0]), threshold, knee)[0], knee / 4, rtol=1e-4)
    # Knee 0 is a hard cut: nothing at or below the threshold, b - threshold above.
    assert np.all(added_hard[:, b <= threshold] == 0.0)
    above = b > threshold
    np.testing.assert_allclose(added_hard[1, above, 0], b[above] - threshold, atol=2e-6)


def test_glow_extremes(penumbra, gpu_call):
    from penumbra.engine.post.glow import glow_reference

    img = hdr_image(20, 30, 7)
    same, stats = run_layers(gpu_call, img, [layer("GLOW", intensity=0.0, radius=4)])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0  # intensity 0 is the identity
    dark, stats = run_layers(gpu_call, img, [layer("GLOW", threshold=1e6, radius=4)])
    np.testing.assert_array_equal(dark, img)  # nothing passes: exactly the input
    assert stats.post_passes == 2
    strong, _ = run_layers(gpu_call, img, [layer("GLOW", threshold=1.0, knee=0.5, intensity=100.0, radius=5)])
    np.testing.assert_allclose(strong, glow_reference(img, 1.0, 0.5, 100.0, 5), rtol=1e-5, atol=1e-4)
    wide, _ = run_layers(
        gpu_call, img, [layer("GLOW", threshold=1.0, knee=0.5, intensity=1.0, radius=256)]
    )  # kernel >> image
    np.testing.assert_allclose(wide, glow_reference(img, 1.0, 0.5, 1.0, 256), rtol=1e-5, atol=1e-5)
    everything, _ = run_layers(
        gpu_call, img, [layer("GLOW", threshold=0.0, knee=0.5, intensity=1.0, radius=3)]
    )  # threshold 0
    np.testing.assert_allclose(everything, glow_reference(img, 0.0, 0.5, 1.0, 3), rtol=1e-5, atol=1e-5)


def test_glow_on_a_single_pixel(penumbra, gpu_call):
    img = np.array([[[4.0, 2.0, 1.0, 0.5]]], np.float32)
    out, _ = run_layers(gpu_call, img, [layer("GLOW", threshold=1.0, knee=0.5, intensity=0.5, radius=16)])
    # Clamp-to-edge: every tap is the pixel itself, so the glow is its bright-pass, 3/4 of it.
    np.testing.assert_allclose(out[0, 0], (4.0 + 1.5, 2.0 + 0.75, 1.0 + 0.375, 0.5), rtol=1e-6)


def test_nan_and_inf_do_not_spread_through_glow(penumbra, gpu_call):
    from penumbra.engine.post.glow import glow_reference

    img = np.full((32, 32, 4), 2.0, np.float32)
    img[10, 10] = np.nan
    img[20, 20, 0] = np.inf
    img[5, 25, 1] = -np.inf
    out, _ = run_layers(gpu_call, img, [layer("GLOW", threshold=1.0, knee=0.5, intensity=1.0, radius=6)])
    assert np.all(np.isfinite(out))
    # Non-finite components count as 0, in the source and in every blur tap.
    np.testing.assert_allclose(out, glow_reference(img, 1.0, 0.5, 1.0, 6), rtol=1e-5, atol=1e-5)
    assert out[0, 0, 0] == pytest.approx(2.0 + 1.0)  # far away: 2 + bright-pass (2 - 1)


@pytest.mark.parametrize("shape", [(37, 53), (36, 52), (1, 1), (2, 7)])
@pytest.mark.parametrize("radius", [0, 5, 16])
def test_half_resolution_glow_matches_its_reference(penumbra, gpu_call, shape, radius):
    """The half-size path (odd and even sizes, a single pixel) against its exact reference:
    four passes, the same tolerance as the full-size path."""
    from penumbra.engine.post.glow import glow_reference

    img = hdr_image(*shape, radius + 1)
    params = dict(threshold=1.2, knee=0.5, intensity=0.7, radius=radius, square_samples=radius == 5)
    out, stats = run_layers(gpu_call, img, [layer("GLOW", half_resolution=True, **params)])
    ref = glow_reference(img, 1.2, 0.5, 0.7, radius, radius == 5, half_resolution=True)
    np.testing.assert_allclose(out, ref, rtol=1e-5, atol=1e-5)
    np.testing.assert_array_equal(out[..., 3], img[..., 3])
    assert stats.post_passes == 4


def test_half_resolution_glow_is_close_to_the_exact_one_and_keeps_its_energy(penumbra, gpu_call):
    """What half resolution trades: on scattered HDR highlights at the default radius 16 the
    added light differs from the full-size glow's by at most 4 % of that glow's peak (measured
    2.6 %), and its total is the same to 1 % (measured 1e-8: the highlights are far from the
    edges, where both blurs are normalised)."""
    from penumbra.engine.post.glow import glow_reference

    rng = np.random.default_rng(7)
    img = np.full((96, 128, 4), 0.2, np.float32)
    img[..., 3] = 1.0
    for y, x in rng.integers(24, (72, 104), size=(12, 2)):
        img[y : y + 2, x : x + 3, :3] = rng.uniform(2.0, 20.0, 3)
    params = dict(threshold=1.0, knee=0.5, intensity=0.6, radius=16)
    half, _ = run_layers(gpu_call, img, [layer("GLOW", half_resolution=True, **params)])
    full = glow_reference(img, 1.0, 0.5, 0.6, 16)
    added_full = full[..., :3] - img[..., :3]
    added_half = half[..., :3].astype(np.float64) - img[..., :3]
    assert np.abs(added_half - added_full).max() <= 0.04 * added_full.max()
    np.testing.assert_allclose(added_half.sum(axis=(0, 1)), added_full.sum(axis=(0, 1)), rtol=0.01)


@pytest.mark.parametrize("shape", [(1, 300), (300, 1), (3, 5)])
def test_half_resolution_glow_at_the_widest_radius(penumbra, gpu_call, shape):
    """Radius 256 (the most) over images far smaller than the kernel, and one-pixel-wide
    strips: the half-size path still matches its reference."""
    from penumbra.engine.post.glow import glow_reference

    img = hdr_image(*shape, 11)
    params = dict(threshold=0.5, knee=1.0, intensity=40.0, radius=256)
    out, _ = run_layers(gpu_call, img, [layer("GLOW", half_resolution=True, **params)])
    np.testing.assert_allclose(
        out, glow_reference(img, 0.5, 1.0, 40.0, 256, half_resolution=True), rtol=1e-5, atol=1e-4
    )
