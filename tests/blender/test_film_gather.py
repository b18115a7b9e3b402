"""The gathering film (engine/frame/film.py ``accumulate`` with ``gather``, shaders/lib/
film_gather.glsl) on the GPU against numpy: one sample's contribution to each film pixel is
the filter's weight at its distance; a constant image stays constant at the borders; a
non-finite sample does not spread."""

import numpy as np
import pytest

W, H = 9, 7


def _accumulate(gpu_call, image, s=5, filter_size=1.5):
    """The accumulation and total weight after one sample ``s`` of ``image`` (H, W, 4)."""
    from devkit import scenes

    scene = scenes.empty_scene(W, H)  # the GPU context is a render's: it needs a camera
    scenes.camera(scene, (0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
    from penumbra.engine.frame import sampling
    from penumbra.engine.frame.film import Film, texture_array
    from penumbra.shaders.loader import ShaderCache

    def job(_engine, _depsgraph):
        import gpu

        film = Film(ShaderCache())
        film.ensure(W, H, False)
        data = np.ascontiguousarray(image, np.float32)
        film.color = gpu.types.GPUTexture(
            (W, H), format="RGBA32F", data=gpu.types.Buffer("FLOAT", data.size, data.ravel())
        )
        dx, dy, weight = sampling.pixel_offset(s, filter_size)
        film.begin(False, False, True, gather_reach=sampling.film_reach(filter_size))
        film.accumulate(weight, False, False, s, sampling.gather_uniforms(dx, dy, filter_size))
        return texture_array(film._accum_color, 4).copy(), weight, (dx, dy)

    return gpu_call(job)


def test_one_sample_reaches_each_pixel_by_the_filters_weight(penumbra, gpu_call):
    from penumbra.engine.frame import sampling

    impulse = np.zeros((H, W, 4), np.float32)
    impulse[3, 4] = 1.0
    accum, weight, (dx, dy) = _accumulate(gpu_call, impulse)
    width = sampling.filter_width(1.5)
    expected = np.zeros((H, W))
    for y in range(H):
        for x in range(W):
            # Film pixel (x, y) sees sample pixel (4, 3)'s point at (4 - dx - x, 3 - dy - y) from its centre.
            expected[y, x] = sampling.blackman_harris(4 - dx - x, width) * sampling.blackman_harris(3 - dy - y, width)
    np.testing.assert_allclose(accum[..., 0], expected, atol=1e-6)
    assert expected.max() > 0.3 and (expected > 0).sum() == 9


@pytest.mark.parametrize("s", [0, 1, 7])
def test_a_constant_image_stays_constant_at_the_borders(penumbra, gpu_call, s):
    flat = np.full((H, W, 4), 0.25, np.float32)
    accum, weight, _shift = _accumulate(gpu_call, flat, s)
    np.testing.assert_allclose(accum / weight, 0.25, rtol=1e-6)


def test_a_non_finite_sample_does_not_spread(penumbra, gpu_call):
    image = np.full((H, W, 4), 0.5, np.float32)
    image[3, 4] = np.nan
    image[1, 1] = np.inf
    accum, weight, _shift = _accumulate(gpu_call, image)
    assert np.all(np.isfinite(accum))
    np.testing.assert_allclose(accum / weight, 0.5, rtol=1e-6)  # its neighbours keep their light
