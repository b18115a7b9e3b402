"""Blender's further passes (engine/frame/features/passes.py, engine/frame/cryptomatte.py): data
passes checked against the scene's geometry, colour passes against the material's own terms,
Shader AOVs against their nodes, Cryptomatte through Blender's own compositor node. Every
render runs in a child process: render-result writes (passes, metadata) must fail a test, not
the run."""

import textwrap

import numpy as np
import pytest

from devkit.analytic import erode
from devkit.session import run_result

# How far the film's filter mixes a pixel with its neighbours at the default Filter Size (the
# gathering film's reach): an averaged pass is a surface's own this far inside its outline.
REACH = 2
INSIDE = 2 * REACH  # erode's cross takes a diagonal neighbour two steps away

SCENE = """
import json, os, tempfile
import numpy as np
import bpy
from devkit import imageio, scenes, session
session.load_penumbra().register()
TMP = tempfile.mkdtemp()
W, H = 96, 64
WORLD = (0.2, 0.3, 0.4)

scene = scenes.empty_scene(W, H)
scenes.set_world(scene, WORLD)
red = scenes.material("Red", (0.8, 0.1, 0.1), roughness=0.4)
red.pass_index = 3
tree = red.node_tree
for name, kind, value in (("mask", "Value", 0.25), ("cover", "Value", 1.0), ("tint", "Color", (0.1, 0.6, 0.3, 1.0))):
    node = tree.nodes.new("ShaderNodeOutputAOV")
    node.aov_name = name
    if kind == "Color":  # through a node: the AOV compiles with the tree
        rgb = tree.nodes.new("ShaderNodeRGB")
        rgb.outputs[0].default_value = value
        tree.links.new(rgb.outputs[0], node.inputs["Color"])
    else:
        node.inputs["Value"].default_value = value
box = scenes.box(scene, "Box", center=(0.0, 0.0, 0.5), size=(1.0, 1.0, 1.0), mat=red)
box.pass_index = 7
rig = bpy.data.objects.new("Rig", None)
scene.collection.objects.link(rig)
blue = scenes.material("Blue", (0.1, 0.2, 0.8), metallic=1.0, roughness=0.3)
ball = scenes.uv_sphere(scene, "Ball", center=(0.0, 0.0, 0.0), radius=0.4, mat=blue)
ball.parent = rig
rig.location = (1.2, 0.6, 0.4)
floor = scenes.plane(scene, "Floor", size=6.0, mat=scenes.material("Grey", (0.5, 0.5, 0.5)))
scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.5, 0.2, 0.0))
scenes.look_at(scene, (3.0, -3.5, 2.6), (0.2, 0.0, 0.3))
layer = scene.view_layers[0]
layer.name = "ViewLayer"
for aov_name, kind in (("mask", "VALUE"), ("cover", "VALUE"), ("tint", "COLOR"), ("unset", "VALUE")):
    aov = layer.aovs.add()
    aov.name, aov.type = aov_name, kind

# Blender 4.5's pass names, as its own engines register them, by 5.0's.
OLD_NAMES = {"IndexOB": "Object Index", "IndexMA": "Material Index", "DiffCol": "Diffuse Color",
             "GlossCol": "Glossy Color", "TransCol": "Transmission Color", "Env": "Environment",
             "DiffDir": "Diffuse Direct", "DiffInd": "Diffuse Indirect", "GlossDir": "Glossy Direct",
             "GlossInd": "Glossy Indirect", "TransDir": "Transmission Direct", "Emit": "Emission"}

def render(name, samples, compositor=False):
    scene.penumbra.render_samples = samples
    imageio.set_format(scene.render.image_settings, "OPEN_EXR_MULTILAYER", color_depth="32", exr_codec="ZIP")
    path = os.path.join(TMP, name + ".exr")
    scene.render.filepath = path
    scene.render.use_file_extension = False
    scene.render.use_compositing = compositor
    bpy.ops.render.render(write_still=True)
    layers = imageio.read_exr_layers(path)
    return {k: {OLD_NAMES.get(p, p): a[::-1] for p, a in v.items()} for k, v in layers.items()}

def compositor():
    # The scene's compositor tree, emptied: (tree, its output node, a Render Layers node).
    # Blender 5.0 made the tree a node group with a Group Output; 4.5 has the scene's own tree.
    if bpy.app.version >= (5, 0, 0):
        comp = bpy.data.node_groups.new("Comp", "CompositorNodeTree")
        scene.compositing_node_group = comp
        out_node = comp.nodes.new("NodeGroupOutput")
        comp.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    else:
        scene.use_nodes = True
        comp = scene.node_tree
        comp.nodes.clear()
        out_node = comp.nodes.new("CompositorNodeComposite")
    rl = comp.nodes.new("CompositorNodeRLayers")
    rl.scene = scene
    return comp, out_node, rl

def save(**arrays):
    path = os.path.join(TMP, "out.npz")
    np.savez(path, **arrays)
    print("RESULT " + json.dumps({"npz": path}))
    session.hard_exit(0)
"""


def child(body):
    result, output = run_result(textwrap.dedent(SCENE) + textwrap.dedent(body), timeout=600)
    with np.load(result["npz"]) as data:
        return {k: data[k] for k in data.files}, output


@pytest.fixture(scope="module")
def data_passes():
    """One 8-sample render with every data and colour pass and the Shader AOVs."""
    out, _ = child(
        """
        for p in ("use_pass_position", "use_pass_object_index", "use_pass_material_index", "use_pass_diffuse_color",
                  "use_pass_glossy_color", "use_pass_transmission_color", "use_pass_environment", "use_pass_z"):
            setattr(layer, p, True)
        layer.penumbra.use_pass_denoising = True
        (passes,) = render("data", 8).values()
        save(**{k.replace(" ", "_"): v for k, v in passes.items()})
        """
    )
    return out


def test_position_and_indices_are_the_centred_samples_surfaces(data_passes):
    """Position lies on the surface the centred sample saw (the box's faces, the floor's plane,
    the ball's sphere); Object and Material Index are the Pass Index of what covers the pixel
    there, exactly; the background holds 0 in each."""
    pos, depth = data_passes["Position"], data_passes["Depth"][..., 0]
    index, material = data_passes["Object_Index"][..., 0], data_passes["Material_Index"][..., 0]
    background = depth > 1e9
    assert background.any() and not background.all()
    assert np.all(pos[background] == 0.0) and np.all(index[background] == 0.0) and np.all(material[background] == 0.0)
    on_box = np.abs(pos - (0.0, 0.0, 0.5)).max(-1)
    ball = np.linalg.norm(pos - (1.2, 0.6, 0.4), axis=-1)
    box_px = (index == 7) & ~background
    assert box_px.sum() > 100
    np.testing.assert_allclose(on_box[box_px], 0.5, atol=2e-3)  # on a face of the unit box
    assert np.all(material[box_px] == 3.0)
    rest = ~box_px & ~background
    assert np.all(index[rest] == 0.0) and np.all(material[rest] == 0.0)
    floor_px = rest & (np.abs(pos[..., 2]) < 2e-3)
    ball_px = rest & (np.abs(ball - 0.4) < 5e-3)
    assert floor_px.sum() > 1000 and ball_px.sum() > 30
    assert (floor_px | ball_px).sum() >= rest.sum() - 2  # every other surface pixel is the floor's or ball's


def test_colour_passes_follow_the_material_and_add_to_the_denoising_albedo(data_passes):
    """Diffuse Color is the base colour with the specular layer's energy taken out (so it has
    the base colour's hue and lies below it); a metal has none and a Glossy Color of its own
    hue; a dielectric's Glossy Color is grey; Denoising Albedo is their sum; Environment is the
    world where no surface is and 0 on surfaces."""
    diff, gloss = data_passes["Diffuse_Color"], data_passes["Glossy_Color"]
    index, depth = data_passes["Object_Index"][..., 0], data_passes["Depth"][..., 0]
    interior = erode(index == 7, INSIDE)
    d = diff[interior]
    np.testing.assert_allclose(d / d[:, :1], np.broadcast_to((1.0, 0.125, 0.125), d.shape), rtol=1e-3)
    assert np.all(d[:, 0] < 0.8) and np.all(d[:, 0] > 0.6)
    g = gloss[interior]
    np.testing.assert_allclose(g, np.broadcast_to(g[:, :1], g.shape), rtol=1e-4)
    assert np.all((g > 0.03) & (g < 0.25))
    pos = data_passes["Position"]
    ball = erode(np.abs(np.linalg.norm(pos - (1.2, 0.6, 0.4), axis=-1) - 0.4) < 5e-3, INSIDE)
    assert ball.sum() > 20
    assert np.all(diff[ball] < 1e-6)  # a metal has no diffuse
    bg = gloss[ball]
    assert np.all(bg[:, 2] > bg[:, 0])  # its reflectance is its base colour's
    albedo = diff + gloss + data_passes["Transmission_Color"]
    np.testing.assert_allclose(data_passes["Denoising_Albedo"], albedo, atol=1e-5)
    assert np.all(data_passes["Transmission_Color"] == 0.0)  # nothing transmits
    env = data_passes["Environment"]
    background = depth > 1e9
    sky = erode(background, INSIDE)
    np.testing.assert_allclose(env[sky], np.broadcast_to((0.2, 0.3, 0.4), env[sky].shape), atol=1e-6)
    assert np.all(env[erode(~background, INSIDE)] == 0.0)  # averaged with the filter: edges mix, inside is 0
    # Denoising Normal inside each face of the box is the face's normal (the faces from Position).
    rel = data_passes["Position"] - (0.0, 0.0, 0.5)
    axis = np.abs(rel).argmax(-1)
    sign = np.sign(np.take_along_axis(rel, axis[..., None], -1)[..., 0])
    faces = 0
    for a in range(3):
        for sgn in (-1.0, 1.0):
            face = erode((data_passes["Object_Index"][..., 0] == 7) & (axis == a) & (sign == sgn), INSIDE)
            if face.sum() > 10:
                faces += 1
                expected = np.zeros(3)
                expected[a] = sgn
                normals = data_passes["Denoising_Normal"][face]
                np.testing.assert_allclose(normals, np.broadcast_to(expected, normals.shape), atol=1e-4)
    assert faces >= 2  # the third face is a thin strip at this size


def test_shader_aovs_write_what_their_nodes_give_and_zero_elsewhere(data_passes):
    """A value AOV is its node's Value on the material that writes it, a colour AOV its
    node's Color (through an RGB node), and both are 0 where no material writes them; an AOV no
    material writes is 0 everywhere. Averaged with the filter like Combined."""
    index = data_passes["Object_Index"][..., 0]
    interior, far = erode(index == 7, INSIDE), erode(index != 7, INSIDE)
    mask, tint = data_passes["mask"][..., 0], data_passes["tint"]
    np.testing.assert_allclose(mask[interior], 0.25, atol=1e-6)
    assert np.all(mask[far] == 0.0)
    np.testing.assert_allclose(tint[interior][:, :3], np.broadcast_to((0.1, 0.6, 0.3), (interior.sum(), 3)), atol=1e-6)
    assert np.all(tint[far][:, :3] == 0.0)
    assert np.all(data_passes["unset"] == 0.0)
    assert 0.0 < mask.mean() < 0.25


def test_a_frame_without_further_passes_has_no_pass_draw_and_one_with_them_draws_each_group_once():
    """Nothing asked, nothing drawn: the technique is not in the frame. With passes, each
    sample draws the seen surfaces once more per group of six passes (and the centred sample's
    group once a frame)."""
    out, _ = child(
        """
        from devkit.session import GpuRunner
        from penumbra.engine.scene.extract import camera_from_scene
        runner = GpuRunner()
        runner.register()
        def job(passes):
            def run(engine, depsgraph):
                cam = camera_from_scene(depsgraph, scene, W, H)
                out = engine.render_frame(depsgraph, cam, W, H, samples=(0, 4), sample_count=4, passes=passes)
                return out.stats.draws, list(out.stats.techniques), sorted(out.passes)
            return runner(run)
        bare = job(())
        some = job(("DIFFUSE_COLOR", "ENVIRONMENT", "AOV_VALUE:mask"))
        more = job(("DIFFUSE_COLOR", "ENVIRONMENT", "AOV_VALUE:mask", "POSITION"))
        save(draws=np.array([bare[0], some[0], more[0]]), bare_has=np.array("passes" in bare[1]),
             some_has=np.array("passes" in some[1]), keys=np.array(more[2]))
        """
    )
    bare, some, more = (int(x) for x in out["draws"])
    assert not bool(out["bare_has"]) and bool(out["some_has"])
    per_sample = (some - bare) / 4  # one group every sample
    assert per_sample >= 3 and per_sample == int(per_sample)
    assert more - some == per_sample  # the centred sample's group: once a frame
    assert {"DIFFUSE_COLOR", "ENVIRONMENT", "AOV_VALUE:mask", "POSITION"} <= set(out["keys"].tolist())


def test_blenders_cryptomatte_node_picks_an_objects_filtered_coverage_from_the_render():
    """Blender's compositor, in background mode, reads Penumbra's Cryptomatte layers and
    manifest: its Cryptomatte node's matte for "Box" is the box's coverage through the film's
    filter and its motion over the shutter (the "cover" AOV, 1 on the box, averaged like
    Combined) within 0.02, edges and motion blur included; the Ball's asset is its parent's
    (Rig)."""
    out, _output = child(
        """
        layer.use_pass_cryptomatte_object = layer.use_pass_cryptomatte_asset = True
        layer.use_pass_cryptomatte_material = True
        box = bpy.data.objects["Box"]  # moving over the shutter: its matte smears
        for frame, x in ((1, -0.4), (3, 0.4)):
            box.location.x = x
            box.keyframe_insert("location", frame=frame)
        scene.frame_set(2)
        scene.render.use_motion_blur = True
        comp, out_node, rl = compositor()
        mattes = []
        for source, name in (("ViewLayer.CryptoObject", "Box"), ("ViewLayer.CryptoAsset", "Rig"),
                             ("ViewLayer.CryptoMaterial", "Grey")):
            node = comp.nodes.new("CompositorNodeCryptomatteV2")
            node.source, node.scene, node.layer_name, node.matte_id = "RENDER", scene, source, name
            comp.links.new(rl.outputs["Image"], node.inputs[0])
            mattes.append(node)
        comb = comp.nodes.new("CompositorNodeCombineColor")
        for i, node in enumerate(mattes):
            comp.links.new(node.outputs["Matte"], comb.inputs[i])
        comp.links.new(comb.outputs[0], out_node.inputs[0])
        layers = render("crypto", 16, compositor=True)
        passes = layers[("ViewLayer", "")]
        composite = next(v for k, v in layers.items() if k[0] != "ViewLayer")
        import OpenImageIO as oiio
        header = oiio.ImageInput.open(os.path.join(TMP, "crypto.exr"))
        meta = {a.name: str(a.value) for a in header.spec().extra_attribs if a.name.startswith("cryptomatte/")}
        header.close()
        save(matte=composite["Combined"], cover=passes["cover"], crypto=passes["CryptoObject00"],
             meta=np.array(json.dumps(meta)))
        """
    )
    matte, cover = out["matte"], out["cover"][..., 0]
    box = matte[..., 0]
    assert cover.max() == pytest.approx(1.0) and (cover > 0.999).sum() > 100
    assert float(np.abs(box - cover).mean()) < 0.02
    edges = (cover > 0.02) & (cover < 0.98)
    assert edges.sum() > 20
    assert float(np.abs(box - cover)[edges].mean()) < 0.05
    rig = matte[..., 1]
    assert rig.max() > 0.99 and float((rig > 0.5).sum()) > 30
    assert float((matte[..., 2] > 0.99).sum()) > 500  # the floor's material
    # The manifest is in the file's header, under Cycles' keys: what Nuke's Cryptomatte reads.
    import json

    from penumbra.engine.frame import cryptomatte

    meta = json.loads(str(out["meta"]))
    prefix = f"cryptomatte/{cryptomatte.name_hash('ViewLayer.CryptoObject'):08x}"[:19]
    assert meta[f"{prefix}/name"] == "ViewLayer.CryptoObject" and meta[f"{prefix}/hash"] == "MurmurHash3_32"
    manifest = json.loads(meta[f"{prefix}/manifest"])
    assert manifest["Box"] == f"{cryptomatte.name_hash('Box'):08x}" and {"Ball", "Floor"} <= set(manifest)
    assert len([k for k in meta if k.endswith("/name")]) == 3  # object, material, asset
    # Coverages of a pixel's ranks add up to at most its whole weight.
    crypto = out["crypto"]
    assert np.all(crypto[..., 1] + crypto[..., 3] <= 1.0 + 1e-5) and np.all(crypto[..., 1] >= crypto[..., 3])


LIGHT_SCENE = """
glass = scenes.material("Glass", (0.9, 0.95, 1.0), roughness=0.05)
glass.node_tree.nodes["Principled BSDF"].inputs["Transmission Weight"].default_value = 1.0
scenes.uv_sphere(scene, "Glass", center=(-1.2, 0.6, 0.45), radius=0.45, mat=glass)
scenes.box(scene, "Lamp", center=(0.2, -1.2, 0.15), size=(0.3, 0.3, 0.3), mat=scenes.emissive("Glow", 2.0))
scenes.light(scene, "Area", "AREA", 200.0, location=(-2.0, -2.0, 3.0), size=1.0)
blue.node_tree.nodes["Principled BSDF"].inputs["Roughness"].default_value = 0.05  # a mirror: traced rays
scene.penumbra.indirect_bounces = 1
for p in ("diffuse_direct", "diffuse_indirect", "diffuse_color", "glossy_direct", "glossy_indirect", "glossy_color",
          "transmission_direct", "transmission_color", "emit", "environment"):
    setattr(layer, "use_pass_" + p, True)
"""


def test_light_passes_add_up_to_combined_per_pixel_and_leave_it_as_it_was():
    """Cycles' algebra: (Diffuse Direct + Indirect) x Diffuse Color + (Glossy Direct +
    Indirect) x Glossy Color + Transmission Direct x Color + Emission + Environment is Combined
    before the post stack, per pixel within 1e-3, in a frame with the world's ratio estimator,
    an area light, a mirror's traced rays, glass and the diffuse bounce; each pass is finite and
    >= 0; and asking for the passes leaves Combined bit for bit as it is without them."""
    out, _ = child(
        LIGHT_SCENE
        + textwrap.dedent(
            """
        (passes,) = render("light", 8).values()
        for p in ("diffuse_direct", "diffuse_indirect", "diffuse_color", "glossy_direct", "glossy_indirect",
                  "glossy_color", "transmission_direct", "transmission_color", "emit", "environment"):
            setattr(layer, "use_pass_" + p, False)
        for aov in list(layer.aovs):
            layer.aovs.remove(aov)
        (bare,) = render("bare", 8).values()
        save(bare=bare["Combined"], **{k.replace(" ", "_"): v for k, v in passes.items()})
        """
        )
    )

    def g(name):
        return out[name.replace(" ", "_")][..., :3].astype(np.float64)

    for name in out:
        assert np.all(np.isfinite(out[name])) and out[name].min() >= 0.0, name
    total = (g("Diffuse Direct") + g("Diffuse Indirect")) * g("Diffuse Color")
    total += (g("Glossy Direct") + g("Glossy Indirect")) * g("Glossy Color")
    total += g("Transmission Direct") * g("Transmission Color") + g("Emission") + g("Environment")
    np.testing.assert_allclose(total, g("Combined"), atol=1e-3)
    for name in ("Diffuse Indirect", "Glossy Indirect", "Transmission Direct", "Emission"):
        assert g(name).max() > 0.05, name  # each carries light here
    np.testing.assert_array_equal(out["Combined"], out["bare"])


def test_the_passes_hold_a_sheen_and_a_coat_over_black_bases():
    """A sheen over a black base (the box) and a coat over a black base without specular (the
    ball): their light is in the Diffuse and Glossy passes, whose colours hold the sheen's and
    the coat's albedo as Cycles' do, so the algebra adds up to Combined within 1e-3 and the
    Diffuse Direct pass carries the sheen's light (with a Diffuse Color of 0 it had none)."""
    out, _ = child(
        LIGHT_SCENE
        + textwrap.dedent(
            """
        b = red.node_tree.nodes["Principled BSDF"]
        b.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        b.inputs["Sheen Weight"].default_value = 1.0
        b.inputs["Sheen Roughness"].default_value = 0.5
        b = blue.node_tree.nodes["Principled BSDF"]
        b.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        b.inputs["Metallic"].default_value = 0.0
        b.inputs["Specular IOR Level"].default_value = 0.0
        b.inputs["Coat Weight"].default_value = 1.0
        (passes,) = render("layers", 4).values()
        save(**{k.replace(" ", "_"): v for k, v in passes.items()})
        """
        )
    )

    def g(name):
        return out[name.replace(" ", "_")][..., :3].astype(np.float64)

    total = (g("Diffuse Direct") + g("Diffuse Indirect")) * g("Diffuse Color")
    total += (g("Glossy Direct") + g("Glossy Indirect")) * g("Glossy Color")
    total += g("Transmission Direct") * g("Transmission Color") + g("Emission") + g("Environment")
    np.testing.assert_allclose(total, g("Combined"), atol=1e-3)
    assert (g("Diffuse Direct") * g("Diffuse Color")).max() > 0.01  # the sheen's light
    assert (g("Glossy Direct") * g("Glossy Color")).max() > 0.01  # the coat's


def test_light_groups_add_up_to_combined_and_each_holds_its_own_light():
    """Light groups: the sun in "key", the area light and the world in "fill", the glowing
    box's emission in "glow". Their passes add up to Combined before the post stack (surfaces
    rough enough that no traced ray adds the scene's reflection), "glow" is the box's emission
    alone, and "key" is the frame lit by the sun alone (the others switched off)."""
    out, output = child(
        """
        for mat in (red, blue, bpy.data.materials["Grey"]):
            mat.node_tree.nodes["Principled BSDF"].inputs["Roughness"].default_value = 0.8
        lamp = scenes.emissive("Glow", 2.0)
        glow = scenes.box(scene, "Glow", center=(0.2, -1.2, 0.15), size=(0.3, 0.3, 0.3), mat=lamp)
        area = scenes.light(scene, "Area", "AREA", 200.0, location=(-2.0, -2.0, 3.0), size=1.0)
        for name in ("key", "fill", "glow"):
            layer.lightgroups.add(name=name)
        bpy.data.objects["Sun"].lightgroup, area.lightgroup, glow.lightgroup = "key", "fill", "glow"
        scene.world.lightgroup = "fill"
        (passes,) = render("groups", 8).values()
        for aov in list(layer.aovs):
            layer.aovs.remove(aov)
        area.hide_render = True
        glow.data.materials[0] = bpy.data.materials["Grey"]
        scenes.set_world(scene, (0.0, 0.0, 0.0))
        (sun,) = render("sun", 8).values()
        save(sun=sun["Combined"], **{k.replace(" ", "_"): v for k, v in passes.items()})
        """
    )
    # The frame may trace rays (its materials are node trees): the report names what groups leave out.
    assert "Penumbra: light group passes hold each group's direct light" in output
    key, fill, glow = out["Combined_key"], out["Combined_fill"], out["Combined_glow"]
    np.testing.assert_allclose(key + fill + glow, out["Combined"][..., :3], atol=1e-4)
    assert glow.max() == pytest.approx(2.0, abs=1e-5) and np.all(glow[glow > 0.0] <= 2.0 + 1e-5)
    box = (glow > 0.0).any(-1)
    assert 0 < box.sum() < 200  # the box's own pixels (and their filtered edge)
    # The same sun, though its map may be packed at another size beside fewer lights.
    np.testing.assert_allclose(key[~box], out["sun"][..., :3][~box], atol=5e-3)
    assert np.abs(key[~box] - out["sun"][..., :3][~box]).mean() < 2e-4
    assert fill.min() >= 0.0 and fill.mean() > 0.1


def test_vector_pass_matches_cycles_and_blenders_vector_blur_smears_as_with_cycles():
    """The box moves along x (and up at the end) while the camera pans: Penumbra's Vector pass
    (the centred sample's surfaces) matches Cycles' Vector pass of the same frame within
    0.01 px at the median and 0.05 px on average (edges differ: Cycles averages its samples),
    and Blender's Vector Blur node, fed with it, changes Penumbra's image as it changes Cycles'
    fed with Cycles' pass (the same smear: cosine above 0.85, the same size within 30 %)."""
    out, _ = child(
        """
        box = bpy.data.objects["Box"]
        for f, x in ((1, -0.6), (2, 0.0), (3, 0.6)):
            box.location = (x, 0.0, 0.5)
            box.keyframe_insert("location", frame=f)
        cam = scene.camera
        for f, dx in ((1, -0.1), (2, 0.0), (3, 0.1)):
            cam.location.x = 3.0 + dx
            cam.keyframe_insert("location", frame=f)
        scene.frame_set(2)
        for aov in list(layer.aovs):
            layer.aovs.remove(aov)
        layer.use_pass_vector = layer.use_pass_z = True
        comp, out_node, rl = compositor()
        blur = comp.nodes.new("CompositorNodeVecBlur")
        comp.links.new(rl.outputs["Image"], blur.inputs["Image"])
        comp.links.new(rl.outputs["Depth"], blur.inputs[1])
        comp.links.new(rl.outputs["Vector"], blur.inputs[2])
        comp.links.new(blur.outputs[0], out_node.inputs[0])
        layers = render("vector", 4, compositor=True)
        penumbra = layers[("ViewLayer", "")]
        blurred = next(v for k, v in layers.items() if k[0] != "ViewLayer")["Combined"]
        scene.render.use_motion_blur = True  # the centred sample's draws are then the moved ones
        blurred_vector = render("vector_blur", 4)[("ViewLayer", "")]["Vector"]
        scene.render.use_motion_blur = False
        scene.render.engine = "CYCLES"
        scene.cycles.samples, scene.cycles.max_bounces, scene.cycles.use_denoising = 16, 0, False
        layers = render("cycles", 16, compositor=True)
        cycles = layers[("ViewLayer", "")]
        cycles_blurred = next(v for k, v in layers.items() if k[0] != "ViewLayer")["Combined"]
        save(vector=penumbra["Vector"], cycles=cycles["Vector"], image=penumbra["Combined"], blurred=blurred,
             vector_blur=blurred_vector,
             cycles_image=cycles["Combined"], cycles_blurred=cycles_blurred)
        """
    )
    diff = np.abs(out["vector"] - out["cycles"])
    assert np.abs(out["cycles"]).max() > 2.0  # the box moves pixels a frame
    assert np.median(diff) < 0.01 and diff.mean() < 0.05
    # With motion blur on (Cycles then writes none) the pass is the centred sample's, drawn at its
    # time in the shutter (an eighth of a frame from the frame's own with 4 samples): near the same.
    assert np.abs(out["vector_blur"]).max() > 2.0
    assert np.abs(out["vector_blur"] - out["vector"]).mean() < 0.2
    # What the blur changes of Penumbra's image is what it changes of Cycles' (same motion).
    ours = (out["blurred"] - out["image"])[..., :3].ravel().astype(np.float64)
    theirs = (out["cycles_blurred"] - out["cycles_image"])[..., :3].ravel().astype(np.float64)
    assert np.abs(theirs).mean() > 0.003  # (4.5's node blurs less than 5.x's)
    assert ours @ theirs / (np.linalg.norm(ours) * np.linalg.norm(theirs)) > 0.85
    assert 0.7 < np.abs(ours).mean() / np.abs(theirs).mean() < 1.4


def test_uv_pass_matches_cycles_and_a_mesh_without_a_map_reads_zero():
    """The UV pass is each surface's active render UV map at the pixel (meshes whose materials
    read no image included), within 1e-3 of Cycles' UV pass at the median; a mesh without a UV
    map writes (0, 0)."""
    out, _ = child(
        """
        for aov in list(layer.aovs):
            layer.aovs.remove(aov)
        for ob in (bpy.data.objects["Box"], bpy.data.objects["Floor"]):
            while len(ob.data.uv_layers):
                ob.data.uv_layers.remove(ob.data.uv_layers[0])
            ob.data.uv_layers.new(name="Map")
            for i, loop in enumerate(ob.data.loops):
                co = ob.data.vertices[loop.vertex_index].co
                ob.data.uv_layers[0].data[i].uv = (co.x / 7.0 + 0.5, co.y / 7.0 + 0.5 + 0.1 * co.z)
        ball = bpy.data.objects["Ball"]
        while len(ball.data.uv_layers):
            ball.data.uv_layers.remove(ball.data.uv_layers[0])
        layer.use_pass_uv = layer.use_pass_object_index = True
        ball.pass_index = 5
        ours = render("uv", 4)[("ViewLayer", "")]
        scene.render.engine = "CYCLES"
        scene.cycles.samples, scene.cycles.max_bounces, scene.cycles.use_denoising = 16, 0, False
        theirs = render("cycles", 16)[("ViewLayer", "")]
        save(uv=ours["UV"], cycles=theirs["UV"], index=ours["Object Index"])
        """
    )
    ball = erode(out["index"][..., 0] == 5, INSIDE)
    rest = out["index"][..., 0] != 5
    diff = np.abs(out["uv"] - out["cycles"])[rest]
    assert np.abs(out["cycles"]).max() > 0.5
    assert np.median(diff) < 1e-3 and diff.mean() < 0.01
    # (u, v) where there is no map: the reader gives the channels in U, A, V order.
    assert ball.sum() > 10 and np.all(out["uv"][ball][:, [0, 2]] == 0.0)


def test_light_passes_add_up_where_pixels_settle():
    """Lamps without a world over rough spheres: settling keeps its pilot's value in the pixels
    it settles (features/settling.py), and the passes keep the pilot's too, so the algebra
    still holds per pixel within 1e-3 (without the pilot's passes: 0.03 here)."""
    from devkit.session import run_result as run

    result, _ = run(
        textwrap.dedent(
            """
            import json
            import numpy as np
            from devkit import session
            session.load_penumbra().register()
            from tools.benchmarks import passes as bench
            scene = bench.lamps(96, 54)
            bench._switch(scene, bench.LIGHT)
            scene.view_layers[0].penumbra.use_pass_lit = True
            scene.penumbra.render_samples = 16
            import tempfile, os
            d = bench._render(scene, os.path.join(tempfile.mkdtemp(), "lamps.exr"))
            g = lambda k: bench._pass(d, k)
            total = sum((g(f"{k} Direct") + g(f"{k} Indirect")) * g(f"{k} Color") for k in ("Diffuse", "Glossy"))
            total = total + g("Transmission Direct") * g("Transmission Color") + g("Emission") + g("Environment")
            print("RESULT " + json.dumps({"error": float(np.abs(total - g("Combined")).max()),
                                          "lit": float(g("Combined").mean())}))
            session.hard_exit(0)
            """
        ),
        timeout=600,
    )
    assert result["lit"] > 0.1 and result["error"] < 1e-3
