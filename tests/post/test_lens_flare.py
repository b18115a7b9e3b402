"""LENS_FLARE on the GPU against its numpy references (``lens_flare.flare_reference``,
``lens_flare.merge``, ``lens_flare.ghost_positions``)."""

from types import SimpleNamespace

import numpy as np
import pytest

from devkit.post import blender_image, flare_scene, layer, pixel_centres, run_layers, run_stack

# The flare these tests start from; each test overrides some of it.
FLARE = dict(
    threshold=1.0, intensity=1.0, mode="ADD", ghosts=5, ghost_spacing=0.35, halo_radius=0.5, halo_width=0.15, image=None
)


def flare_params(**params):
    return {**FLARE, **params}


def reference(img, lens=None, **params):
    """``flare_reference`` of FLARE with ``params`` overridden."""
    from penumbra.engine.post.lens_flare import flare_reference

    return flare_reference(img, SimpleNamespace(**flare_params(**params)), lens)


def sanitized(img):
    return np.nan_to_num(img.astype(np.float64), nan=0.0, posinf=0.0, neginf=0.0)


@pytest.mark.parametrize("ghosts,spacing", [(5, 0.35), (1, 0.0), (16, 0.13)])
def test_lens_flare_matches_reference(penumbra, gpu_call, ghosts, spacing):
    img = flare_scene()
    params = dict(ghosts=ghosts, ghost_spacing=spacing, intensity=0.8)
    out, stats = run_layers(gpu_call, img, [layer("LENS_FLARE", **flare_params(**params))])
    f = reference(img, **params)
    assert f.max() > 1.0  # the test sees a real flare
    np.testing.assert_allclose(out[..., :3] - img[..., :3], f, atol=2e-5 * f.max())
    np.testing.assert_array_equal(out[..., 3], img[..., 3])
    assert stats.post_passes == 1


def test_lens_flare_with_lens_image(penumbra, gpu_call):
    rng = np.random.default_rng(3)
    lens = rng.uniform(0, 2, (5, 7, 4)).astype(np.float32)
    img = flare_scene(seed=1)
    out, _ = run_stack(
        gpu_call, img, make_layers=lambda: [layer("LENS_FLARE", **flare_params(image=blender_image("Dirt", lens)))]
    )[0]
    f = reference(img, lens=lens)
    np.testing.assert_allclose(out[..., :3] - img[..., :3], f, atol=2e-5 * f.max())


def test_lens_flare_ghosts_sit_where_predicted(penumbra, gpu_call):
    """One bright pixel: each ghost's centroid is at C + (b - C) / (spacing * i - 1)."""
    from penumbra.engine.post.lens_flare import ghost_positions

    h, w = 96, 128
    img = np.zeros((h, w, 4), np.float32)
    img[60, 80, :3] = 100.0  # centre of the light: (80.5, 60.5)
    out, _ = run_layers(
        gpu_call, img, [layer("LENS_FLARE", **flare_params(threshold=1.0, ghosts=6, ghost_spacing=0.3, halo_width=0.0))]
    )
    f = out[..., 0] - img[..., 0]
    x, y = pixel_centres(h, w)
    checked = 0
    for i, gx, gy, scale in ghost_positions(80.5, 60.5, w, h, 6, 0.3):
        reach = scale * np.sqrt(2.0) + 1.0  # the ghost of one texel spans +-scale pixels per axis
        if not (reach < gx < w - reach and reach < gy < h - reach):
            continue
        near = np.hypot(x - gx, y - gy) <= reach
        weight = f * near
        assert weight.sum() > 0, f"ghost {i} missing"
        cx, cy = (weight * x).sum() / weight.sum(), (weight * y).sum() / weight.sum()
        assert abs(cx - gx) < 0.3 and abs(cy - gy) < 0.3, (i, cx, cy, gx, gy)
        checked += 1
    assert checked >= 4
    # Nothing else flares: all energy lies in the predicted ghosts.
    mask = np.zeros((h, w), bool)
    for _, gx, gy, scale in ghost_positions(80.5, 60.5, w, h, 6, 0.3):
        mask |= np.hypot(x - gx, y - gy) <= scale * np.sqrt(2.0) + 1.0
    assert f[~mask].max() == 0.0


def test_lens_flare_halo_is_a_ring(penumbra, gpu_call):
    h, w = 80, 80
    img = np.zeros((h, w, 4), np.float32)
    x, y = pixel_centres(h, w)
    r = np.hypot(x - 40, y - 40) / np.hypot(40, 40)
    img[np.hypot(x - 40, y - 40) < 4, :3] = 10.0  # a bright disc at the centre
    out, _ = run_layers(gpu_call, img, [layer("LENS_FLARE", **flare_params(ghosts=0, halo_radius=0.5, halo_width=0.1))])
    f = out[..., 0] - img[..., 0]
    ref = reference(img, ghosts=0, halo_radius=0.5, halo_width=0.1)
    np.testing.assert_allclose(out[..., :3] - img[..., :3], ref, atol=2e-5 * ref.max())
    assert f[(r < 0.4) | (r > 0.6)].max() == 0.0
    angles = np.arctan2(y - 40, x - 40)[f > 0.1]
    assert np.histogram(angles, bins=16, range=(-np.pi, np.pi))[0].min() > 0  # closed ring


@pytest.mark.parametrize("mode", ["ADD", "SCREEN", "AVERAGE", "DIFFERENCE"])
def test_lens_flare_merge_modes(penumbra, gpu_call, mode):
    """Each mode against its formula, given the flare the shader itself produced (ADD minus
    input) and the numpy reference of that flare."""
    from penumbra.engine.post.lens_flare import merge

    img = flare_scene(seed=4)
    img[5, 5, :3] = (1.5, 0.5, 3.0)  # HDR input where the flare is also present
    added, _ = run_layers(gpu_call, img, [layer("LENS_FLARE", **flare_params(intensity=0.6))])
    f = added[..., :3].astype(np.float64) - img[..., :3]
    np.testing.assert_allclose(f, reference(img, intensity=0.6), atol=2e-5 * f.max())
    out, _ = run_layers(gpu_call, img, [layer("LENS_FLARE", **flare_params(intensity=0.6, mode=mode))])
    # f was read back as (c + f) - c in float32: allow its rounding, scaled like the formula.
    tol = 1e-6 * (1.0 + np.abs(img[..., :3])) * (1.0 + np.abs(f))
    assert np.all(np.abs(out[..., :3] - merge(img[..., :3], f, mode)) <= tol)
    np.testing.assert_array_equal(out[..., 3], img[..., 3])


def test_lens_flare_screen_hdr_behaviour(penumbra, gpu_call):
    """Documented: SCREEN on values above 1 follows the formula, even where it darkens."""
    from penumbra.engine.post.lens_flare import LENS_RAMP, merge

    img = np.zeros((1, 1, 4), np.float32)
    img[0, 0] = (3.0, 2.0, 0.5, 1.0)
    # 1 x 1: every ghost reads the pixel itself with weight 1; one ghost, tint LENS_RAMP[0].
    out, _ = run_layers(
        gpu_call, img, [layer("LENS_FLARE", **flare_params(threshold=0.0, ghosts=1, halo_width=0.0, mode="SCREEN"))]
    )
    f = img[0, 0, :3] * LENS_RAMP[0]
    np.testing.assert_allclose(out[0, 0, :3], merge(img[0, 0, :3], f, "SCREEN"), rtol=1e-6)
    assert out[0, 0, 0] == pytest.approx(-3.0)  # R: c = f = 3 gives 1 - (-2) * (-2)


def test_lens_flare_identities(penumbra, gpu_call):
    img = flare_scene(seed=2)
    for mode in ("ADD", "SCREEN", "AVERAGE", "DIFFERENCE"):
        same, stats = run_layers(gpu_call, img, [layer("LENS_FLARE", **flare_params(intensity=0.0, mode=mode))])
        np.testing.assert_array_equal(same, img)
        assert stats.post_passes == 0
    same, stats = run_layers(gpu_call, img, [layer("LENS_FLARE", **flare_params(ghosts=0, halo_width=0.0))])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0
    # Nothing above the threshold: the flare is black and each mode returns merge(c, 0).
    high = float(img.max()) + 0.01
    for mode, expect, tol in (("ADD", img, 0.0), ("SCREEN", img, 1e-6), ("DIFFERENCE", img, 0.0)):
        out, stats = run_layers(gpu_call, img, [layer("LENS_FLARE", **flare_params(threshold=high, mode=mode))])
        np.testing.assert_allclose(out, expect, atol=tol * 60, rtol=tol)
        assert stats.post_passes == 1
    out, _ = run_layers(gpu_call, img, [layer("LENS_FLARE", **flare_params(threshold=high, mode="AVERAGE"))])
    np.testing.assert_allclose(out[..., :3], img[..., :3] * 0.5, rtol=1e-7)


def test_lens_flare_mix_nan_and_tiny_images(penumbra, gpu_call):
    from penumbra.engine.post.lens_flare import LENS_RAMP

    img = flare_scene(seed=6)
    full, _ = run_layers(gpu_call, img, [layer("LENS_FLARE", **flare_params())])
    half, _ = run_layers(gpu_call, img, [layer("LENS_FLARE", mix=0.5, **flare_params())])
    np.testing.assert_allclose(half, 0.5 * img + 0.5 * full, atol=1e-5 * full.max())

    bad = img.copy()
    bad[30, 41] = np.nan  # the brightest light becomes NaN: read as 0, never spread
    bad[10, 12, 0] = np.inf
    out, _ = run_layers(gpu_call, bad, [layer("LENS_FLARE", **flare_params(threshold=0.5))])
    assert np.all(np.isfinite(out))
    f = reference(bad, threshold=0.5)
    np.testing.assert_allclose(out[..., :3], sanitized(bad)[..., :3] + f, atol=2e-5 * f.max())

    # 1 x 1: every ghost reads the pixel itself (weight 1); the halo ring misses r = 0.
    one = np.full((1, 1, 4), 5.0, np.float32)
    out, _ = run_layers(
        gpu_call,
        one,
        [layer("LENS_FLARE", **flare_params(ghosts=16, ghost_spacing=2.0, halo_radius=0.0, halo_width=0.0))],
    )
    np.testing.assert_allclose(out[0, 0, :3], 5.0 + 16 * 4.0 * LENS_RAMP[0], rtol=1e-6)
    out, _ = run_layers(gpu_call, one, [layer("LENS_FLARE", **flare_params(ghosts=0, halo_radius=0.0, halo_width=1.0))])
    np.testing.assert_allclose(out[0, 0, :3], 5.0 + 4.0 * LENS_RAMP[0], rtol=1e-6)  # ring = 1 at r = 0
    strip = np.random.default_rng(9).uniform(0, 0.8, (1, 300, 4)).astype(np.float32)
    strip[0, 200, :3] = 50.0
    params = dict(ghosts=16, ghost_spacing=2.0, intensity=10.0, halo_width=0.5)
    out, _ = run_layers(gpu_call, strip, [layer("LENS_FLARE", **flare_params(**params))])
    f = reference(strip, **params)
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out[..., :3] - strip[..., :3], f, atol=2e-5 * f.max())


def test_lens_flare_defaults_change_an_hdr_image_and_stay_finite(penumbra, gpu_call):
    img = flare_scene(seed=11)
    out, stats = run_layers(gpu_call, img, [layer("LENS_FLARE")])
    assert np.all(np.isfinite(out)) and stats.post_passes >= 1
    assert np.abs(out - img).max() > 0.05
