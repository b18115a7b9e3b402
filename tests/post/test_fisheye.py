"""FISHEYE on the GPU against its numpy references (``fisheye.fisheye_source``,
``fisheye.fisheye_reference``)."""

import numpy as np
import pytest

from devkit.post import coordinate_image, flare_scene, layer, pixel_centres, run_layers


@pytest.mark.parametrize("strength", [-1.0, -0.4, 0.5, 1.0])
def test_fisheye_reads_where_the_mapping_says(penumbra, gpu_call, strength):
    from penumbra.engine.post.fisheye import fisheye_source

    h, w = 45, 80
    out, _ = run_layers(gpu_call, coordinate_image(h, w), [layer("FISHEYE", strength=strength, edge="CLAMP")])
    x, y = pixel_centres(h, w)
    sx, sy = fisheye_source(x, y, w, h, strength)
    # Bilinear reads of a linear ramp return the position itself (clamped at the borders).
    np.testing.assert_allclose(out[..., 0], np.clip(sx, 0.5, w - 0.5), atol=1e-4)
    np.testing.assert_allclose(out[..., 1], np.clip(sy, 0.5, h - 0.5), atol=1e-4)
    # The map is monotonic along rows and columns through the centre (no folds), and the corner
    # circle is fixed: the corner pixels read (almost) themselves.
    assert np.all(np.diff(out[h // 2, :, 0]) >= -1e-5) and np.all(np.diff(out[:, w // 2, 1]) >= -1e-5)
    # Bulge: the pixel 10.5 px right of the centre reads closer to it (magnified); pinch: farther.
    read = out[h // 2, w // 2 + 10, 0] - w / 2
    assert (read < 10.5) if strength > 0 else (read > 10.5)


@pytest.mark.parametrize("edge", ["CLAMP", "BLACK", "MIRROR"])
@pytest.mark.parametrize("strength", [-1.0, -0.6, 0.3, 1.0])
def test_fisheye_edge_modes_match_reference(penumbra, gpu_call, edge, strength):
    from penumbra.engine.post.fisheye import fisheye_reference

    rng = np.random.default_rng(int(strength * 10) + 17)
    img = rng.uniform(0, 3, (40, 64, 4)).astype(np.float32)
    out, stats = run_layers(gpu_call, img, [layer("FISHEYE", strength=strength, edge=edge)])
    assert np.all(np.isfinite(out)) and stats.post_passes == 1
    np.testing.assert_allclose(out, fisheye_reference(img, strength, edge), atol=1e-4)


def test_fisheye_limits_have_no_holes(penumbra, gpu_call):
    """A full bulge reads only inside the image, so even BLACK leaves no empty pixel; a full
    pinch with BLACK is empty exactly where the mapping leaves the image."""
    from penumbra.engine.post.fisheye import fisheye_source

    h, w = 36, 90
    img = np.ones((h, w, 4), np.float32)
    out, _ = run_layers(gpu_call, img, [layer("FISHEYE", strength=1.0, edge="BLACK")])
    np.testing.assert_allclose(out, 1.0, atol=1e-6)
    out, _ = run_layers(gpu_call, img, [layer("FISHEYE", strength=-1.0, edge="BLACK")])
    x, y = pixel_centres(h, w)
    sx, sy = fisheye_source(x, y, w, h, -1.0)
    inside = (sx >= 0.5) & (sx <= w - 0.5) & (sy >= 0.5) & (sy <= h - 0.5)
    far_out = (sx < -0.5) | (sx > w + 0.5) | (sy < -0.5) | (sy > h + 0.5)
    assert inside.any() and far_out.any()
    np.testing.assert_allclose(out[inside], 1.0, atol=1e-5)
    np.testing.assert_array_equal(out[far_out], 0.0)  # transparent black, alpha included


def test_fisheye_identity_mix_nan_and_tiny_images(penumbra, gpu_call):
    from penumbra.engine.post.fisheye import fisheye_reference

    rng = np.random.default_rng(8)
    img = rng.uniform(0, 1, (25, 31, 4)).astype(np.float32)
    same, stats = run_layers(gpu_call, img, [layer("FISHEYE", strength=0.0, edge="MIRROR")])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0

    full, _ = run_layers(gpu_call, img, [layer("FISHEYE", strength=0.7, edge="CLAMP")])
    half, _ = run_layers(gpu_call, img, [layer("FISHEYE", mix=0.5, strength=0.7, edge="CLAMP")])
    np.testing.assert_allclose(half, 0.5 * img + 0.5 * full, atol=1e-6)

    bad = img.copy()
    bad[12, 15] = np.nan  # the centre pixel, magnified by the bulge
    bad[3, 3, 0] = -np.inf
    out, _ = run_layers(gpu_call, bad, [layer("FISHEYE", strength=0.8, edge="MIRROR")])
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out, fisheye_reference(bad, 0.8, "MIRROR"), atol=1e-4)

    for size in ((1, 1), (1, 300), (300, 1)):
        img = rng.uniform(0, 1, (*size, 4)).astype(np.float32)
        for edge in ("CLAMP", "BLACK", "MIRROR"):
            out, _ = run_layers(gpu_call, img, [layer("FISHEYE", strength=-1.0, edge=edge)])
            assert np.all(np.isfinite(out)) and out.shape == img.shape
            np.testing.assert_allclose(out, fisheye_reference(img, -1.0, edge), atol=1e-4)


def test_fisheye_defaults_change_an_hdr_image_and_stay_finite(penumbra, gpu_call):
    img = flare_scene(seed=11)
    out, stats = run_layers(gpu_call, img, [layer("FISHEYE")])
    assert np.all(np.isfinite(out)) and stats.post_passes >= 1
    assert np.abs(out - img).max() > 0.05
