"""GLOW, SCANLINES, SEPIA, PIXELATE and NOISE on the GPU against numpy references.

Images are float RGBA, row 0 at the bottom. Tolerances are stated per test; the GPU works in
float32 and the references in float64.
"""

from types import SimpleNamespace

import numpy as np
import pytest

import scenes
from test_post import gaussian_reference, run_layers, run_stack


def run_frames(gpu_call, image, layers, frames):
    """The stack once per frame number in ``frames``; returns [(array, stats)]."""
    return run_stack(gpu_call, image, layers, frames=frames)


def run_frame(gpu_call, image, layers, frame):
    return run_frames(gpu_call, image, layers, [frame])[0]


# --- layer builders ----------------------------------------------------------------------


def glow_layer(threshold=1.0, knee=0.5, intensity=0.5, radius=4, square_samples=False, mix=1.0):
    p = SimpleNamespace(threshold=threshold, knee=knee, intensity=intensity, radius=radius, square_samples=square_samples)
    return ("GLOW", True, mix, p)


def scanlines_layer(count=16, thickness=0.5, intensity=0.5, scroll_speed=0.0, antialias=True, mix=1.0):
    p = SimpleNamespace(count=count, thickness=thickness, intensity=intensity, scroll_speed=scroll_speed, antialias=antialias)
    return ("SCANLINES", True, mix, p)


def sepia_layer(amount=1.0, mix=1.0):
    return ("SEPIA", True, mix, SimpleNamespace(amount=amount))


def pixelate_layer(size=4, sampling="CENTER", mix=1.0):
    return ("PIXELATE", True, mix, SimpleNamespace(size=size, sampling=sampling))


def noise_layer(amount=0.1, size=1, monochrome=False, seed=0, mix=1.0):
    return ("NOISE", True, mix, SimpleNamespace(amount=amount, size=size, monochrome=monochrome, seed=seed))


def hdr_image(h, w, seed, highlights=6):
    """Random colours in [0, 1.5) with a few HDR highlights (up to 40) and alpha in [0, 1)."""
    rng = np.random.default_rng(seed)
    img = rng.uniform(0.0, 1.5, (h, w, 4)).astype(np.float32)
    img[..., 3] = rng.uniform(0.0, 1.0, (h, w))
    for _ in range(highlights):
        y, x = rng.integers(0, h), rng.integers(0, w)
        img[y, x, :3] = rng.uniform(5.0, 40.0, 3)
    return img


# --- GLOW --------------------------------------------------------------------------------


def glow_reference(img, threshold, knee, intensity, radius, square_samples=False):
    """``img`` rgb + intensity * Gaussian(bright-pass), alpha kept; non-finite input -> 0."""
    from penumbra.engine.post.glow import bright_pass

    clean = np.where(np.isfinite(img), img, 0.0).astype(np.float64)
    bright = bright_pass(clean[..., :3], threshold, threshold * knee)
    if square_samples:
        bright = bright * bright
    padded = np.concatenate([bright, np.zeros_like(bright[..., :1])], -1)
    out = clean.copy()
    out[..., :3] += intensity * gaussian_reference(padded, radius)[..., :3]
    return out


@pytest.mark.parametrize("radius", [0, 3, 12])
@pytest.mark.parametrize("square", [False, True])
def test_glow_matches_reference(penumbra, gpu_call, radius, square):
    img = hdr_image(37, 53, radius)
    out, stats = run_layers(gpu_call, img, [glow_layer(1.2, 0.5, 0.7, radius, square)])
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
    out, _ = run_layers(gpu_call, img, [glow_layer(1.0, 0.5, intensity, 8, square)])
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
    soft, _ = run_layers(gpu_call, img, [glow_layer(threshold, knee_fraction, intensity, 0)])
    hard, _ = run_layers(gpu_call, img, [glow_layer(threshold, 0.0, intensity, 0)])
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
    img = hdr_image(20, 30, 7)
    same, stats = run_layers(gpu_call, img, [glow_layer(intensity=0.0)])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0  # intensity 0 is the identity
    dark, stats = run_layers(gpu_call, img, [glow_layer(threshold=1e6)])
    np.testing.assert_array_equal(dark, img)  # nothing passes: exactly the input
    assert stats.post_passes == 2
    strong, _ = run_layers(gpu_call, img, [glow_layer(1.0, 0.5, 100.0, 5)])
    np.testing.assert_allclose(strong, glow_reference(img, 1.0, 0.5, 100.0, 5), rtol=1e-5, atol=1e-4)
    wide, _ = run_layers(gpu_call, img, [glow_layer(1.0, 0.5, 1.0, 256)])  # kernel >> image
    np.testing.assert_allclose(wide, glow_reference(img, 1.0, 0.5, 1.0, 256), rtol=1e-5, atol=1e-5)
    everything, _ = run_layers(gpu_call, img, [glow_layer(0.0, 0.5, 1.0, 3)])  # threshold 0
    np.testing.assert_allclose(everything, glow_reference(img, 0.0, 0.5, 1.0, 3), rtol=1e-5, atol=1e-5)


def test_glow_on_a_single_pixel(penumbra, gpu_call):
    img = np.array([[[4.0, 2.0, 1.0, 0.5]]], np.float32)
    out, _ = run_layers(gpu_call, img, [glow_layer(1.0, 0.5, 0.5, 16)])
    # Clamp-to-edge: every tap is the pixel itself, so the glow is its bright-pass, 3/4 of it.
    np.testing.assert_allclose(out[0, 0], (4.0 + 1.5, 2.0 + 0.75, 1.0 + 0.375, 0.5), rtol=1e-6)


def test_nan_and_inf_do_not_spread_through_glow(penumbra, gpu_call):
    img = np.full((32, 32, 4), 2.0, np.float32)
    img[10, 10] = np.nan
    img[20, 20, 0] = np.inf
    img[5, 25, 1] = -np.inf
    out, _ = run_layers(gpu_call, img, [glow_layer(1.0, 0.5, 1.0, 6)])
    assert np.all(np.isfinite(out))
    # Non-finite components count as 0, in the source and in every blur tap.
    np.testing.assert_allclose(out, glow_reference(img, 1.0, 0.5, 1.0, 6), rtol=1e-5, atol=1e-5)
    assert out[0, 0, 0] == pytest.approx(2.0 + 1.0)  # far away: 2 + bright-pass (2 - 1)


# --- SCANLINES ---------------------------------------------------------------------------


def scanlines_reference(img, count, thickness, intensity, speed, frame, antialias):
    from penumbra.engine.post.scanlines import scanline_darkness, scroll_offset

    h = img.shape[0]
    dark = scanline_darkness(np.arange(h), h, count, thickness, scroll_offset(frame, speed), antialias)
    out = img.astype(np.float64).copy()
    out[..., :3] *= (1.0 - intensity * dark)[:, None, None]
    return out, dark


SCANLINE_CASES = [
    # count, thickness, intensity, speed, frame, antialias
    (16, 0.5, 0.8, 0.0, 0, False),  # period 4 px, two dark rows out of four
    (16, 0.5, 0.8, 0.0, 0, True),  # aligned bands: same as above
    (10, 0.3, 0.6, 0.25, 3, True),  # period 6.4 px: fractional coverage at band edges
    (7, 0.65, 1.0, -0.37, 11, True),
    (24, 0.4, 0.7, 0.13, 5, False),
    (200, 0.3, 0.5, 0.0, 0, True),  # period < 1 px: every row averages to ~thickness
    (1, 0.25, 0.9, 1.37, 100003, True),  # one line, large frame * speed
]


@pytest.mark.parametrize("case", SCANLINE_CASES)
def test_scanlines_row_profile_matches_reference(penumbra, gpu_call, case):
    count, thickness, intensity, speed, frame, antialias = case
    h, w = 64, 40
    img = np.ones((h, w, 4), np.float32)
    img[..., :3] *= np.linspace(0.1, 4.0, w)[None, :, None]  # HDR gradient across the rows
    out, stats = run_frame(gpu_call, img, [scanlines_layer(count, thickness, intensity, speed, antialias)], frame)
    ref, dark = scanlines_reference(img, count, thickness, intensity, speed, frame, antialias)
    if not antialias:
        # Point sampling is discontinuous: the cases keep every row centre away from an edge.
        from penumbra.engine.post.scanlines import scroll_offset

        u = (np.arange(h) + 0.5) * count / h - scroll_offset(frame, speed)
        f = u - np.floor(u)
        assert np.min(np.abs(f - thickness)) > 1e-3 and np.min(np.minimum(f, 1 - f)) > 1e-3
        assert set(np.unique(dark)) <= {0.0, 1.0}
    # The row profile (output / input): float32 phase and coverage, measured max error 9e-7
    # (at band edges with a 9-pixel period; 3e-8 where bands are pixel-aligned).
    profile = out[..., :3] / img[..., :3]
    np.testing.assert_allclose(profile, np.broadcast_to((1.0 - intensity * dark)[:, None, None], profile.shape), rtol=0, atol=2e-6)
    np.testing.assert_allclose(out, ref, rtol=0, atol=8e-6)  # the same, for values up to 4
    np.testing.assert_array_equal(out[..., 3], img[..., 3])
    assert stats.post_passes == 1
    assert 0.0 <= dark.min() and dark.max() <= 1.0
    if antialias and h % count == 0:
        # Box filtering conserves the band area: over whole periods the mean is the thickness.
        assert dark.mean() == pytest.approx(thickness, abs=1e-12)
        assert (1.0 - profile.mean()) / intensity == pytest.approx(thickness, abs=2e-6)


def test_scanlines_aligned_profile_by_hand(penumbra, gpu_call):
    """count 16 over 64 rows: rows 4k, 4k+1 dark, 4k+2, 4k+3 bright; scrolling 1/4 line per
    frame moves the pattern up one pixel per frame."""
    img = np.full((64, 8, 4), 2.0, np.float32)
    runs = run_frames(gpu_call, img, [scanlines_layer(16, 0.5, 0.75, 0.25, antialias=True)], [0, 1, 1, 2])
    rows = [r[0][:, 0, 0] for r in runs]
    expected = np.where(np.arange(64) % 4 < 2, 2.0 * 0.25, 2.0)
    np.testing.assert_allclose(rows[0], expected, atol=1e-6)
    np.testing.assert_allclose(rows[1], np.roll(expected, 1), atol=1e-6)
    np.testing.assert_array_equal(rows[1], rows[2])  # same frame, same pixels
    np.testing.assert_allclose(rows[3], np.roll(expected, 2), atol=1e-6)


def test_scanlines_extremes(penumbra, gpu_call):
    img = hdr_image(30, 20, 2)
    for layer in (scanlines_layer(intensity=0.0), scanlines_layer(thickness=0.0)):
        out, stats = run_layers(gpu_call, img, [layer])
        np.testing.assert_array_equal(out, img)
        assert stats.post_passes == 0
    full, _ = run_layers(gpu_call, img, [scanlines_layer(9, 1.0, 0.6)])  # all dark
    np.testing.assert_allclose(full[..., :3], img[..., :3] * 0.4, rtol=1e-6)
    # 100000 lines over 30 rows: each pixel box-filters 3333.3 periods, so its darkness is
    # the thickness up to a part of one period in 3333 (|dark - 0.3| <= 0.3 / 3333).
    dense, _ = run_layers(gpu_call, img, [scanlines_layer(100000, 0.3, 1.0)])
    ref, dark = scanlines_reference(img, 100000, 0.3, 1.0, 0.0, 0, True)
    np.testing.assert_allclose(dense[..., :3] / img[..., :3], ref[..., :3] / img[..., :3], rtol=0, atol=2e-6)
    assert np.all(np.abs(dark - 0.3) <= 0.3 / 3333)
    one = np.array([[[2.0, 1.0, 0.5, 1.0]]], np.float32)
    out, _ = run_layers(gpu_call, one, [scanlines_layer(1, 0.3, 0.5)])
    np.testing.assert_allclose(out[0, 0], (2.0 * 0.85, 0.85, 0.5 * 0.85, 1.0), rtol=1e-6)


# --- SEPIA -------------------------------------------------------------------------------


@pytest.mark.parametrize("amount", [1.0, 0.37])
def test_sepia_matrix_exact(penumbra, gpu_call, amount):
    from penumbra.engine.post.sepia import SEPIA_MATRIX

    m = np.array(SEPIA_MATRIX)
    np.testing.assert_array_equal(m[0], (0.393, 0.769, 0.189))
    img = hdr_image(23, 31, 5)
    out, stats = run_layers(gpu_call, img, [sepia_layer(amount)])
    rgb = img[..., :3].astype(np.float64)
    ref = rgb + amount * (rgb @ m.T - rgb)
    np.testing.assert_allclose(out[..., :3], ref, rtol=1e-6, atol=1e-5)
    np.testing.assert_array_equal(out[..., 3], img[..., 3])
    assert stats.post_passes == 1


def test_sepia_extremes(penumbra, gpu_call):
    img = np.array([[[1.0, 1.0, 1.0, 1.0], [0.0, 0.0, 0.0, 0.5]]], np.float32)
    out, _ = run_layers(gpu_call, img, [sepia_layer(1.0)])
    np.testing.assert_allclose(out[0, 0], (1.351, 1.203, 0.937, 1.0), atol=1e-6)  # not clamped
    np.testing.assert_array_equal(out[0, 1], (0.0, 0.0, 0.0, 0.5))
    same, stats = run_layers(gpu_call, img, [sepia_layer(0.0)])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0
    one, _ = run_layers(gpu_call, img[:, :1] * 3.0, [sepia_layer(1.0)])
    np.testing.assert_allclose(one[0, 0, :3], 3.0 * np.array([1.351, 1.203, 0.937]), atol=1e-5)


# --- PIXELATE ----------------------------------------------------------------------------


def pixelate_reference(img, size, sampling):
    """Cells anchored at (0, 0); CENTER: pixel origin + n // 2 of the existing n; AVERAGE: mean."""
    h, w = img.shape[:2]
    clean = np.where(np.isfinite(img), img, 0.0).astype(np.float64)
    out = np.empty_like(clean)
    for y0 in range(0, h, size):
        for x0 in range(0, w, size):
            cell = clean[y0 : y0 + size, x0 : x0 + size]
            if sampling == "CENTER":
                value = cell[cell.shape[0] // 2, cell.shape[1] // 2]
            else:
                value = cell.mean(axis=(0, 1))
            out[y0 : y0 + size, x0 : x0 + size] = value
    return out


@pytest.mark.parametrize("size", [2, 3, 4, 7, 16])
def test_pixelate_center_matches_reference(penumbra, gpu_call, size):
    img = hdr_image(23, 37, size)  # neither side a multiple of most sizes: partial edge cells
    out, stats = run_layers(gpu_call, img, [pixelate_layer(size, "CENTER")])
    np.testing.assert_array_equal(out, pixelate_reference(img, size, "CENTER").astype(np.float32))
    assert stats.post_passes == 1


def test_pixelate_center_pixel_choice(penumbra, gpu_call):
    """Even sizes take the upper/right of the two middle pixels; partial cells the middle of
    the pixels that exist."""
    h, w = 6, 10
    y, x = np.mgrid[0:h, 0:w]
    img = np.stack([x, y, x * 100 + y, np.ones_like(x)], -1).astype(np.float32)  # value = coordinates
    out, _ = run_layers(gpu_call, img, [pixelate_layer(4, "CENTER")])
    # x cells [0,4) [4,8) [8,10) -> x 2, 6, 9; y cells [0,4) [4,6) -> y 2, 5.
    np.testing.assert_array_equal(out[0, :, 0], [2, 2, 2, 2, 6, 6, 6, 6, 9, 9])
    np.testing.assert_array_equal(out[:, 0, 1], [2, 2, 2, 2, 5, 5])
    out3, _ = run_layers(gpu_call, img, [pixelate_layer(3, "CENTER")])
    np.testing.assert_array_equal(out3[0, :, 0], [1, 1, 1, 4, 4, 4, 7, 7, 7, 9])


@pytest.mark.parametrize("size", [2, 3, 5, 8, 16])
def test_pixelate_average_matches_reference(penumbra, gpu_call, size):
    img = hdr_image(23, 37, 10 + size)
    out, stats = run_layers(gpu_call, img, [pixelate_layer(size, "AVERAGE")])
    # float32 sums of at most 256 values: measured relative error <= 1.5e-7.
    np.testing.assert_allclose(out, pixelate_reference(img, size, "AVERAGE"), rtol=2e-6, atol=1e-6)
    assert stats.post_passes == 3
    edge = out[20:, 35:]  # the top-right partial cell for size 5 is 3 x 2 pixels
    if size == 5:
        np.testing.assert_allclose(edge[0, 0], img[20:23, 35:37].astype(np.float64).mean(axis=(0, 1)), rtol=2e-6)


@pytest.mark.parametrize("sampling", ["CENTER", "AVERAGE"])
def test_pixelate_cell_larger_than_the_image(penumbra, gpu_call, sampling):
    img = hdr_image(13, 21, 4)
    out, _ = run_layers(gpu_call, img, [pixelate_layer(1000, sampling)])
    if sampling == "CENTER":
        expected = img[13 // 2, 21 // 2].astype(np.float64)
    else:
        expected = img.astype(np.float64).mean(axis=(0, 1))
    np.testing.assert_allclose(out, np.broadcast_to(expected, img.shape), rtol=2e-6)
    huge, _ = run_layers(gpu_call, img, [pixelate_layer(2**31 - 1, sampling)])
    np.testing.assert_array_equal(huge, out)  # sizes are clamped to the image's larger side


def test_pixelate_extremes(penumbra, gpu_call):
    img = hdr_image(9, 11, 1)
    same, stats = run_layers(gpu_call, img, [pixelate_layer(1, "AVERAGE")])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0
    one = np.array([[[3.0, 2.0, 1.0, 0.5]]], np.float32)
    for sampling in ("CENTER", "AVERAGE"):
        out, _ = run_layers(gpu_call, one, [pixelate_layer(5, sampling)])
        np.testing.assert_array_equal(out, one)
    row = hdr_image(1, 50, 3)
    out, _ = run_layers(gpu_call, row, [pixelate_layer(8, "AVERAGE")])
    np.testing.assert_allclose(out, pixelate_reference(row, 8, "AVERAGE"), rtol=2e-6)


def test_nan_stays_inside_its_pixelate_cell(penumbra, gpu_call):
    img = np.ones((16, 16, 4), np.float32)
    img[5, 6] = np.nan
    out, _ = run_layers(gpu_call, img, [pixelate_layer(4, "AVERAGE")])
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out[4:8, 4:8], 15.0 / 16.0, rtol=1e-6)  # counted as 0
    np.testing.assert_array_equal(out[:4], 1.0)


# --- NOISE -------------------------------------------------------------------------------


def test_noise_is_deterministic_per_frame_and_matches_reference(penumbra, gpu_call):
    from penumbra.engine.post.noise import grain_reference

    img = hdr_image(40, 50, 8)
    layer = noise_layer(0.2, 1, False, seed=3)
    (a, stats), (b, _), (c, _), (d, _) = run_frames(gpu_call, img, [layer], [7, 7, 8, -5])
    np.testing.assert_array_equal(a, b)  # the same frame gives identical pixels
    assert np.mean(a[..., :3] != c[..., :3]) > 0.99  # another frame gives other grain
    assert stats.post_passes == 1
    for out, frame in ((a, 7), (c, 8), (d, -5)):
        ref = img.astype(np.float64)
        ref[..., :3] += 0.2 * grain_reference(50, 40, frame, 1, 3, False)
        # One float32 addition: measured 1.6e-6 absolute on a 34.0 pixel, i.e. half an ulp.
        np.testing.assert_allclose(out, ref, rtol=1e-7, atol=1e-6)
    np.testing.assert_array_equal(a[..., 3], img[..., 3])


def test_noise_grain_is_zero_mean_and_uniform(penumbra, gpu_call):
    h = w = 256
    amount = 0.3
    img = np.full((h, w, 4), 0.5, np.float32)
    runs = run_frames(gpu_call, img, [noise_layer(amount, 1, False)], [1, 2])
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
    big, _ = run_layers(gpu_call, img, [noise_layer(0.5, 4, True)])
    g = big[..., :3] - 1.0
    np.testing.assert_array_equal(g[..., 0], g[..., 1])  # monochrome: one value for R, G, B
    np.testing.assert_array_equal(g[..., 0], g[..., 2])
    per_cell = g[::4, ::4, 0]  # 6 x 8 cells, the last column of cells 2 pixels wide
    np.testing.assert_array_equal(g[..., 0], np.repeat(np.repeat(per_cell, 4, 0), 4, 1)[:24, :30])
    assert len(np.unique(per_cell)) == per_cell.size  # and the cells differ
    seeds = [run_layers(gpu_call, img, [noise_layer(0.5, 1, True, seed=s)])[0] for s in (0, 1)]
    assert np.mean(seeds[0] != seeds[1]) > 0.7  # alpha (untouched) is a quarter of the values


def test_noise_extremes(penumbra, gpu_call):
    from penumbra.engine.post.noise import grain_reference

    img = hdr_image(16, 16, 9)
    same, stats = run_layers(gpu_call, img, [noise_layer(0.0)])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0
    loud, _ = run_frame(gpu_call, img, [noise_layer(10.0, 1, False)], 42)
    ref = img.astype(np.float64)
    ref[..., :3] += 10.0 * grain_reference(16, 16, 42)
    np.testing.assert_allclose(loud, ref, atol=1e-5)
    one_cell, _ = run_layers(gpu_call, img * 0 + 1, [noise_layer(0.5, 10000, False)])
    assert len(np.unique(one_cell[..., 0])) == 1  # grain larger than the image: one value
    pixel = np.array([[[1.0, 1.0, 1.0, 1.0]]], np.float32)
    out, _ = run_frame(gpu_call, pixel, [noise_layer(0.25)], 3)
    np.testing.assert_allclose(out[0, 0, :3], 1.0 + 0.25 * grain_reference(1, 1, 3)[0, 0], atol=1e-7)


# --- all five ----------------------------------------------------------------------------


ALL_LAYERS = {
    "GLOW": lambda mix: glow_layer(0.8, 0.5, 0.9, 5, mix=mix),
    "SCANLINES": lambda mix: scanlines_layer(11, 0.4, 0.7, mix=mix),
    "SEPIA": lambda mix: sepia_layer(0.8, mix=mix),
    "PIXELATE": lambda mix: pixelate_layer(5, "AVERAGE", mix=mix),
    "NOISE": lambda mix: noise_layer(0.2, 2, mix=mix),
}


@pytest.mark.parametrize("effect", list(ALL_LAYERS))
def test_mix_blends_and_zero_mix_is_identity(penumbra, gpu_call, effect):
    img = hdr_image(24, 40, 11)
    full, _ = run_layers(gpu_call, img, [ALL_LAYERS[effect](1.0)])
    half, _ = run_layers(gpu_call, img, [ALL_LAYERS[effect](0.5)])
    np.testing.assert_allclose(half, 0.5 * img + 0.5 * full, rtol=1e-6, atol=1e-6)
    none, stats = run_layers(gpu_call, img, [ALL_LAYERS[effect](0.0)])
    np.testing.assert_array_equal(none, img)
    assert stats.post_passes == 0


@pytest.mark.parametrize("size", [(1, 1), (1, 300), (300, 1)])
def test_all_effects_on_degenerate_image_sizes(penumbra, gpu_call, size):
    img = np.full((*size, 4), 0.5, np.float32)
    img[0, 0, :3] = 20.0
    layers = [make(1.0) for make in ALL_LAYERS.values()]
    out, stats = run_layers(gpu_call, img, layers)
    assert np.all(np.isfinite(out)) and out.shape == img.shape
    assert stats.post_passes == 2 + 1 + 1 + 3 + 1


def test_new_effects_as_scene_layers(penumbra, gpu_call):
    """The generated properties drive the effects: defaults through the real frame path."""
    import bpy
    from penumbra.engine.extract import camera_from_scene
    from penumbra.engine.post import EFFECTS

    scene = scenes.demo_scene(48, 32)
    for ob in scene.objects:
        if ob.type == "LIGHT":
            ob.data.use_shadow = False  # only the post stack matters here
    scene.penumbra.layers.clear()
    for eid in ALL_LAYERS:
        bpy.ops.penumbra.layer_add(effect=eid)
        defaults = EFFECTS[eid].defaults()
        params = scene.penumbra.layers[scene.penumbra.active_layer_index].params()
        for name, value in vars(defaults).items():
            assert getattr(params, name) == (value if isinstance(value, str) else pytest.approx(value))

    def render(frame):
        scene.frame_current = frame

        def job(engine, depsgraph):
            cam = camera_from_scene(depsgraph, scene, 48, 32)
            out = engine.render_frame(depsgraph, cam, 48, 32)
            return out.stats, out.color_array().copy()

        return gpu_call(job)

    (stats, a), (_, b), (_, c) = render(5), render(5), render(6)
    assert stats.post_passes == 2 + 1 + 1 + 3 + 1  # defaults: glow 2, pixelate AVERAGE 3
    assert np.all(np.isfinite(a))
    np.testing.assert_array_equal(a, b)  # the scene's frame seeds the grain: reproducible
    assert not np.array_equal(a, c)
