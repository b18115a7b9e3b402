"""Bad or degenerate input renders with a clear message, never a crash or a traceback."""

import math

import bpy
import numpy as np
import pytest

from devkit import scenes
from devkit.render import render


def _lit_scene(size=48):
    scene = scenes.empty_scene(size, size)
    scenes.set_world(scene, (0.1, 0.1, 0.1))
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(30), 0, 0))
    scenes.top_camera(scene, height=10.0, ortho_scale=6.0)
    return scene


def test_missing_camera_is_a_clear_error(penumbra):
    scene = scenes.empty_scene(16, 16)
    scenes.plane(scene)
    with pytest.raises(RuntimeError, match="(?i)camera"):
        bpy.ops.render.render()


def test_empty_scene_renders_world_colour(penumbra):
    scene = _lit_scene()
    c = render(scene, passes=("Combined", "Depth"))
    np.testing.assert_allclose(c["Combined"][..., :3], 0.1, rtol=1e-6)
    assert np.all(c["Depth"] == 1e10)


def test_meshes_without_faces_and_zero_scale(penumbra):
    scene = _lit_scene()
    scenes.mesh_object(scene, "Edges", [(0, 0, 0), (1, 0, 0), (1, 1, 0)], [])
    flat = scenes.box(scene, "Flat", center=(0, 0, 1))
    flat.scale = (0.0, 0.0, 0.0)
    squashed = scenes.box(scene, "Squashed", center=(1.5, 0, 1), size=(1, 1, 1))
    squashed.scale = (1.0, 1.0, 0.0)  # a zero-thickness box: normals must stay finite
    c = render(scene)["Combined"]
    assert np.all(np.isfinite(c))
    # The squashed box is a visible, lit square (its top normal survives zero z-scale).
    assert c[..., 0].max() > 0.5


def test_nan_vertices_are_skipped_with_a_message(penumbra, capfd):
    scene = _lit_scene()
    ob = scenes.box(scene, "Broken", center=(0, 0, 1))
    ob.data.vertices[0].co = (float("nan"), 0.0, 0.0)
    ob.data.vertices[1].co = (float("inf"), 0.0, 0.0)
    scenes.plane(scene, mat=scenes.material("W", (0.8, 0.8, 0.8), specular=0.0))
    c = render(scene)["Combined"]
    assert np.all(np.isfinite(c))
    assert "non-finite" in capfd.readouterr().err


def test_curves_and_text_render_as_meshes(penumbra):
    scene = _lit_scene(64)
    text = bpy.data.curves.new("Text", "FONT")
    text.body = "P"
    text.size = 4.0
    ob = bpy.data.objects.new("Text", text)
    ob.location = (-1.2, -1.5, 0.5)
    scene.collection.objects.link(ob)
    c = render(scene)["Combined"]
    bg = 0.1
    covered = np.abs(c[..., 0] - bg) > 0.05
    assert 0.03 < covered.mean() < 0.6  # the glyph shows up, lit


def test_huge_shadow_map_is_clamped_with_a_message(penumbra, capfd):
    scene = _lit_scene()
    scenes.plane(scene)
    scenes.box(scene, center=(0, 0, 1))
    scene.penumbra.shadow_map_size = 1_000_000  # above any GPU's maximum
    scene.penumbra.shadow_texels_per_pixel = 0.0  # every map at that size (not what the pixels need)
    c = render(scene)["Combined"]
    assert np.all(np.isfinite(c))
    captured = capfd.readouterr()
    assert "clamped to" in captured.out + captured.err  # the render report
    scene.penumbra.shadow_map_size = 1
    c = render(scene)["Combined"]
    assert np.all(np.isfinite(c))


def test_negative_scale_and_instances_render_like_originals(penumbra):
    """A mirrored (negative-scale) box and a collection instance of a box shade exactly like
    the plain box: normals stay outward, instance matrices are applied."""
    scene = scenes.empty_scene(96, 32)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(20), math.radians(10), 0))
    scenes.camera(scene, (0, 0, 10), (0, 0, 0), ortho_scale=9.0, clip=(0.1, 20))
    mat = scenes.material("M", (0.6, 0.6, 0.6), roughness=1.0, specular=0.0)
    scenes.box(scene, "Plain", center=(-3, 0, 0), mat=mat)
    mirrored = scenes.box(scene, "Mirrored", center=(0, 0, 0), mat=mat)
    mirrored.scale = (-1.0, 1.0, 1.0)
    coll = bpy.data.collections.new("Src")
    src = scenes.box(scene, "Source", center=(0, 0, 0), mat=mat)
    scene.collection.objects.unlink(src)
    coll.objects.link(src)
    inst = bpy.data.objects.new("Instance", None)
    inst.instance_type = "COLLECTION"
    inst.instance_collection = coll
    inst.location = (3, 0, 0)
    scene.collection.objects.link(inst)
    scene.penumbra.shadow_filter = "NONE"
    c = render(scene)["Combined"][..., 0]
    # Pixel columns at the three box centres (ortho scale 9 over 96 px: 1 m = 96/9 px).
    px = lambda x: int(round((x + 4.5) * 96 / 9.0))  # noqa: E731
    plain, mirror, instance = c[16, px(-3)], c[16, px(0)], c[16, px(3)]
    assert plain > 0.1
    assert mirror == pytest.approx(plain, rel=1e-5)
    assert instance == pytest.approx(plain, rel=1e-5)
