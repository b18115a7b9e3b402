"""Assets as Blender's own glTF importer builds them: a file written by Blender's exporter and
read back renders without a false warning, and what Penumbra does not draw of the imported
Principled BSDF is named."""

from pathlib import Path

import bpy
import numpy as np
import pytest

from devkit import scenes
from devkit.render import render

SIZE = 32


def _textured_plane(scene, name, uv_maps=("UVMap",)):
    """A plane whose Principled BSDF reads a Base Color image and a normal map (through a
    Normal Map node), on UV maps ``uv_maps`` (the first active for render)."""
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    ob = bpy.context.object
    ob.name = name
    for extra in uv_maps[1:]:
        ob.data.uv_layers.new(name=extra)
    ob.data.uv_layers[0].name = uv_maps[0]
    mat = scenes.material(f"{name}Mat", (0.8, 0.8, 0.8))
    tree = mat.node_tree
    bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    rng = np.random.default_rng(5)
    base = bpy.data.images.new(f"{name}Base", 16, 16, alpha=True)
    base.pixels.foreach_set(rng.random(16 * 16 * 4, dtype=np.float32))
    normal = bpy.data.images.new(f"{name}Normal", 16, 16, alpha=True)
    flat = np.tile(np.array([0.5, 0.5, 1.0, 1.0], np.float32), 16 * 16)
    normal.pixels.foreach_set(flat)
    normal.colorspace_settings.name = "Non-Color"
    tex = tree.nodes.new("ShaderNodeTexImage")
    tex.image = base
    tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    ntex = tree.nodes.new("ShaderNodeTexImage")
    ntex.image = normal
    nmap = tree.nodes.new("ShaderNodeNormalMap")
    tree.links.new(ntex.outputs["Color"], nmap.inputs["Color"])
    tree.links.new(nmap.outputs["Normal"], bsdf.inputs["Normal"])
    ob.data.materials.append(mat)
    return ob, nmap


def _lit_scene():
    scene = scenes.empty_scene(SIZE, SIZE)
    scenes.light(scene, "Sun", "SUN", 3.0)
    scenes.top_camera(scene, height=5.0, ortho_scale=2.0)
    return scene


def _penumbra_report(scene, capfd):
    """The render report's lines (Blender prints them on stdout in background mode)."""
    capfd.readouterr()
    scene.render.engine = "PENUMBRA"
    scene.penumbra.render_samples = 1
    image = render(scene)["Combined"]
    return image, capfd.readouterr().out


def test_a_gltf_round_trip_renders_without_a_uv_map_warning(penumbra, capfd, tmp_path):
    """Blender's exporter and importer: the imported Normal Map names the UV map ("UVMap")
    its images leave unnamed (the active render map), which is the same layer: no warning of
    several UV maps, and the normal map is read."""
    assert bpy.ops.preferences.addon_enable(module="io_scene_gltf2") == {"FINISHED"}
    from penumbra.engine.scene.materials import material_from_blender

    scene = _lit_scene()
    _textured_plane(scene, "Asset")
    path = Path(tmp_path) / "asset.glb"
    bpy.ops.export_scene.gltf(filepath=str(path), export_format="GLB", use_selection=True)
    imported = _lit_scene()
    with bpy.context.temp_override(scene=imported):
        bpy.ops.import_scene.gltf(filepath=str(path))
    plane = next(ob for ob in imported.objects if ob.type == "MESH")
    mat = plane.material_slots[0].material
    named = [n.uv_map for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeNormalMap"]
    assert named == ["UVMap"]  # what the importer writes (the case under test)
    read = material_from_blender(mat)
    assert "normal" in read.textures and not read.messages, read.messages
    image, report = _penumbra_report(imported, capfd)
    assert "several UV maps" not in report, report
    assert np.isfinite(image).all() and image[..., :3].max() > 0.05


def test_a_normal_map_on_another_uv_map_is_named(penumbra, capfd):
    """The counter-case: a Normal Map on the mesh's second UV map, its images on the active
    one, reads two layers: that is named."""
    scene = _lit_scene()
    _ob, nmap = _textured_plane(scene, "TwoMaps", uv_maps=("UVMap", "Detail"))
    nmap.uv_map = "Detail"
    _image, report = _penumbra_report(scene, capfd)
    assert "object 'TwoMaps': its materials read several UV maps" in report, report


@pytest.mark.parametrize("how", ["texture", "colour", "white"])
def test_specular_tint_is_drawn_and_not_named(penumbra, how):
    """glTF's specular-glossiness import drives Specular Tint with a texture: Penumbra draws
    it (a texture through the compiled tree, a colour in the read material) and names nothing."""
    from penumbra.engine.scene.materials import material_from_blender

    mat = scenes.material(f"Tint_{how}", (0.5, 0.5, 0.5))
    bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    if how == "texture":
        tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
        tex.image = bpy.data.images.new("TintImage", 4, 4)
        mat.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Specular Tint"])
    elif how == "colour":
        bsdf.inputs["Specular Tint"].default_value = (1.0, 0.5, 0.2, 1.0)
    read = material_from_blender(mat)
    assert not read.messages, read.messages
    assert (read.tree is not None) == (how == "texture")
    if how == "colour":
        assert read.specular_tint == pytest.approx((1.0, 0.5, 0.2))
        assert read.f0[:3] == pytest.approx((0.04, 0.02, 0.008))
