"""The Properties editor shows what works: Blender's generic panels minus the features
Penumbra ignores, the EEVEE panels that edit what it reads, and its own Film and Passes;
optional passes exist only when switched on."""

import bpy
import numpy as np
import pytest

from devkit import scenes
from devkit.render import render

SHOWN = [
    "RENDER_PT_format", "RENDER_PT_output", "RENDER_PT_color_management", "RENDER_PT_stereoscopy",
    "DATA_PT_EEVEE_light", "DATA_PT_camera", "DATA_PT_lens", "DATA_PT_context_mesh", "DATA_PT_vertex_colors",
    "EEVEE_MATERIAL_PT_surface", "EEVEE_WORLD_PT_surface", "OBJECT_PT_visibility", "OBJECT_PT_custom_props",
    "OBJECT_PT_shading",  # holds Light Linking and Shadow Linking
    "OBJECT_PT_shadow_terminator",  # Geometry, Shading and (drawn by compat) Normal Offset
    "PHYSICS_PT_add", "PARTICLE_PT_context_particles", "PENUMBRA_PT_film", "PENUMBRA_PT_passes",
    "DATA_PT_camera_dof", "DATA_PT_camera_dof_aperture",  # depth of field by lens sampling
    "PENUMBRA_PT_motion_blur", "PENUMBRA_PT_motion_blur_curve",  # Blender's motion blur settings
    "PENUMBRA_PT_world_sun",  # EEVEE's World > Sun: threshold, angle, shadow
    "DATA_PT_context_lightprobe", "PENUMBRA_PT_lightprobe",  # Plane probes: planar reflections
]  # fmt: skip
HIDDEN = [
    "DATA_PT_light",  # would repeat the light type switch
    "RENDER_PT_freestyle", "DATA_PT_lightprobe", "RENDER_PT_eevee_motion_blur", "VIEWLAYER_PT_layer_passes",
]  # fmt: skip


def _panel(name):
    """The registered panel class ``name``, however deep among Panel's subclasses."""
    pending = list(bpy.types.Panel.__subclasses__())
    while pending:
        panel = pending.pop()
        if panel.__name__ == name:
            return panel
        pending.extend(panel.__subclasses__())
    return None


@pytest.mark.parametrize("name", SHOWN)
def test_panels_that_work_are_shown(penumbra, name):
    panel = _panel(name)
    assert panel is not None, f"{name} does not exist in Blender {bpy.app.version_string}"
    assert "PENUMBRA" in panel.COMPAT_ENGINES


@pytest.mark.parametrize("name", HIDDEN)
def test_panels_of_ignored_features_are_hidden(penumbra, name):
    panel = _panel(name) or _panel(name.replace("eevee_", "eevee_next_"))
    if panel is None:
        pytest.skip(f"{name} does not exist in Blender {bpy.app.version_string}")
    assert "PENUMBRA" not in getattr(panel, "COMPAT_ENGINES", set())


def test_shadow_terminator_panel_draws_all_three_offsets(penumbra):
    """Blender's Shadow Terminator panel draws Geometry and Shading Offset for an engine other
    than EEVEE; Penumbra also honours EEVEE's Normal Offset, drawn by a hook of its own."""
    from penumbra.ui import compat

    panel = _panel("OBJECT_PT_shadow_terminator")
    assert compat.draw_normal_offset in panel._dyn_ui_initialize()
    scene = scenes.empty_scene(8, 8)
    sphere = scenes.uv_sphere(scene, segments=8, rings=4)
    context = type("Context", (), {"object": sphere, "engine": "PENUMBRA"})
    assert panel.poll(context)  # its poll reads COMPAT_ENGINES, which now holds PENUMBRA


def test_every_shown_panel_is_generic_or_chosen(penumbra):
    from penumbra.ui import compat

    # Some panels share one COMPAT_ENGINES set with the panel they derive from.
    chosen = [
        getattr(p, "COMPAT_ENGINES", None) for p in bpy.types.Panel.__subclasses__() if p.__name__ in compat.INCLUDE
    ]
    for panel in bpy.types.Panel.__subclasses__():
        engines = getattr(panel, "COMPAT_ENGINES", set())
        if "PENUMBRA" in engines and not panel.__name__.startswith("PENUMBRA_"):
            assert "BLENDER_RENDER" in engines or any(engines is c for c in chosen), panel.__name__


def test_shadow_pass_exists_only_when_switched_on(penumbra):
    scene = scenes.empty_scene(24, 16)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.6, 0.3, 0.0))
    scenes.box_over_plane(scene)
    scenes.top_camera(scene)
    assert "Shadow" not in render(scene, passes=("Combined",))
    with_pass = render(scene, passes=("Combined", "Shadow"))
    assert with_pass["Shadow"].shape == (16, 24, 1)
    assert 0.0 <= with_pass["Shadow"].min() < 0.5 < with_pass["Shadow"].max() <= 1.0  # the box's shadow


def test_lit_pass_is_the_image_before_the_post_stack_and_lines_up_with_depth(penumbra):
    """With a FISHEYE layer, Combined is warped but Lit is the unwarped lit image: equal to a
    render without post layers, so it lines up with Depth."""
    scene = scenes.demo_scene(48, 32)
    scene.penumbra.layers.clear()
    plain = render(scene, passes=("Combined", "Depth"))
    layer = scene.penumbra.layers.add()
    layer.effect = "FISHEYE"
    layer.fisheye.strength = 0.8
    warped = render(scene, passes=("Combined", "Depth", "Lit"))
    assert "Lit" not in plain
    np.testing.assert_array_equal(warped["Lit"], plain["Combined"])
    np.testing.assert_array_equal(warped["Depth"], plain["Depth"])
    assert np.abs(warped["Combined"] - plain["Combined"]).max() > 0.05


@pytest.mark.parametrize("falloff", ["QUADRATIC", "LINEAR", "INVERSE_QUADRATIC"])
def test_mist_pass_matches_cycles(penumbra, falloff):
    """Blender's Mist pass (distance from the camera, the world's start, depth and falloff)
    against Cycles' on the same scene, away from silhouettes; the background is 1."""
    from devkit import engines

    scene = scenes.empty_scene(64, 40)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.5, 0.2, 0.0))
    scenes.box_over_plane(scene, plane_size=8.0)
    scenes.look_at(scene, (5.0, -7.0, 3.0), (0.0, 0.0, 0.5))
    scene.world.mist_settings.start, scene.world.mist_settings.depth = 4.0, 9.0
    scene.world.mist_settings.falloff = falloff
    scene.view_layers[0].use_pass_mist = True
    ours = render(scene)["Mist"][..., 0]
    engines.configure(scene, "CYCLES", samples=1)
    scene.view_layers[0].use_pass_mist = True
    ref = render(scene)["Mist"][..., 0]
    scene.render.engine = "PENUMBRA"
    edges = np.zeros_like(ref, bool)
    for axis in (0, 1):
        jump = np.abs(np.diff(ref, axis=axis)) > 0.06  # a silhouette, not the smooth ramp
        pad = [(0, 0), (0, 0)]
        pad[axis] = (0, 1)
        edges |= np.pad(jump, pad)
        pad[axis] = (1, 0)
        edges |= np.pad(jump, pad)
    background = ref >= 1.0 - 1e-6
    inside = ~edges & ~background
    assert inside.mean() > 0.25 and 0.05 < ref[inside].mean() < 0.95  # the ramp is in view
    np.testing.assert_allclose(ours[inside], ref[inside], atol=2e-3)
    assert np.all(ours[background & ~edges] == 1.0)


def test_normal_pass_matches_cycles(penumbra):
    """World-space shading normals (facing the camera) against Cycles' Normal pass, away from
    silhouettes: a plane, a box and a smooth sphere; the background is 0."""
    from devkit import engines

    scene = scenes.empty_scene(64, 40)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.5, 0.2, 0.0))
    scenes.box_over_plane(scene, plane_size=6.0, box_center=(-1.0, 0.0, 0.5))
    sphere = scenes.uv_sphere(scene, center=(1.2, 0.3, 0.8), radius=0.8, segments=48, rings=24)
    for poly in sphere.data.polygons:
        poly.use_smooth = True
    scenes.look_at(scene, (5.0, -7.0, 4.0), (0.0, 0.0, 0.3))
    scene.view_layers[0].use_pass_normal = True
    ours = render(scene)["Normal"]
    engines.configure(scene, "CYCLES", samples=1)
    scene.view_layers[0].use_pass_normal = True
    ref = render(scene)["Normal"]
    scene.render.engine = "PENUMBRA"
    diff = np.abs(np.diff(ref, axis=0)).max(-1)
    edges = np.zeros(ref.shape[:2], bool)
    edges[1:] |= diff > 0.1
    edges[:-1] |= diff > 0.1
    diff = np.abs(np.diff(ref, axis=1)).max(-1)
    edges[:, 1:] |= diff > 0.1
    edges[:, :-1] |= diff > 0.1
    background = np.abs(ref).max(-1) == 0.0
    inside = ~edges & ~background
    assert inside.mean() > 0.15  # ground, box faces and sphere in view
    np.testing.assert_allclose(ours[inside], ref[inside], atol=5e-3)
    assert np.all(ours[background & ~edges] == 0.0)


class _Layout:
    """Records what a panel's ``draw`` asks of its layout (properties, labels)."""

    def __init__(self):
        self.props, self.labels = [], []
        self.use_property_split = self.use_property_decorate = False

    def prop(self, data, name, **_kw):
        assert hasattr(data, name), name  # a property the datablock has, in this Blender
        self.props.append(name)

    def label(self, text="", **_kw):
        self.labels.append(text)

    def column(self, **_kw):
        return self

    row = column


@pytest.mark.parametrize(
    "kind, shown",
    [
        ("PLANE", ["influence_distance", "clip_start"]),
        ("SPHERE", ["influence_type", "influence_distance", "falloff", "clip_start", "clip_end"]),
        ("VOLUME", []),
    ],
)
def test_the_probe_panel_shows_what_penumbra_reads(penumbra, kind, shown):
    """Penumbra's Probe panel draws a Plane probe's influence and clipping offset (planar
    reflections), a Sphere probe's influence and clip range (its cube map), and says a Volume
    probe is not used."""
    import types

    panel = _panel("PENUMBRA_PT_lightprobe")
    probe = bpy.data.lightprobes.new(kind, kind)
    layout = _Layout()
    panel.draw(
        types.SimpleNamespace(layout=layout, split_layout=lambda: layout), types.SimpleNamespace(lightprobe=probe)
    )
    assert layout.props == shown
    assert bool(layout.labels) == (not shown)
