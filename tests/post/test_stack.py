"""The post stack as a whole: several layers, their order, an 8K frame, and layers driven by
the scene's layer properties through the production frame path."""

import bpy
import numpy as np
import pytest

from devkit import scenes
from devkit.post import blender_image, layer, run_flat, run_layers
from devkit.render import render


def test_mix_blends_and_zero_mix_is_identity(penumbra, gpu_call):
    rng = np.random.default_rng(3)
    img = rng.uniform(0, 1, (24, 40, 4)).astype(np.float32)
    full, _ = run_layers(gpu_call, img, [layer("VIGNETTE", radius=0.2, softness=0.3)])
    half, _ = run_layers(gpu_call, img, [layer("VIGNETTE", mix=0.25, radius=0.2, softness=0.3)])
    np.testing.assert_allclose(half, 0.75 * img + 0.25 * full, atol=1e-6)
    off = [layer("VIGNETTE", mix=0.0, radius=0.2, softness=0.3), layer("BLUR", radius=0, sigma=0.0)]
    none, stats = run_layers(gpu_call, img, off)
    np.testing.assert_array_equal(none, img)
    assert stats.post_passes == 0


def test_stack_order_matters(penumbra, gpu_call):
    from penumbra.engine.post.blur import gaussian_reference
    from penumbra.engine.post.vignette import vignette_factor

    rng = np.random.default_rng(4)
    img = rng.uniform(0, 1, (32, 48, 4)).astype(np.float32)
    blur, vignette = layer("BLUR", radius=4, sigma=0.0), layer("VIGNETTE", radius=0.1, softness=0.5)
    a, _ = run_layers(gpu_call, img, [blur, vignette])
    b, _ = run_layers(gpu_call, img, [vignette, blur])
    h, w = img.shape[:2]
    y, x = np.mgrid[0:h, 0:w] + 0.5
    f = vignette_factor(x, y, w, h, 0.1, 0.5, 1.0)[..., None]
    np.testing.assert_allclose(a[..., :3], gaussian_reference(img, 4)[..., :3] * (1 - f), atol=1e-5)
    np.testing.assert_allclose(
        b[..., :3],
        gaussian_reference(np.concatenate([img[..., :3] * (1 - f), img[..., 3:]], -1), 4)[..., :3],
        atol=1e-5,
    )


def test_8k_frame_through_cheap_and_separable_layers(penumbra, gpu_call):
    """An 8K (7680x4320) HDR frame through a blur and a vignette: the stack allocates its
    targets at that size, and the result matches the references at sampled pixels."""
    from penumbra.engine.post.vignette import vignette_factor

    h, w = 4320, 7680
    color = (2.0, 1.0, 0.5, 1.0)
    stack = [layer("BLUR", radius=3, sigma=0.0), layer("VIGNETTE", radius=0.9, softness=0.4)]
    ((sampled, stats),) = run_flat(gpu_call, w, h, color, [stack], step=60)  # cleared on the GPU
    assert stats.post_passes == 3
    rows = np.arange(0, h, 60)[:, None] + 0.5
    cols = np.arange(0, w, 60)[None, :] + 0.5
    f = vignette_factor(cols, rows, w, h, 0.9, 0.4, 1.0)
    expected = np.array(color[:3]) * (1 - f)[..., None]  # a blur of a flat image is the image
    np.testing.assert_allclose(sampled[..., :3], expected, rtol=1e-5, atol=1e-6)


def test_new_effects_as_scene_layers(penumbra, gpu_call):
    """The generated properties drive the effects: defaults through the real frame path."""
    from penumbra.engine.post import EFFECTS
    from penumbra.engine.scene.extract import camera_from_scene

    effect_ids = ["GLOW", "SCANLINES", "SEPIA", "PIXELATE", "NOISE"]
    scene = scenes.demo_scene(48, 32)
    for ob in scene.objects:
        if ob.type == "LIGHT":
            ob.data.use_shadow = False  # only the post stack matters here
    scene.penumbra.layers.clear()
    for eid in effect_ids:
        bpy.ops.penumbra.layer_add(effect=eid)
        defaults = EFFECTS[eid].defaults()
        params = scene.penumbra.layers[scene.penumbra.active_layer_index].params()
        for name, value in vars(defaults).items():
            assert getattr(params, name) == (value if isinstance(value, str) else pytest.approx(value))

    def render_frame(frame):
        scene.frame_current = frame

        def job(engine, depsgraph):
            cam = camera_from_scene(depsgraph, scene, 48, 32)
            out = engine.render_frame(depsgraph, cam, 48, 32)
            return out.stats, out.color_array().copy()

        return gpu_call(job)

    (stats, a), (_, b), (_, c) = render_frame(5), render_frame(5), render_frame(6)
    assert stats.post_layers == len(effect_ids)
    assert stats.post_passes == 2 + 1 + 3 + 1  # defaults: glow 2, scanlines + sepia 1, pixelate AVERAGE 3
    assert np.all(np.isfinite(a))
    np.testing.assert_array_equal(a, b)  # the scene's frame seeds the grain: reproducible
    assert not np.array_equal(a, c)


def test_image_parameters_through_layer_properties(penumbra):
    """The production path: layer properties (an Image pointer) -> render settings -> a final
    render. A 1 x 1 LUT recolours everything; a black lens image removes the flare."""
    scene = scenes.empty_scene(16, 12)
    scenes.top_camera(scene)
    scenes.set_world(scene, (0.5, 0.5, 0.5))
    lut = blender_image("LUT", np.array([[(0.2, 0.4, 0.8, 1.0)]], np.float32))
    dirt = blender_image("Dirt", np.zeros((2, 2, 4), np.float32))
    bpy.ops.penumbra.layer_add(effect="LENS_FLARE")
    bpy.ops.penumbra.layer_add(effect="COLORIZER")
    layers = scene.penumbra.layers
    assert [item.effect for item in layers] == ["COLORIZER", "LENS_FLARE"]
    layers[0].colorizer.image = lut
    layers[0].colorizer.blur_radius = 0
    layers[1].lens_flare.threshold = 0.0  # everything flares...
    layers[1].lens_flare.image = dirt  # ...through a black lens texture
    c = render(scene)["Combined"]
    np.testing.assert_allclose(c[..., :3], np.broadcast_to((0.2, 0.4, 0.8), c[..., :3].shape), atol=1e-6)
    layers[1].lens_flare.image = None  # the built-in ramp: now the flare shows
    c = render(scene)["Combined"]
    assert np.all(c[..., :3] > (0.2 + 1e-3, 0.4 + 1e-3, 0.8 + 1e-3))
