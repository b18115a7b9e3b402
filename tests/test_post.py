"""Post layers on the GPU against numpy references."""

from types import SimpleNamespace

import numpy as np
import pytest

import scenes


def run_stack(gpu_call, image, layers=None, frames=(0,), make_layers=None):
    """Upload ``image`` (h, w, 4 float32) and run the post stack on it once per frame number
    in ``frames`` (fresh context and stack each time); returns [(array, FrameStats)].

    ``make_layers()``, when given, builds the layers after the file is reset (for layers that
    reference Blender images)."""

    def job(engine, depsgraph):
        import gpu
        from penumbra.engine.post import PostContext, PostStack
        from penumbra.engine.renderer import FrameStats, texture_array
        from penumbra.shaders.loader import ShaderCache

        h, w = image.shape[:2]
        buf = gpu.types.Buffer("FLOAT", image.size, image.ravel().tolist())
        src = gpu.types.GPUTexture((w, h), format="RGBA32F", data=buf)
        shaders = ShaderCache()
        results = []
        for frame in frames:
            stats = FrameStats()
            ctx = PostContext(shaders, w, h, frame=frame, stats=stats)
            out = PostStack().run(ctx, src, stack)
            results.append((texture_array(out, 4).copy(), stats))
        return results

    scenes.top_camera(scenes.empty_scene(8, 8))
    stack = make_layers() if make_layers is not None else layers
    return gpu_call(job)


def run_layers(gpu_call, image, layers):
    """``run_stack`` for one frame: (array, FrameStats)."""
    return run_stack(gpu_call, image, layers)[0]


def blur_layer(radius, sigma=0.0, mix=1.0):
    return ("BLUR", True, mix, SimpleNamespace(radius=radius, sigma=sigma))


def vignette_layer(radius=0.8, softness=0.6, roundness=1.0, color=(0, 0, 0), mix=1.0):
    return ("VIGNETTE", True, mix, SimpleNamespace(radius=radius, softness=softness, roundness=roundness, color=color))


def gaussian_reference(img, radius, sigma=None):
    """Separable Gaussian with clamp-to-edge, in float64."""
    from penumbra.engine.kernels import gaussian_1d

    w = gaussian_1d(radius, sigma)
    out = img.astype(np.float64)
    for axis in (1, 0):
        pad = [(0, 0)] * 3
        pad[axis] = (radius, radius)
        p = np.pad(out, pad, mode="edge")
        acc = np.zeros_like(out)
        for i, wi in enumerate(w):
            sl = [slice(None)] * 3
            sl[axis] = slice(i, i + out.shape[axis])
            acc += wi * p[tuple(sl)]
        out = acc
    return out


@pytest.mark.parametrize("radius", [1, 5, 20])
def test_blur_matches_gaussian_convolution(penumbra, gpu_call, radius):
    rng = np.random.default_rng(radius)
    img = rng.uniform(0, 4, (37, 53, 4)).astype(np.float32)  # HDR values, odd sizes
    img[18, 26] = (50.0, 0.0, 10.0, 1.0)  # an HDR impulse
    out, stats = run_layers(gpu_call, img, [blur_layer(radius)])
    np.testing.assert_allclose(out, gaussian_reference(img, radius), rtol=1e-5, atol=1e-5)
    assert stats.post_passes == 2


def test_blur_preserves_energy_of_an_impulse(penumbra, gpu_call):
    img = np.zeros((64, 64, 4), np.float32)
    img[32, 32] = 1000.0
    out, _ = run_layers(gpu_call, img, [blur_layer(8)])
    assert out[..., 0].sum() == pytest.approx(1000.0, rel=1e-5)


def test_nan_and_inf_do_not_spread_through_blur(penumbra, gpu_call):
    img = np.ones((32, 32, 4), np.float32)
    img[10, 10] = np.nan
    img[20, 20] = np.inf
    out, _ = run_layers(gpu_call, img, [blur_layer(6)])
    assert np.all(np.isfinite(out))
    assert out[0, 0, 0] == pytest.approx(1.0)


def test_vignette_matches_reference_profile(penumbra, gpu_call):
    from penumbra.engine.post.vignette import vignette_factor

    h, w = 90, 160
    img = np.full((h, w, 4), 2.0, np.float32)
    color = (0.1, 0.2, 0.3)
    out, _ = run_layers(gpu_call, img, [vignette_layer(0.5, 0.7, 0.5, color)])
    y, x = np.mgrid[0:h, 0:w] + 0.5
    f = vignette_factor(x, y, w, h, 0.5, 0.7, 0.5)
    ref = 2.0 * (1 - f)[..., None] + f[..., None] * np.array(color)
    np.testing.assert_allclose(out[..., :3], ref, atol=1e-5)
    np.testing.assert_allclose(out[..., 3], 2.0)  # alpha untouched


def test_mix_blends_and_zero_mix_is_identity(penumbra, gpu_call):
    rng = np.random.default_rng(3)
    img = rng.uniform(0, 1, (24, 40, 4)).astype(np.float32)
    full, _ = run_layers(gpu_call, img, [vignette_layer(0.2, 0.3)])
    half, _ = run_layers(gpu_call, img, [vignette_layer(0.2, 0.3, mix=0.25)])
    np.testing.assert_allclose(half, 0.75 * img + 0.25 * full, atol=1e-6)
    none, stats = run_layers(gpu_call, img, [vignette_layer(0.2, 0.3, mix=0.0), blur_layer(0)])
    np.testing.assert_array_equal(none, img)
    assert stats.post_passes == 0


def test_stack_order_matters(penumbra, gpu_call):
    rng = np.random.default_rng(4)
    img = rng.uniform(0, 1, (32, 48, 4)).astype(np.float32)
    a, _ = run_layers(gpu_call, img, [blur_layer(4), vignette_layer(0.1, 0.5)])
    b, _ = run_layers(gpu_call, img, [vignette_layer(0.1, 0.5), blur_layer(4)])
    from penumbra.engine.post.vignette import vignette_factor

    h, w = img.shape[:2]
    y, x = np.mgrid[0:h, 0:w] + 0.5
    f = vignette_factor(x, y, w, h, 0.1, 0.5, 1.0)[..., None]
    np.testing.assert_allclose(a[..., :3], gaussian_reference(img, 4)[..., :3] * (1 - f), atol=1e-5)
    np.testing.assert_allclose(b[..., :3], gaussian_reference(np.concatenate([img[..., :3] * (1 - f), img[..., 3:]], -1), 4)[..., :3], atol=1e-5)


@pytest.mark.parametrize("size", [(1, 1), (1, 300)])
def test_post_layers_on_degenerate_image_sizes(penumbra, gpu_call, size):
    img = np.full((*size, 4), 0.5, np.float32)
    out, _ = run_layers(gpu_call, img, [blur_layer(12), vignette_layer()])
    assert np.all(np.isfinite(out)) and out.shape == img.shape


def test_8k_frame_through_cheap_and_separable_layers(penumbra, gpu_call):
    """An 8K (7680x4320) HDR frame through a blur and a vignette: the stack allocates its
    targets at that size, and the result matches the references at sampled pixels."""
    from penumbra.engine.post.vignette import vignette_factor

    h, w = 4320, 7680
    color = (2.0, 1.0, 0.5, 1.0)

    def job(engine, depsgraph):
        import gpu
        from penumbra.engine.post import PostContext, PostStack
        from penumbra.engine.renderer import FrameStats, texture_array
        from penumbra.shaders.loader import ShaderCache

        src = gpu.types.GPUTexture((w, h), format="RGBA32F")
        src.clear(format="FLOAT", value=color)  # no 500 MB upload from Python
        stats = FrameStats()
        ctx = PostContext(ShaderCache(), w, h, stats=stats)
        out = PostStack().run(ctx, src, [blur_layer(3), vignette_layer(0.9, 0.4)])
        return texture_array(out, 4)[::60, ::60].copy(), stats

    scenes.top_camera(scenes.empty_scene(8, 8))
    sampled, stats = gpu_call(job)
    assert stats.post_passes == 3
    rows = np.arange(0, h, 60)[:, None] + 0.5
    cols = np.arange(0, w, 60)[None, :] + 0.5
    f = vignette_factor(cols, rows, w, h, 0.9, 0.4, 1.0)
    expected = np.array(color[:3]) * (1 - f)[..., None]  # a blur of a flat image is the image
    np.testing.assert_allclose(sampled[..., :3], expected, rtol=1e-5, atol=1e-6)
