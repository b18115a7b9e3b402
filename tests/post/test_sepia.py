"""SEPIA on the GPU against its numpy reference (``sepia.sepia_reference``)."""

import numpy as np
import pytest

from devkit.post import hdr_image, layer, run_layers


@pytest.mark.parametrize("amount", [1.0, 0.37])
def test_sepia_matrix_exact(penumbra, gpu_call, amount):
    from penumbra.engine.post.sepia import SEPIA_MATRIX, sepia_reference

    m = np.array(SEPIA_MATRIX)
    np.testing.assert_array_equal(m[0], (0.393, 0.769, 0.189))
    img = hdr_image(23, 31, 5)
    out, stats = run_layers(gpu_call, img, [layer("SEPIA", amount=amount)])
    ref = sepia_reference(img[..., :3], amount)
    np.testing.assert_allclose(out[..., :3], ref, rtol=1e-6, atol=1e-5)
    np.testing.assert_array_equal(out[..., 3], img[..., 3])
    assert stats.post_passes == 1


def test_sepia_extremes(penumbra, gpu_call):
    img = np.array([[[1.0, 1.0, 1.0, 1.0], [0.0, 0.0, 0.0, 0.5]]], np.float32)
    out, _ = run_layers(gpu_call, img, [layer("SEPIA", amount=1.0)])
    np.testing.assert_allclose(out[0, 0], (1.351, 1.203, 0.937, 1.0), atol=1e-6)  # not clamped
    np.testing.assert_array_equal(out[0, 1], (0.0, 0.0, 0.0, 0.5))
    same, stats = run_layers(gpu_call, img, [layer("SEPIA", amount=0.0)])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0
    one, _ = run_layers(gpu_call, img[:, :1] * 3.0, [layer("SEPIA", amount=1.0)])
    np.testing.assert_allclose(one[0, 0, :3], 3.0 * np.array([1.351, 1.203, 0.937]), atol=1e-5)
