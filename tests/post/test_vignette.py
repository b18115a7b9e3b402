"""VIGNETTE on the GPU against its numpy reference (``vignette.vignette_factor``)."""

import numpy as np

from devkit.post import layer, run_layers


def test_vignette_matches_reference_profile(penumbra, gpu_call):
    from penumbra.engine.post.vignette import vignette_factor

    h, w = 90, 160
    img = np.full((h, w, 4), 2.0, np.float32)
    color = (0.1, 0.2, 0.3)
    out, _ = run_layers(gpu_call, img, [layer("VIGNETTE", radius=0.5, softness=0.7, roundness=0.5, color=color)])
    y, x = np.mgrid[0:h, 0:w] + 0.5
    f = vignette_factor(x, y, w, h, 0.5, 0.7, 0.5)
    ref = 2.0 * (1 - f)[..., None] + f[..., None] * np.array(color)
    np.testing.assert_allclose(out[..., :3], ref, atol=1e-5)
    np.testing.assert_allclose(out[..., 3], 2.0)  # alpha untouched
