"""The world's light with visibility (issue 33): the short version of ``tools.bench world``.

``sky_outdoor`` (objects on a ground under a uniform sky) and ``window_room`` (a closed room
lit through one window) from ``devkit.world_scenes`` at 160x90, Penumbra against Cycles with
max_bounces 0 (the world's direct light, with visibility) at 256 spp through the same pixel
filter; error is the mean absolute difference of display RGB ('Standard' view, 0..1). The
references are cached in out/reference_cache (rendered once when missing: about 15 s).

Measured on 5.2 (MAE at 64 samples): outdoors 0.008 (0.050 with the world unoccluded, as
before World > Shadows), under the rotated HDRI 0.008 (0.031), in the room through its portal
0.021 (0.768 unoccluded: the room as bright as the sky); the outdoor one-sample frame (ambient
occlusion) is within 0.04 of the 64-sample one.
"""

import functools

import numpy as np
import pytest

from devkit import scenes
from devkit import world_scenes as ws

WIDTH, HEIGHT = 160, 90
REFERENCE_SPP = 256
SAMPLES = 64
# MAE at SAMPLES against Cycles' direct light (the HDRI sky: a sun blob, turned by a Mapping node)
TARGETS = {"sky_outdoor": 0.02, "sky_outdoor_hdri": 0.02, "window_room": 0.03}


@functools.lru_cache(maxsize=None)
def _reference(name):
    return ws.cycles_reference(name, REFERENCE_SPP, WIDTH, HEIGHT)


@functools.lru_cache(maxsize=None)
def _penumbra(name, samples, world_shadows=True):
    scene = ws.build(name, WIDTH, HEIGHT)
    ws.use_engine(scene, "PENUMBRA", render_samples=samples, world_shadows=world_shadows)
    return ws.render_display(scene)


def _error(name, samples, world_shadows=True):
    return ws.mae(_penumbra(name, samples, world_shadows), _reference(name))


@pytest.mark.parametrize("name", sorted(TARGETS))
def test_world_light_matches_cycles_direct(penumbra, name):
    """At 64 samples Penumbra is within the issue's target of Cycles' direct light from the
    world: 0.02 outdoors (contact shadows and creases darkened as Cycles darkens them), 0.03
    in the room (light only through the window)."""
    error = _error(name, SAMPLES)
    assert error <= TARGETS[name], (name, error)


def test_the_worlds_sun_brings_the_hdri_closer_to_cycles(penumbra):
    """World > Sun at its default (threshold 10, as EEVEE): the HDRI's sun blob, taken out of
    the world's light as a shadowed sun, leaves the frame nearer Cycles than the blob left in
    it (threshold 0) by at least 15 % (measured at 160x90: 0.0080 against 0.0103 on 5.2, 0.0108
    against 0.0131 on 4.5; before glossy lobes read the image itself, features/world_env.py,
    which reflects the blob where the SH light spread it, 0.0085 against 0.0115 and 0.0113
    against 0.0143)."""
    with_sun = _error("sky_outdoor_hdri", SAMPLES)
    scene = ws.build("sky_outdoor_hdri", WIDTH, HEIGHT)
    scene.world.sun_threshold = 0.0
    ws.use_engine(scene, "PENUMBRA", render_samples=SAMPLES, world_shadows=True)
    without = ws.mae(ws.render_display(scene), _reference("sky_outdoor_hdri"))
    assert with_sun <= 0.85 * without, (with_sun, without)


@pytest.mark.parametrize("name", ["sky_outdoor", "window_room"])
def test_world_shadows_are_what_brings_it_close(penumbra, name):
    """Premise of the accuracy test: with world_shadows off the frame is much farther from
    Cycles (at least twice the error and 0.02 more), so the measurement can tell the two."""
    on, off = _error(name, SAMPLES, True), _error(name, SAMPLES, False)
    assert off >= 2.0 * on and off - on >= 0.02, (name, on, off)


def test_a_room_without_a_portal_finds_its_window(penumbra, monkeypatch):
    """The room with its light portal removed, as most interiors users render come: the
    world's probe (``world/probe.py``) finds the window from depth and the frame draws its
    directions through it. At 64 samples within the room's target of Cycles (measured 0.018;
    0.099 with the probe off, the directions drawn over the whole sphere)."""
    from penumbra.engine.frame.world import probe

    def room():
        scene = ws.build("window_room", WIDTH, HEIGHT)
        ws.use_engine(scene, "PENUMBRA", render_samples=SAMPLES, world_shadows=True)
        ws._portal(scene, False)
        return ws.mae(ws.render_display(scene), _reference("window_room"))

    found = room()
    monkeypatch.setattr(probe, "INTERIOR_SHARE", 0.0)  # no frame is an interior
    blind = room()
    assert found <= TARGETS["window_room"] and blind >= 2.0 * found, (found, blind)


def _guided(gpu_call, scene, samples=4):
    """(FrameStats of a ``samples``-sample frame of ``scene``, its light finite and >= 0)."""
    from penumbra.engine.scene.extract import camera_from_scene

    w, h = scene.render.resolution_x, scene.render.resolution_y

    def job(engine, depsgraph):
        cam = camera_from_scene(depsgraph, scene, w, h)
        out = engine.render_frame(depsgraph, cam, w, h, samples=(0, samples), sample_count=samples)
        return out.stats, out.color_array().copy()

    stats, color = gpu_call(job)
    assert np.all(np.isfinite(color)) and color.min() >= 0.0
    return stats


def test_the_probe_tells_a_room_from_a_house_seen_outside(penumbra, gpu_call):
    """The room without its portal, seen from inside, is an interior (its directions come
    through the window), with a 10 km ground outside too; the same room on that ground seen
    from its garden is not (the middle of what that camera sees lies inside the house: the
    probe looks from the camera); a room lit by lamps is not probed; a closed box (no opening)
    takes no guide."""
    scene = ws.build("window_room_bare", 64, 36)
    ws.use_engine(scene, "PENUMBRA", render_samples=4)
    inside = _guided(gpu_call, scene)
    assert inside.world_guided and inside.probe_draws > 0

    # A 10 km ground outside, the camera in a corner 10 cm from two walls: the probe's near
    # plane must not cut them (it sees its room though the farthest thing drawn is 7 km away).
    scenes.plane(scene, "Garden", size=10000.0, z=-0.2, mat=scenes.white())
    cam = scene.camera
    home = tuple(cam.location), tuple(cam.rotation_euler)
    cam.location = (1.9, -2.4, 1.4)
    scenes.aim(cam, (0.0, 2.5, 1.4))
    assert _guided(gpu_call, scene).world_guided
    cam.location, cam.rotation_euler = home
    cam.location = (1.5, 9.0, 2.0)
    scenes.aim(cam, (0.0, 0.0, 1.2))
    outside = _guided(gpu_call, scene)
    assert outside.probe_draws > 0 and not outside.world_guided

    closed = ws.build("window_room_bare", 64, 36)
    ws.use_engine(closed, "PENUMBRA", render_samples=4)
    for name in ("WallN_below", "WallN_above"):  # the window filled in
        ob = closed.objects[name]
        ob.scale.z = 30.0
    assert not _guided(gpu_call, closed).world_guided

    lamp = ws.build("window_room_bare", 64, 36)
    ws.use_engine(lamp, "PENUMBRA", render_samples=4)
    scenes.light(lamp, "Lamp", "POINT", 5000.0, location=(0.0, 0.0, 2.0))
    lit = _guided(gpu_call, lamp)
    assert lit.probe_draws == 0 and not lit.world_guided


@pytest.mark.parametrize("scale", [1e-3, 1e3])
def test_the_probe_finds_the_window_at_any_scale(penumbra, gpu_call, scale):
    """The room without its portal scaled by 1e-3 (a doll's house) and 1e3 (a hangar), the
    camera with it: still an interior, its light finite and >= 0 (``_guided``)."""
    scene = ws.build("window_room_bare", 64, 36)
    ws.use_engine(scene, "PENUMBRA", render_samples=4)
    for ob in scene.objects:
        ob.location = tuple(scale * c for c in ob.location)
        if ob.type != "CAMERA":
            ob.scale = tuple(scale * c for c in ob.scale)
    cam = scene.camera.data
    cam.clip_start, cam.clip_end = cam.clip_start * scale, cam.clip_end * scale
    assert _guided(gpu_call, scene).world_guided


@pytest.mark.parametrize("name", ["sky_outdoor"])
def test_one_sample_frame_is_close_to_the_converged_one(penumbra, name):
    """The sky-lit one-sample frame (the viewport while the view moves: ambient occlusion for
    the world's visibility) is within 0.04 MAE of the 64-sample frame. (The room's is not a
    target: with its portal a one-sample frame takes a sample's directions through the window,
    0.18 from the converged frame; without the portal it was the whole sky's light, 0.77.)"""
    first, converged = _penumbra(name, 1), _penumbra(name, SAMPLES)
    error = ws.mae(first, converged)
    assert error <= 0.04, (name, error)


def test_the_room_is_closed_but_for_its_window(penumbra):
    """No light leaks at the room's seams: with the window plugged (a box filling the
    opening, overlapping the wall), Cycles' direct light inside is black; open, the floor
    and walls are lit."""
    scene = ws.build("window_room", 64, 36)
    ws.use_engine(scene, "CYCLES", samples=8)
    lit = ws.render_display(scene)
    x0, x1, z0, z1, y = scene["world_window"]

    scenes.box(
        scene,
        "Plug",
        center=((x0 + x1) / 2, y + ws.WALL / 2, (z0 + z1) / 2),
        size=(x1 - x0 + 0.1, ws.WALL, z1 - z0 + 0.1),
        mat=scene.objects["WallN_left"].data.materials[0],
    )
    closed = ws.render_display(scene)
    assert float(closed.max()) < 1e-6, float(closed.max())
    assert float(np.median(lit)) > 0.05, float(np.median(lit))


def test_the_environment_mapping_is_read_and_what_is_not_drawn_is_named(penumbra):
    """The HDRI sky's Mapping rotation turns the world's light (its SH, directions and drawn
    background: a background pixel equals Cycles'); a Location or Scale on it is named, not
    dropped silently."""
    import math

    from penumbra.engine.scene.materials import world_from_blender

    scene = ws.build("sky_outdoor_hdri", 64, 36)
    world = world_from_blender(scene)
    assert world.rotation is not None and not world.messages
    np.testing.assert_allclose(
        world.rotation[:2, :2],
        [
            [math.cos(ws.HDRI_ROTATION_Z), -math.sin(ws.HDRI_ROTATION_Z)],
            [math.sin(ws.HDRI_ROTATION_Z), math.cos(ws.HDRI_ROTATION_Z)],
        ],
        atol=1e-6,
    )
    mapping = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeMapping")
    mapping.inputs["Location"].default_value = (0.5, 0.0, 0.0)
    mapping.inputs["Scale"].default_value = (2.0, 1.0, 1.0)
    messages = " ".join(world_from_blender(scene).messages)
    assert "Location" in messages and "Scale" in messages


def test_the_background_follows_cycles_equirectangular_mapping(penumbra):
    """Looking at the horizon through the rotated HDRI sky, Penumbra's background is Cycles'
    (it had been half a turn off): within 0.01 display MAE."""
    import math

    scene = scenes.empty_scene(64, 32)
    ws.hdri_sky(scene)
    mapping = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, ws.HDRI_ROTATION_Z)
    scenes.camera(scene, (0.0, 0.0, 0.0), (math.radians(95.0), 0.0, math.radians(-40.0)))
    images = {}
    for engine in ("CYCLES", "PENUMBRA"):
        ws.use_engine(scene, engine, samples=4) if engine == "CYCLES" else ws.use_engine(scene, engine)
        images[engine] = ws.render_display(scene)
    assert ws.mae(images["PENUMBRA"], images["CYCLES"]) < 0.01


@pytest.mark.parametrize(("fov", "pitch"), [(120.0, 150.0), (170.0, 90.0)])
def test_the_background_at_a_wide_angle_is_cycles(penumbra, fov, pitch):
    """A 120-degree view looking 60 degrees up, and a 170-degree view at the horizon, through
    the rotated HDRI sky. At 120 degrees the zenith's columns read the sky at its width on the
    sphere (they had taken the image's coarsest mips, which average the ground in: 0.15 per
    column off Cycles). At 170 degrees the footprint crosses a mip level within a pixel quad
    and the seam lies in view: each pixel's level is addressed at its own size (llvmpipe had
    answered one pixel's size for all: black and sky texels in the ground, 0.09-0.14 per
    column off). Within 0.002 MAE of Cycles and no column beyond 0.01 (measured 7e-5 and
    2.4e-4 at 120 degrees, 0.0013 and 0.003 at 170: the horizon's sharp edge is filtered over
    a wider pixel there)."""
    import math

    scene = scenes.empty_scene(128, 64)
    ws.hdri_sky(scene)
    camera = scenes.camera(scene, (0.0, 0.0, 0.0), (math.radians(pitch), 0.0, math.radians(-40.0)))
    camera.data.lens_unit = "FOV"
    camera.data.angle = math.radians(fov)
    images = {}
    for engine in ("CYCLES", "PENUMBRA"):
        ws.use_engine(scene, engine, samples=16) if engine == "CYCLES" else ws.use_engine(scene, engine)
        images[engine] = ws.render_display(scene)
    columns = np.abs(images["PENUMBRA"] - images["CYCLES"]).mean(axis=(0, 2))
    assert ws.mae(images["PENUMBRA"], images["CYCLES"]) < 0.002 and columns.max() < 0.01, columns.max()


@pytest.mark.parametrize(("width", "height", "strength"), [(1, 1, 1.0), (2, 1, 1e6), (8192, 4, 1.0), (64, 32, 0.0)])
def test_extreme_environment_images_render_finite(penumbra, gpu_call, width, height, strength):
    """HDRIs of 1x1 to 8k wide, strength 0 to 1e6, through the world's sampled directions and
    its ambient occlusion (4 samples): every pixel is finite, a black one costs no direction."""
    import bpy

    scene = ws.build("sky_outdoor", 48, 27)
    image = bpy.data.images.new("extreme_sky", width, height, alpha=True, float_buffer=True)
    rng = np.random.default_rng(width)
    image.pixels.foreach_set(
        np.concatenate([rng.random((width * height, 3)) * 4.0, np.ones((width * height, 1))], 1)
        .astype(np.float32)
        .ravel()
    )
    tree = scene.world.node_tree
    bg = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = image
    tree.links.new(env.outputs["Color"], bg.inputs["Color"])
    bg.inputs["Strength"].default_value = strength
    scene.penumbra.render_samples = 4

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        out = engine.render_frame(
            depsgraph, camera_from_scene(depsgraph, scene, 48, 27), 48, 27, samples=(0, 4), sample_count=4
        )
        return out.stats, out.color_array().copy()

    stats, color = gpu_call(job)
    assert np.all(np.isfinite(color))
    assert (stats.world_directions == 0) == (strength == 0.0), stats.world_directions


def test_the_world_light_and_indirect_views_show_their_terms_alone(penumbra, gpu_call):
    """Debug views WORLD_LIGHT and INDIRECT draw one term of the colour, with the frame's own
    samples: with no lamp the world's light is the whole frame; the bounce is the frame with it
    less the frame without, within float rounding but where the maps differ (with the bounce
    every object is drawn into every map, so a few shadow edges move: measured 2.9 % of the
    values, by up to 0.014)."""
    from penumbra.engine.scene.extract import camera_from_scene

    scene = ws.build("sky_outdoor", 64, 36)
    ws.use_engine(scene, "PENUMBRA", world_shadows=True)
    sun = scenes.light(scene, "Sun", "SUN", 2.0, rotation=(0.6, 0.0, 0.4))

    def frame(view, bounces, with_sun):
        scene.penumbra.debug_view = view
        scene.penumbra.indirect_bounces = bounces
        sun.hide_render = not with_sun

        def job(engine, depsgraph):
            cam = camera_from_scene(depsgraph, scene, 64, 36)
            out = engine.render_frame(depsgraph, cam, 64, 36, samples=(0, 4), sample_count=4, aux=False)
            return out.lit_array().copy() if view == "NONE" else out.debug.image.copy()

        return gpu_call(job)[..., :3]

    np.testing.assert_allclose(frame("WORLD_LIGHT", 0, False), frame("NONE", 0, False), atol=1e-5)
    bounce = frame("INDIRECT", 1, True)
    difference = np.abs(bounce - (frame("NONE", 1, True) - frame("NONE", 0, True)))
    assert np.mean(difference > 2e-4) < 0.05 and difference.mean() < 1e-3, (
        np.mean(difference > 2e-4),
        difference.mean(),
    )
    assert bounce.mean() > 1e-3  # the sun's light bounced off the ground onto the objects


def test_the_bounce_brings_the_room_toward_cycles_with_one_bounce(penumbra):
    """The room at 16 samples with Light Paths > Diffuse Bounces 1 against Cycles with one
    diffuse bounce: much closer than without the bounce (measured on 5.2: 0.052 against 0.102;
    at 320x180 and 64 samples 0.031, the bench's table)."""
    reference = ws.cycles_reference("window_room", REFERENCE_SPP, WIDTH, HEIGHT, bounces=1)

    def error(bounces):
        scene = ws.build("window_room", WIDTH, HEIGHT)
        ws.use_engine(scene, "PENUMBRA", render_samples=16, indirect_bounces=bounces)
        return ws.mae(ws.render_display(scene), reference)

    with_bounce, without = error(1), error(0)
    assert with_bounce < 0.7 * without, (with_bounce, without)


def test_glossy_spheres_have_no_negative_light_nor_blotches(penumbra):
    """Glossy spheres (roughness 0.15-0.5) under a dim sky and a sun, where the world's light
    was once a control variate that went negative under a few blocked glossy directions
    (black dots on the spheres; 482 pixels of the demo, down to -1.16). Its ratio form
    (lit.frag.glsl WORLD_RATIO, per lobe) at 16 samples: nothing below zero (the harness checks
    every frame), within 0.008 of Cycles' direct light overall (measured 0.0041 against 1024
    spp with 4 directions a sample, 0.0051 with the 2 its share of the light now takes; the
    control variate 0.0055), and no dark spot: at most 10 pixels darker than Cycles by
    0.1 in display luminance (measured 4, on silhouettes; the control variate 29)."""
    image = _penumbra("glossy_spheres", 16)
    reference = _reference("glossy_spheres")
    error = ws.mae(image, reference)
    luminance = np.array([0.2126, 0.7152, 0.0722])
    dark = int(np.count_nonzero(reference @ luminance - image @ luminance > 0.1))
    assert error <= 0.008 and dark <= 10, (error, dark)


def test_open_ground_takes_the_sh_light_exactly(penumbra):
    """Where nothing blocks the world, its ratio is 1: a ground alone under the sky renders as
    with World > Shadows off, to float rounding, at 4 samples (no noise at all). (Without the
    first sample's ambient occlusion, whose screen-space estimate is not 1 on an open plane, and
    with all 4 samples: adaptive sampling stops the frame without directions after its pilot.)"""
    frames = []
    for shadows in (True, False):
        scene = scenes.empty_scene(64, 36)
        ws.uniform_sky(scene, ws.SKY_COLOR, ws.SKY_STRENGTH)
        scenes.plane(scene, "Ground", size=200.0, mat=ws.principled("Ground", (0.5, 0.5, 0.5), 0.3))
        scenes.look_at(scene, (0.0, -4.0, 2.0), (0.0, 0.0, 0.0), lens=35.0)
        ws.use_engine(
            scene, "PENUMBRA", render_samples=4, world_shadows=shadows, world_ao=False, use_adaptive_sampling=False
        )
        frames.append(ws.render_display(scene))
    np.testing.assert_allclose(frames[0], frames[1], atol=2e-5)
