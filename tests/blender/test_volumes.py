"""Participating media (engine/scene/volumes.py, engine/frame/features/volumes.py) against
analytic references: Beer-Lambert through slabs (with Cycles' coefficients of each volume
shader), the airlight integral of a point light in homogeneous fog (devkit.volume_scenes,
numerically exact), the edges of a light shaft against the slit that makes it; a frame
without media unchanged; and the extremes (no density, huge density, anisotropy +-0.99, the
camera inside the medium, media past the clip range, a tiny and a flat box, a Volume object)."""

import math

import bpy
import numpy as np
import pytest

from devkit import scenes
from devkit import volume_scenes as vs
from devkit.render import render, technique_frame

W, H = 33, 33


def _slab_scene(**material):
    """An orthographic camera looking straight down at an emitting plane (radiance 1) through
    a 1-unit slab of the medium ``material`` (``volume_scenes.volume_material``): no light."""
    scene = scenes.empty_scene(W, H)
    scenes.plane(scene, "Floor", size=20.0, mat=scenes.emissive("Glow", 1.0))
    vs.fog_box(scene, "Slab", center=(0.0, 0.0, 1.0), size=(30.0, 30.0, 1.0), **material)
    scenes.top_camera(scene, height=5.0, ortho_scale=4.0)
    return scene


@pytest.mark.parametrize(
    "material, extinction",
    [
        (dict(kind="ABSORB", color=(0.0, 0.0, 0.0), density=0.7), (0.7, 0.7, 0.7)),
        # Volume Absorption: (1 - Color) x Density, per channel.
        (dict(kind="ABSORB", color=(0.2, 0.5, 0.9), density=2.0), (1.6, 1.0, 0.2)),
        # Volume Scatter: Color x Density (its extinction); no light, so nothing scattered in.
        (dict(kind="SCATTER", color=(0.3, 0.6, 0.9), density=1.5), (0.45, 0.9, 1.35)),
        # Principled Volume: Color x Density + max(1 - Color, 0) x max(1 - sqrt(Absorption
        # Color), 0) x Density.
        (
            dict(kind="PRINCIPLED", color=(0.5, 0.2, 0.8), density=1.2, **{"Absorption Color": (0.25, 0.0, 1.0, 1.0)}),
            (0.5 * 1.2 + 0.5 * 0.5 * 1.2, 0.2 * 1.2 + 0.8 * 1.2, 0.8 * 1.2),
        ),
    ],
)
def test_a_slab_lets_through_what_beer_lambert_says(penumbra, material, extinction):
    """Straight through a slab of thickness 1: exp(-extinction), within 0.5 %."""
    image = render(_slab_scene(**material))["Combined"]
    pixel = image[H // 2, W // 2, :3]
    expected = vs.slab_transmittance(extinction, 1.0)
    assert np.allclose(pixel, expected, rtol=0.005, atol=0.0), (pixel, expected)
    # The whole view crosses the same slab: the image is flat.
    assert np.ptp(image[..., :3], axis=(0, 1)).max() < 1e-4


def _fog_scene(g, samples, camera_inside=False):
    """A point light of 100 W (radius 0) in a cube of fog 8 units wide, no surface, the world
    black; the camera on the axis through the cube's centre."""
    scene = scenes.empty_scene(W, H)
    vs.fog_box(scene, "Fog", size=(8.0, 8.0, 8.0), kind="SCATTER", color=(1.0, 1.0, 1.0), density=0.15, anisotropy=g)
    scenes.light(scene, "Lamp", "POINT", 100.0, location=(0.0, 0.0, 1.0), shadow_soft_size=0.0)
    y = -2.0 if camera_inside else -10.0
    scenes.camera(scene, (0.0, y, 0.0), (math.pi / 2, 0.0, 0.0), lens=50.0, clip=(0.1, 100.0))
    scene.penumbra.render_samples = samples
    scene.penumbra.filter_size = 0.0
    scene.penumbra.use_adaptive_sampling = False
    return scene


@pytest.mark.parametrize("g, samples", [(0.0, 16), (0.7, 16), (-0.5, 16), (0.3, 1)])
def test_a_point_light_in_fog_gives_the_airlight_integral(penumbra, g, samples):
    """The centre pixel (its ray along the axis, through the cube from t = 6 to 14) against the
    single-scattering integral with Henyey-Greenstein g, within 1 % (one sample of the march
    too: its points are drawn in proportion to the transmittance, step by step)."""
    image = render(_fog_scene(g, samples))["Combined"]
    box = ((-4.0, -4.0, -4.0), (4.0, 4.0, 4.0))
    ref = vs.airlight((0, -10, 0), (0, 1, 0), 6.0, 14.0, (0, 0, 1.0), 100.0, 0.15, 0.15, g=g, box=box)
    pixel = image[H // 2, W // 2, :3]
    assert np.allclose(pixel, ref, rtol=0.01), (pixel, ref)


def test_the_camera_inside_the_fog_starts_the_integral_at_its_clip_start(penumbra):
    image = render(_fog_scene(0.0, 16, camera_inside=True))["Combined"]
    box = ((-4.0, -4.0, -4.0), (4.0, 4.0, 4.0))
    ref = vs.airlight((0, -2, 0), (0, 1, 0), 0.1, 6.0, (0, 0, 1.0), 100.0, 0.15, 0.15, box=box)
    pixel = image[H // 2, W // 2, :3]
    assert np.allclose(pixel, ref, rtol=0.01), (pixel, ref)


def test_a_world_volume_fills_the_view_to_the_clip_end(penumbra):
    """A World > Volume of pure absorption: an emitting plane 5 units away shows through
    exp(-sigma (5 - clip start)), and the world's colour behind it what is left of the clip end's
    sphere about the camera."""
    scene = scenes.empty_scene(W, H)
    scenes.set_world(scene, (1.0, 1.0, 1.0))
    scenes.plane(scene, "Panel", size=2.0, mat=scenes.emissive("Glow", 1.0))
    cam = scenes.camera(scene, (0.0, 0.0, 5.0), (0.0, 0.0, 0.0), ortho_scale=4.0, clip=(0.1, 8.0))
    tree = scene.world.node_tree
    node = tree.nodes.new("ShaderNodeVolumeAbsorption")
    node.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    node.inputs["Density"].default_value = 0.2
    out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld")
    tree.links.new(node.outputs[0], out.inputs["Volume"])
    image = render(scene)["Combined"][..., :3]
    assert cam.data.type == "ORTHO"
    assert np.allclose(image[H // 2, W // 2], math.exp(-0.2 * 4.9), rtol=0.005)
    # Pixel (1, 1) sees the world through the medium's sphere of the clip end about the camera,
    # from its clip start plane: r off the axis, sqrt(8^2 - r^2) - 0.1 of it.
    r = math.hypot(*((1.5 / W - 0.5) * 4.0, (1.5 / H - 0.5) * 4.0))
    assert np.allclose(image[1, 1], math.exp(-0.2 * (math.sqrt(64.0 - r * r) - 0.1)), rtol=0.005)


def test_a_light_shaft_has_the_edges_of_the_slit_it_comes_through(penumbra):
    """A sun straight down through a slit 1 unit wide (x in [-0.5, 0.5]) in an opaque roof over
    fog, seen side-on by an orthographic camera along +Y (4 units across 65 pixels): the
    in-scattered light fills the slit's columns, and its edges (half the shaft's height) lie
    within 1 pixel of x = -0.5 and 0.5."""
    w, h = 65, 33
    scene = scenes.empty_scene(w, h)
    dark = scenes.material("Roof", (0.0, 0.0, 0.0), specular=0.0)
    for x in (-5.5, 5.5):
        scenes.box(scene, f"Roof{x}", center=(x, 0.0, 2.05), size=(10.0, 10.0, 0.1), mat=dark)
    vs.fog_box(scene, "Fog", center=(0.0, 0.0, 0.0), size=(8.0, 2.0, 3.9), kind="SCATTER", density=0.3)
    scenes.light(scene, "Sun", "SUN", 3.0, angle=0.0)
    scenes.camera(scene, (0.0, -10.0, 0.0), (math.pi / 2, 0.0, 0.0), ortho_scale=4.0, clip=(0.1, 20.0))
    scene.penumbra.render_samples = 16
    scene.penumbra.shadow_map_size = 2048
    image = render(scene)["Combined"][..., 0]
    row = image[h // 2]
    lit = row > 0.5 * row.max()
    columns = np.flatnonzero(lit)
    assert row.max() > 0.01 and np.all(np.diff(columns) == 1)  # one shaft
    px = w / 4.0  # pixels per unit
    left, right = columns[0], columns[-1] + 1  # pixel edges of the lit run
    assert abs(left - (w / 2 - 0.5 * px)) <= 1.0 and abs(right - (w / 2 + 0.5 * px)) <= 1.0, (left, right)
    assert row[: int(w / 2 - 0.5 * px) - 2].max() < 0.02 * row.max()  # the roof's shadow holds


def test_surfaces_in_fog_take_their_lights_through_it(penumbra):
    """A sun-lit white floor under a slab of absorbing medium, seen from below the slab: the
    sun's light on the floor is what the slab lets through along the sun's direction."""
    scene = scenes.empty_scene(W, H)
    scenes.plane(scene, "Floor", size=20.0, mat=scenes.white())
    vs.fog_box(
        scene, "Slab", center=(0.0, 0.0, 3.0), size=(60.0, 60.0, 1.0), kind="ABSORB", color=(0, 0, 0), density=0.5
    )
    scenes.light(scene, "Sun", "SUN", 2.0, rotation=(0.5, 0.0, 0.0))
    scenes.camera(scene, (0.0, 0.0, 2.0), (0.0, 0.0, 0.0), ortho_scale=4.0, clip=(0.1, 10.0))
    image = render(scene)["Combined"][..., :3]
    unshadowed = scenes.WHITE_ALBEDO / math.pi * 2.0 * math.cos(0.5)
    expected = unshadowed * math.exp(-0.5 * 1.0 / math.cos(0.5))
    assert np.allclose(image[H // 2, W // 2], expected, rtol=0.01), (image[H // 2, W // 2], expected)


def test_a_frame_without_media_is_the_frame_before_volumes(penumbra, gpu_call):
    """No medium: the technique is not wanted, and the frame is bit for bit the frame of a
    renderer without it, with the same draws and passes."""
    scene = scenes.demo_scene(64, 40)
    on, stats_on, _ = technique_frame(gpu_call, scene, 64, 40, 4)
    off, stats_off, _ = technique_frame(gpu_call, scene, 64, 40, 4, without=("volumes",))
    assert "volumes" not in stats_on.techniques
    assert np.array_equal(on, off)
    assert (stats_on.draws, stats_on.passes) == (stats_off.draws, stats_off.passes)
    assert not any(
        "VOLUMES" in dict(k.program().defines) and dict(k.program().defines)["VOLUMES"] for k in stats_on.lit_keys
    )


def test_a_fog_frame_names_the_technique_and_its_approximations(penumbra, gpu_call):
    scene = _fog_scene(0.0, 4)
    _image, stats, _ = technique_frame(gpu_call, scene, W, H, 4)
    assert "volumes" in stats.techniques and "settling" not in stats.techniques
    assert any("single scattering" in m for m in stats.messages)


@pytest.mark.parametrize(
    "case",
    ["density 0", "density 1e4", "g 0.99", "g -0.99", "tiny box", "flat box", "past the clip range", "volume object"],
)
def test_the_extremes_render_finite_non_negative_frames(penumbra, case):
    """Each renders (the harness checks every frame is finite and >= 0) and keeps what it must:
    no density is no medium; a huge one hides what is behind it; the phase's extremes stay
    finite looking into and away from the light; a tiny box is marched; a flat box and a Volume
    object are named, not drawn."""
    scene = _fog_scene(0.0, 4)
    fog = bpy.data.materials["Fog"].node_tree.nodes["Volume Scatter"]
    box = bpy.data.objects["Fog"]
    if case == "density 0":
        fog.inputs["Density"].default_value = 0.0
    elif case == "density 1e4":
        fog.inputs["Density"].default_value = 1e4
        scenes.plane(scene, "Back", size=30.0, mat=scenes.emissive("Glow", 1.0)).location = (0.0, 0.0, 0.0)
        bpy.data.objects["Back"].rotation_euler = (math.pi / 2, 0.0, 0.0)
        bpy.data.objects["Back"].location = (0.0, 10.0, 0.0)
    elif case.startswith("g "):
        fog.inputs["Anisotropy"].default_value = float(case[2:])
    elif case == "tiny box":
        box.scale = (1e-4, 1e-4, 1e-4)
    elif case == "flat box":
        box.scale = (1.0, 0.0, 1.0)
    elif case == "past the clip range":
        box.scale = (1e4, 1e4, 1e4)
    else:
        volume = bpy.data.volumes.new("Smoke")
        volume.filepath = "//missing.vdb"
        scenes.link(scene, bpy.data.objects.new("Smoke", volume))
    result = render(scene)["Combined"][..., :3]
    centre = result[H // 2, W // 2]
    assert np.all(np.isfinite(result)) and result.min() >= 0.0
    if case == "density 0":
        assert result.max() == 0.0
    elif case == "density 1e4":
        assert centre.max() < 1e-6  # the emitting wall behind is hidden, the lamp's light scattered at the front only
    elif case.startswith("g "):
        assert centre.max() > 0.0
    elif case == "past the clip range":
        assert centre.max() > 0.0  # marched from the clip start to the clip end


def test_the_volume_light_view_shows_the_media_light_alone(penumbra, gpu_call):
    """Debug view Volume Light: in the fog with no surface it is the whole frame; over an
    emitting floor behind an absorbing slab (nothing scattered, nothing emitted) it is black."""
    from penumbra.engine.scene.extract import camera_from_scene

    def frame(scene, view):
        scene.penumbra.debug_view = view

        def job(engine, depsgraph):
            cam = camera_from_scene(depsgraph, scene, W, H)
            out = engine.render_frame(depsgraph, cam, W, H, samples=(0, 4), sample_count=4, aux=False)
            return out.lit_array().copy() if view == "NONE" else out.debug.image.copy()

        return gpu_call(job)[..., :3]

    fog = _fog_scene(0.3, 4)
    shown = frame(fog, "VOLUME_LIGHT")
    np.testing.assert_allclose(shown, frame(fog, "NONE"), rtol=1e-5, atol=1e-7)
    assert shown.max() > 0.01
    slab = _slab_scene(kind="ABSORB", color=(0.0, 0.0, 0.0), density=0.7)
    assert frame(slab, "VOLUME_LIGHT").max() == 0.0
    assert frame(slab, "NONE").max() > 0.4


def _glow(strength):
    """The emitting floor's strength (``scenes.emissive``)."""
    bsdf = next(n for n in bpy.data.materials["Glow"].node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Emission Strength"].default_value = strength


def _shader_slab(build):
    """``_slab_scene`` over a black floor, the slab's tree built by ``build(tree, output)``."""
    scene = _slab_scene(kind="ABSORB", density=0.0)
    _glow(0.0)
    tree = bpy.data.materials["Slab"].node_tree
    for node in [n for n in tree.nodes if n.bl_idname != "ShaderNodeOutputMaterial"]:
        tree.nodes.remove(node)
    build(tree, next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"))
    return scene


def test_emitting_and_mixed_media_follow_the_closures_sums(penumbra):
    """Add Shader (absorption 2 + emission 0.6) over a black floor: the slab's own light,
    e / a (1 - exp(-a)); Mix Shader at 0.25 of absorptions 1 and 3 over the emitting floor:
    exp(-1.5)."""

    def emitting(tree, out):
        absorb = tree.nodes.new("ShaderNodeVolumeAbsorption")
        absorb.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        absorb.inputs["Density"].default_value = 2.0
        glow = tree.nodes.new("ShaderNodeEmission")
        glow.inputs["Strength"].default_value = 0.6
        add = tree.nodes.new("ShaderNodeAddShader")
        tree.links.new(absorb.outputs[0], add.inputs[0])
        tree.links.new(glow.outputs[0], add.inputs[1])
        tree.links.new(add.outputs[0], out.inputs["Volume"])

    pixel = render(_shader_slab(emitting))["Combined"][H // 2, W // 2, :3]
    assert np.allclose(pixel, 0.6 / 2.0 * (1.0 - math.exp(-2.0)), rtol=0.005), pixel

    def mixed(tree, out):
        mix = tree.nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = 0.25
        for slot, density in ((1, 1.0), (2, 3.0)):
            absorb = tree.nodes.new("ShaderNodeVolumeAbsorption")
            absorb.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
            absorb.inputs["Density"].default_value = density
            tree.links.new(absorb.outputs[0], mix.inputs[slot])
        tree.links.new(mix.outputs[0], out.inputs["Volume"])

    scene = _shader_slab(mixed)
    _glow(1.0)
    pixel = render(scene)["Combined"][H // 2, W // 2, :3]
    assert np.allclose(pixel, math.exp(-1.5), rtol=0.005), pixel


def test_a_volume_input_fed_by_a_node_is_named(penumbra):
    """A Density from a texture: drawn at the socket's value, and the material says so."""
    from penumbra.engine.scene.materials import material_from_blender

    mat = vs.volume_material("Smoke", kind="PRINCIPLED", density=0.5)
    noise = mat.node_tree.nodes.new("ShaderNodeTexNoise")
    mat.node_tree.links.new(noise.outputs["Fac"], mat.node_tree.nodes["Principled Volume"].inputs["Density"])
    read = material_from_blender(mat)
    assert not read.surface and read.volume is not None
    assert np.allclose(read.volume.extinction, 0.5)  # the socket's own value
    assert any("Density is fed by a node" in m for m in read.messages), read.messages
    from penumbra.engine.scene.materials import summary

    lines = [text for _icon, text in summary(read)]
    assert any(t.startswith("Volume: its interior alone") and "extinction 0.5" in t for t in lines), lines
