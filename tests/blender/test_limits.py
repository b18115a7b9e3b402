"""Scenes beyond the GPU tables: which lights are kept is decided by their contribution, and
the render report says what was left out (never only stderr, never silently)."""

import bpy
import numpy as np

from devkit import scenes
from devkit.render import render


def _grid_of_lights(scene, count, energy, shadow):
    for i in range(count):
        x, y = (i % 8) - 3.5, (i // 8) - 3.5
        scenes.light(scene, f"L{i:03d}", "POINT", energy, location=(x, y, 3.0), use_shadow=shadow)


def test_lights_beyond_the_table_drop_the_weakest_and_say_so(penumbra, capfd):
    scene = scenes.empty_scene(48, 48)
    scenes.plane(scene)
    scenes.top_camera(scene, height=10.0, ortho_scale=10.0)
    _grid_of_lights(scene, 64, 50.0, shadow=False)
    # A 65th light, far away and faint, created first so depsgraph order would keep it.
    faint = scenes.light(scene, "A_faint", "POINT", 0.001, location=(500.0, 0.0, 3.0), use_shadow=False)
    with_faint = render(scene)["Combined"]
    captured = capfd.readouterr()
    assert "65 lights; only the 64 that contribute most" in captured.out + captured.err
    bpy.data.objects.remove(faint)
    without = render(scene)["Combined"]
    np.testing.assert_array_equal(with_faint, without)  # the faint one is the one left out
    captured = capfd.readouterr()
    assert "contribute most" not in captured.out + captured.err  # 64 lights: nothing to say


def test_more_shadow_maps_than_the_atlas_holds_is_reported(penumbra, capfd):
    scene = scenes.empty_scene(32, 32)
    # A solid ground (a flat one shadows nothing and would need no map), all of it in view.
    scenes.box(scene, "Ground", center=(0, 0, -0.5), size=(10.0, 10.0, 1.0))
    scenes.box(scene, center=(0, 0, 0.5))
    scenes.top_camera(scene, height=10.0, ortho_scale=10.0)
    _grid_of_lights(scene, 32, 20.0, shadow=True)  # 32 point lights, several cube faces each: > 96 tiles
    scene.penumbra.shadow_map_size = 64
    c = render(scene)["Combined"]
    assert np.all(np.isfinite(c))
    captured = capfd.readouterr()
    assert "left unshadowed: more than 96 shadow maps" in captured.out + captured.err


def test_material_preview_falls_back_to_eevee_like_cycles(penumbra):
    engine = penumbra.engine.render_engine.PenumbraRenderEngine
    assert engine.bl_use_eevee_viewport is True
    assert bpy.types.RenderEngine.bl_rna_get_subclass_py("PENUMBRA") is engine  # the registered class
