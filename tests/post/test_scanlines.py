"""SCANLINES on the GPU against its numpy references (``scanlines.scanline_darkness``,
``scanlines.scanlines_reference``). Images are float RGBA, row 0 at the bottom."""

import numpy as np
import pytest

from devkit.post import hdr_image, layer, run_layers, run_stack

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
    from penumbra.engine.post.scanlines import scanlines_reference

    count, thickness, intensity, speed, frame, antialias = case
    h, w = 64, 40
    img = np.ones((h, w, 4), np.float32)
    img[..., :3] *= np.linspace(0.1, 4.0, w)[None, :, None]  # HDR gradient across the rows
    lines = layer(
        "SCANLINES", count=count, thickness=thickness, intensity=intensity, scroll_speed=speed, antialias=antialias
    )
    out, stats = run_stack(gpu_call, img, [lines], frames=[frame])[0]
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
    np.testing.assert_allclose(
        profile, np.broadcast_to((1.0 - intensity * dark)[:, None, None], profile.shape), rtol=0, atol=2e-6
    )
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
    runs = run_stack(
        gpu_call,
        img,
        [layer("SCANLINES", count=16, thickness=0.5, intensity=0.75, scroll_speed=0.25, antialias=True)],
        frames=[0, 1, 1, 2],
    )
    rows = [r[0][:, 0, 0] for r in runs]
    expected = np.where(np.arange(64) % 4 < 2, 2.0 * 0.25, 2.0)
    np.testing.assert_allclose(rows[0], expected, atol=1e-6)
    np.testing.assert_allclose(rows[1], np.roll(expected, 1), atol=1e-6)
    np.testing.assert_array_equal(rows[1], rows[2])  # same frame, same pixels
    np.testing.assert_allclose(rows[3], np.roll(expected, 2), atol=1e-6)


def test_scanlines_extremes(penumbra, gpu_call):
    from penumbra.engine.post.scanlines import scanlines_reference

    img = hdr_image(30, 20, 2)
    for off in (layer("SCANLINES", count=16, intensity=0.0), layer("SCANLINES", count=16, thickness=0.0)):
        out, stats = run_layers(gpu_call, img, [off])
        np.testing.assert_array_equal(out, img)
        assert stats.post_passes == 0
    full, _ = run_layers(gpu_call, img, [layer("SCANLINES", count=9, thickness=1.0, intensity=0.6)])  # all dark
    np.testing.assert_allclose(full[..., :3], img[..., :3] * 0.4, rtol=1e-6)
    # 100000 lines over 30 rows: each pixel box-filters 3333.3 periods, so its darkness is
    # the thickness up to a part of one period in 3333 (|dark - 0.3| <= 0.3 / 3333).
    dense, _ = run_layers(gpu_call, img, [layer("SCANLINES", count=100000, thickness=0.3, intensity=1.0)])
    ref, dark = scanlines_reference(img, 100000, 0.3, 1.0, 0.0, 0, True)
    np.testing.assert_allclose(dense[..., :3] / img[..., :3], ref[..., :3] / img[..., :3], rtol=0, atol=2e-6)
    assert np.all(np.abs(dark - 0.3) <= 0.3 / 3333)
    one = np.array([[[2.0, 1.0, 0.5, 1.0]]], np.float32)
    out, _ = run_layers(gpu_call, one, [layer("SCANLINES", count=1, thickness=0.3, intensity=0.5)])
    np.testing.assert_allclose(out[0, 0], (2.0 * 0.85, 0.85, 0.5 * 0.85, 1.0), rtol=1e-6)
