"""What a view layer overrides and filters is honoured in a final render: Override > Material,
World and Samples, Filter > Environment, Surfaces, Curves and Motion Blur, each against the
render of a scene set up to be what the view layer asks for. Renders run in a child process."""

import textwrap

import numpy as np

from devkit.session import run_result

BODY = """
import json, os, tempfile
import numpy as np
import bpy
from devkit import imageio, scenes, session
session.load_penumbra().register()
TMP = tempfile.mkdtemp()
scene = scenes.empty_scene(64, 48)
scenes.set_world(scene, (0.2, 0.3, 0.4))
red = scenes.material("Red", (0.8, 0.1, 0.1), roughness=0.4)
box = scenes.box(scene, "Box", center=(0.0, 0.0, 0.5), size=(1.0, 1.0, 1.0), mat=red)
floor = scenes.plane(scene, "Floor", size=6.0, mat=scenes.material("Grey", (0.5, 0.5, 0.5)))
scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.5, 0.2, 0.0))
scenes.look_at(scene, (3.0, -3.5, 2.6), (0.2, 0.0, 0.3))
scene.penumbra.render_samples = 4
layer = scene.view_layers[0]
clay = scenes.material("Clay", (0.6, 0.6, 0.55), roughness=0.8)
other = bpy.data.worlds.new("Other")
other.use_nodes = True
other.node_tree.nodes["Background"].inputs["Color"].default_value = (0.6, 0.2, 0.1, 1.0)
results = {}

def render(name):
    imageio.set_format(scene.render.image_settings, "OPEN_EXR", color_depth="32", exr_codec="ZIP")
    path = os.path.join(TMP, name + ".exr")
    scene.render.filepath = path
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True)
    results[name] = imageio.read_exr(path)["Combined"]

render("plain")
layer.material_override = clay
render("override_material")
layer.material_override = None
for ob in (box, floor):
    ob.material_slots[0].material = clay
render("all_clay")
box.material_slots[0].material = red
floor.material_slots[0].material = bpy.data.materials["Grey"]
layer.world_override = other
render("override_world")
layer.world_override = None
world = scene.world
scene.world = other
render("other_world")
scene.world = world
layer.samples = 2
render("override_samples")
layer.samples = 0
scene.penumbra.render_samples = 2
render("two_samples")
scene.penumbra.render_samples = 4
layer.use_sky = False
render("no_environment")
layer.use_sky = True
layer.use_solid = False
render("no_surfaces")
layer.use_solid = True
box.location.x = 0.0
box.keyframe_insert("location", frame=1)
box.location.x = 0.6
box.keyframe_insert("location", frame=2)
scene.frame_set(1)
scene.render.use_motion_blur = True
render("blurred")
layer.use_motion_blur = False
render("blur_filtered")
scene.render.use_motion_blur = False
render("not_blurred")
path = os.path.join(TMP, "out.npz")
np.savez(path, **results)
print("RESULT " + json.dumps({"npz": path}))
session.hard_exit(0)
"""


def test_view_layer_overrides_and_filters_render_what_they_ask_for():
    result, _ = run_result(textwrap.dedent(BODY), timeout=600)
    with np.load(result["npz"]) as data:
        r = {k: data[k] for k in data.files}
    # Override > Material: every object drawn with it, as if each slot held it.
    assert np.abs(r["override_material"] - r["plain"]).max() > 0.05
    np.testing.assert_array_equal(r["override_material"], r["all_clay"])
    # Override > World: the scene lit and seen through that world.
    np.testing.assert_array_equal(r["override_world"], r["other_world"])
    # Override > Samples: the layer's count instead of the scene's.
    np.testing.assert_array_equal(r["override_samples"], r["two_samples"])
    # Filter > Environment off: the background is transparent (RGBA 0), the surfaces lit as before.
    plain, bare = r["plain"], r["no_environment"]
    sky = np.all(np.abs(plain - (0.2, 0.3, 0.4, 1.0)) < 1e-6, axis=-1)
    assert sky.sum() > 50 and np.all(bare[sky] == 0.0)
    covered = bare[..., 3] == 1.0
    assert covered.sum() > 1000
    np.testing.assert_allclose(bare[covered][:, :3], plain[covered][:, :3], atol=1e-6)
    # Filter > Surfaces off: only the world is seen.
    np.testing.assert_allclose(r["no_surfaces"], np.broadcast_to((0.2, 0.3, 0.4, 1.0), plain.shape), atol=1e-6)
    # Filter > Motion Blur off: as with motion blur off, and unlike the blurred render.
    assert np.abs(r["blurred"] - r["not_blurred"]).max() > 0.05
    np.testing.assert_array_equal(r["blur_filtered"], r["not_blurred"])
