"""Post-layer operators, .blend round-trip, registration, pass counting and the geometry cache."""

import bpy
import numpy as np
import pytest

from devkit import scenes
from devkit.render import engine_frame


def _effects(scene):
    return [layer.effect for layer in scene.penumbra.layers]


def test_layer_operators(penumbra):
    scene = scenes.empty_scene(32, 32)
    assert bpy.ops.penumbra.layer_remove.poll() is False  # nothing to remove
    bpy.ops.penumbra.layer_add(effect="VIGNETTE")
    bpy.ops.penumbra.layer_add(effect="BLUR")
    s = scene.penumbra
    assert _effects(scene) == ["BLUR", "VIGNETTE"]  # added above the active layer
    assert s.active_layer_index == 0
    s.layers[0].blur.radius = 7
    bpy.ops.penumbra.layer_duplicate()
    assert _effects(scene) == ["BLUR", "BLUR", "VIGNETTE"]
    assert s.layers[1].blur.radius == 7 and s.active_layer_index == 1
    bpy.ops.penumbra.layer_move(direction="DOWN")
    assert _effects(scene) == ["BLUR", "VIGNETTE", "BLUR"] and s.active_layer_index == 2
    assert bpy.ops.penumbra.layer_move(direction="DOWN") == {"CANCELLED"}  # already at the bottom
    bpy.ops.penumbra.layer_move(direction="UP")
    bpy.ops.penumbra.layer_remove()
    assert _effects(scene) == ["BLUR", "VIGNETTE"]
    assert s.active_layer_index == 1


def test_settings_survive_save_and_reload(penumbra, tmp_path):
    scene = scenes.demo_scene(32, 32)
    s = scene.penumbra
    s.shadow_filter = "NONE"
    s.shadow_map_size = 777
    s.pcf_spacing = 2.5
    s.layers[1].vignette.color = (0.25, 0.5, 0.75)
    s.layers[0].enabled = False
    s.active_layer_index = 1
    path = str(tmp_path / "roundtrip.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert len(bpy.context.scene.penumbra.layers) == 0
    bpy.ops.wm.open_mainfile(filepath=path)
    s = bpy.context.scene.penumbra
    assert (s.shadow_filter, s.shadow_map_size, s.pcf_spacing) == ("NONE", 777, 2.5)
    assert [(layer.effect, layer.name, layer.enabled) for layer in s.layers] == [
        ("BLUR", "Soft focus", False),
        ("VIGNETTE", "Vignette", True),
    ]
    assert tuple(s.layers[1].vignette.color) == pytest.approx((0.25, 0.5, 0.75))
    assert s.layers[0].blur.radius == 3 and s.active_layer_index == 1


def test_unregister_removes_everything_then_register_restores(penumbra):
    from penumbra import operators, properties, ui
    from penumbra.engine import render_engine

    names = [c.__name__ for m in (properties, operators.layers, operators.presets, ui.panels) for c in m.classes]
    names.append("PENUMBRA_PT_shadows")

    def engines():
        try:
            bpy.context.scene.render.engine = "PENUMBRA"
            return {"PENUMBRA"}
        except TypeError:
            return set()

    assert "PENUMBRA" in engines()
    assert "PENUMBRA" in bpy.types.RENDER_PT_format.COMPAT_ENGINES
    penumbra.unregister()
    try:
        assert not hasattr(bpy.types.Scene, "penumbra")
        assert "PENUMBRA" not in engines()
        for name in names:
            assert not hasattr(bpy.types, name), name
        assert "PENUMBRA" not in bpy.types.RENDER_PT_format.COMPAT_ENGINES
        assert "PENUMBRA" not in bpy.types.DATA_PT_light.COMPAT_ENGINES
    finally:
        penumbra.register()
    assert hasattr(bpy.types.Scene, "penumbra") and "PENUMBRA" in engines()
    assert render_engine.PenumbraRenderEngine.bl_idname == "PENUMBRA"


def test_disabled_and_zero_mix_layers_cost_no_pass(penumbra, gpu_call):
    scene = scenes.demo_scene(64, 36)
    blur, vig = scene.penumbra.layers
    full, img_full = engine_frame(gpu_call, scene, 64, 36)
    assert full.post_passes == 3  # blur: 2 separable passes, vignette: 1
    blur.enabled = False
    s1, _ = engine_frame(gpu_call, scene, 64, 36)
    assert s1.post_passes == 1
    vig.mix = 0.0
    s2, img_none = engine_frame(gpu_call, scene, 64, 36)
    assert s2.post_passes == 0
    blur.enabled, blur.blur.radius = True, 0  # radius 0 is the identity
    s3, img_r0 = engine_frame(gpu_call, scene, 64, 36)
    assert s3.post_passes == 0
    np.testing.assert_array_equal(img_none, img_r0)
    assert not np.array_equal(img_full, img_none)


def test_geometry_cache_rebuilds_only_changed_meshes(penumbra, gpu_call):
    """One engine instance (as in the viewport): a second frame re-extracts nothing; editing
    one mesh re-extracts that mesh only."""
    scene = scenes.demo_scene(64, 36)

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        cam = camera_from_scene(depsgraph, scene, 64, 36)
        engine.render_frame(depsgraph, cam, 64, 36)
        first = engine.cache.built
        engine.render_frame(depsgraph, cam, 64, 36)
        second = engine.cache.built - first
        engine.cache.invalidate({scene.objects["Ball"].data.name_full})
        engine.render_frame(depsgraph, cam, 64, 36)
        third = engine.cache.built - first - second
        return first, second, third

    first, second, third = gpu_call(job)
    assert first == 5 and second == 0 and third == 1


def test_solo_shows_only_soloed_layers(penumbra, gpu_call):
    scene = scenes.demo_scene(64, 36)
    blur, vig = scene.penumbra.layers
    blur.enabled = False
    blur.solo = True  # solo overrides the enable switch, and hides the other layers
    stats, img_solo = engine_frame(gpu_call, scene, 64, 36)
    assert stats.post_passes == 2
    vig.enabled, blur.solo = False, False
    blur.enabled = True
    stats, img_blur_only = engine_frame(gpu_call, scene, 64, 36)
    np.testing.assert_array_equal(img_solo, img_blur_only)
