"""COLORIZER on the GPU against its numpy reference (``colorizer.colorizer_reference``)."""

import numpy as np
import pytest

from devkit.post import blender_image, flare_scene, layer, run_layers, run_stack


@pytest.mark.parametrize("blur_radius", [0, 3])
def test_colorizer_default_ramp_matches_reference(penumbra, gpu_call, blur_radius):
    from penumbra.engine.post.colorizer import DEFAULT_LUT, colorizer_reference

    rng = np.random.default_rng(10 + blur_radius)
    img = rng.uniform(0, 1.3, (37, 52, 4)).astype(np.float32)  # odd size, some luminance > 1
    out, stats = run_layers(gpu_call, img, [layer("COLORIZER", image=None, blur_radius=blur_radius, strength=0.7)])
    np.testing.assert_allclose(out, colorizer_reference(img, DEFAULT_LUT, blur_radius, 0.7), atol=2e-6)
    assert stats.post_passes == (3 if blur_radius else 1)


def test_colorizer_lookup_coordinates_hit_texel_centres(penumbra, gpu_call):
    """x = 0 / 0.5 / 1 and y = 0 land exactly on texel centres of a 3 x 2 LUT."""
    lut = np.zeros((2, 3, 4), np.float32)
    lut[..., 3] = 1.0
    lut[0, :, :3] = [(1, 0, 0), (0, 1, 0), (0, 0, 1)]  # y = 0 row (image centre)
    lut[1, :, :3] = [(5, 5, 5), (6, 6, 6), (7, 7, 7)]
    for value, expect in ((0.0, (1, 0, 0)), (0.5, (0, 1, 0)), (1.0, (0, 0, 1)), (3.0, (0, 0, 1))):
        img = np.full((5, 5, 4), value, np.float32)  # grey: luminance = value; centre pixel y = 0
        out, _ = run_stack(
            gpu_call, img, make_layers=lambda: [layer("COLORIZER", image=blender_image("LUT", lut), blur_radius=0)]
        )[0]
        np.testing.assert_allclose(out[2, 2, :3], expect, atol=1e-6)
        assert out[2, 2, 3] == value  # alpha kept


@pytest.mark.parametrize("lut_shape", [(3, 7), (1, 16), (1, 1)])
def test_colorizer_with_image_lut(penumbra, gpu_call, lut_shape):
    from penumbra.engine.post.colorizer import colorizer_reference

    rng = np.random.default_rng(sum(lut_shape))
    lut = rng.uniform(0, 2, (*lut_shape, 4)).astype(np.float32)
    img = rng.uniform(0, 1, (30, 41, 4)).astype(np.float32)
    out, _ = run_stack(
        gpu_call,
        img,
        make_layers=lambda: [layer("COLORIZER", image=blender_image("LUT", lut), blur_radius=2, strength=1.0)],
    )[0]
    np.testing.assert_allclose(out, colorizer_reference(img, lut, 2, 1.0), atol=5e-6)


def test_colorizer_identity_mix_nan_and_tiny_images(penumbra, gpu_call):
    from penumbra.engine.post.colorizer import DEFAULT_LUT, colorizer_reference

    rng = np.random.default_rng(5)
    img = rng.uniform(0, 1, (20, 24, 4)).astype(np.float32)
    same, stats = run_layers(gpu_call, img, [layer("COLORIZER", image=None, blur_radius=4, strength=0.0)])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0

    full, _ = run_layers(gpu_call, img, [layer("COLORIZER", image=None, blur_radius=1, strength=1.0)])
    half, _ = run_layers(gpu_call, img, [layer("COLORIZER", mix=0.5, image=None, blur_radius=1, strength=1.0)])
    np.testing.assert_allclose(half, 0.5 * img + 0.5 * full, atol=1e-6)

    bad = img.copy()
    bad[5, 5] = np.nan
    bad[12, 7, 1] = np.inf
    out, _ = run_layers(gpu_call, bad, [layer("COLORIZER", image=None, blur_radius=2, strength=1.0)])
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out, colorizer_reference(bad, DEFAULT_LUT, 2, 1.0), atol=2e-6)

    # 1 x 1 (y = 0: the centre row) and a 1-pixel-high strip with a blur wider than the image.
    one = np.full((1, 1, 4), 0.25, np.float32)
    out, _ = run_layers(gpu_call, one, [layer("COLORIZER", image=None, blur_radius=256, strength=1.0)])
    np.testing.assert_allclose(out, colorizer_reference(one, DEFAULT_LUT, 0, 1.0), atol=1e-6)
    strip = rng.uniform(0, 1, (1, 300, 4)).astype(np.float32)
    out, _ = run_layers(gpu_call, strip, [layer("COLORIZER", image=None, blur_radius=40, strength=1.0)])
    np.testing.assert_allclose(out, colorizer_reference(strip, DEFAULT_LUT, 40, 1.0), atol=2e-6)


def test_colorizer_defaults_change_an_hdr_image_and_stay_finite(penumbra, gpu_call):
    img = flare_scene(seed=11)
    out, stats = run_layers(gpu_call, img, [layer("COLORIZER")])
    assert np.all(np.isfinite(out)) and stats.post_passes >= 1
    assert np.abs(out - img).max() > 0.05


@pytest.mark.parametrize("space", ["sRGB", "Non-Color"])
def test_a_byte_lut_is_read_as_blenders_own_texture_holds_it(penumbra, gpu_call, space):
    """A user's LUT is drawn from Penumbra's own float table of its pixels (the same values on
    every GPU). For an 8-bit image the table is what Blender's own texture of it gives a
    shader: that texture holds the image's bytes, as SRGB8_A8 (which a sampler decodes with the
    sRGB transfer function, IEC 61966-2-1) for sRGB, as RGBA8 (bytes / 255) for Non-Color."""
    import bpy

    from penumbra.engine.post.base import image_pixels, srgb_to_linear

    rng = np.random.default_rng(5)
    image = bpy.data.images.new(f"Byte LUT {space}", 16, 3, float_buffer=False)
    image.colorspace_settings.name = space
    image.pixels.foreach_set(rng.uniform(0, 1, 16 * 3 * 4).astype(np.float32))
    table = image_pixels(image)
    assert table is not None and table.shape == (3, 16, 4)

    def blenders(_engine, _depsgraph):
        import gpu

        texture = gpu.texture.from_image(image)
        return texture.format, np.asarray(texture.read().to_list(), np.float32).reshape(3, 16, 4)

    fmt, held = gpu_call(blenders)
    stored = held[..., :3] / 255.0
    assert fmt == ("SRGB8_A8" if space == "sRGB" else "RGBA8")
    expected = srgb_to_linear(stored) if space == "sRGB" else stored
    np.testing.assert_allclose(table[..., :3], expected, atol=1e-6)
    if space == "sRGB":
        assert np.abs(table[..., :3] - stored).max() > 0.05  # decoded, not the bytes
