"""PIXELATE on the GPU against its numpy reference (``pixelate.pixelate_reference``)."""

import numpy as np
import pytest

from devkit.post import hdr_image, layer, run_layers


@pytest.mark.parametrize("size", [2, 3, 4, 7, 16])
def test_pixelate_center_matches_reference(penumbra, gpu_call, size):
    from penumbra.engine.post.pixelate import pixelate_reference

    img = hdr_image(23, 37, size)  # neither side a multiple of most sizes: partial edge cells
    out, stats = run_layers(gpu_call, img, [layer("PIXELATE", size=size, sampling="CENTER")])
    np.testing.assert_array_equal(out, pixelate_reference(img, size, "CENTER").astype(np.float32))
    assert stats.post_passes == 1


def test_pixelate_center_pixel_choice(penumbra, gpu_call):
    """Even sizes take the upper/right of the two middle pixels; partial cells the middle of
    the pixels that exist."""
    h, w = 6, 10
    y, x = np.mgrid[0:h, 0:w]
    img = np.stack([x, y, x * 100 + y, np.ones_like(x)], -1).astype(np.float32)  # value = coordinates
    out, _ = run_layers(gpu_call, img, [layer("PIXELATE", size=4, sampling="CENTER")])
    # x cells [0,4) [4,8) [8,10) -> x 2, 6, 9; y cells [0,4) [4,6) -> y 2, 5.
    np.testing.assert_array_equal(out[0, :, 0], [2, 2, 2, 2, 6, 6, 6, 6, 9, 9])
    np.testing.assert_array_equal(out[:, 0, 1], [2, 2, 2, 2, 5, 5])
    out3, _ = run_layers(gpu_call, img, [layer("PIXELATE", size=3, sampling="CENTER")])
    np.testing.assert_array_equal(out3[0, :, 0], [1, 1, 1, 4, 4, 4, 7, 7, 7, 9])


@pytest.mark.parametrize("size", [2, 3, 5, 8, 16])
def test_pixelate_average_matches_reference(penumbra, gpu_call, size):
    from penumbra.engine.post.pixelate import pixelate_reference

    img = hdr_image(23, 37, 10 + size)
    out, stats = run_layers(gpu_call, img, [layer("PIXELATE", size=size, sampling="AVERAGE")])
    # float32 sums of at most 256 values: measured relative error <= 1.5e-7.
    np.testing.assert_allclose(out, pixelate_reference(img, size, "AVERAGE"), rtol=2e-6, atol=1e-6)
    assert stats.post_passes == 3
    edge = out[20:, 35:]  # the top-right partial cell for size 5 is 3 x 2 pixels
    if size == 5:
        np.testing.assert_allclose(edge[0, 0], img[20:23, 35:37].astype(np.float64).mean(axis=(0, 1)), rtol=2e-6)


@pytest.mark.parametrize("sampling", ["CENTER", "AVERAGE"])
def test_pixelate_cell_larger_than_the_image(penumbra, gpu_call, sampling):
    img = hdr_image(13, 21, 4)
    out, _ = run_layers(gpu_call, img, [layer("PIXELATE", size=1000, sampling=sampling)])
    if sampling == "CENTER":
        expected = img[13 // 2, 21 // 2].astype(np.float64)
    else:
        expected = img.astype(np.float64).mean(axis=(0, 1))
    np.testing.assert_allclose(out, np.broadcast_to(expected, img.shape), rtol=2e-6)
    huge, _ = run_layers(gpu_call, img, [layer("PIXELATE", size=2**31 - 1, sampling=sampling)])
    np.testing.assert_array_equal(huge, out)  # sizes are clamped to the image's larger side


def test_pixelate_extremes(penumbra, gpu_call):
    from penumbra.engine.post.pixelate import pixelate_reference

    img = hdr_image(9, 11, 1)
    same, stats = run_layers(gpu_call, img, [layer("PIXELATE", size=1, sampling="AVERAGE")])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0
    one = np.array([[[3.0, 2.0, 1.0, 0.5]]], np.float32)
    for sampling in ("CENTER", "AVERAGE"):
        out, _ = run_layers(gpu_call, one, [layer("PIXELATE", size=5, sampling=sampling)])
        np.testing.assert_array_equal(out, one)
    row = hdr_image(1, 50, 3)
    out, _ = run_layers(gpu_call, row, [layer("PIXELATE", size=8, sampling="AVERAGE")])
    np.testing.assert_allclose(out, pixelate_reference(row, 8, "AVERAGE"), rtol=2e-6)


def test_nan_stays_inside_its_pixelate_cell(penumbra, gpu_call):
    img = np.ones((16, 16, 4), np.float32)
    img[5, 6] = np.nan
    out, _ = run_layers(gpu_call, img, [layer("PIXELATE", size=4, sampling="AVERAGE")])
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out[4:8, 4:8], 15.0 / 16.0, rtol=1e-6)  # counted as 0
    np.testing.assert_array_equal(out[:4], 1.0)
