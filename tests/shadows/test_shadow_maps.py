"""Which shadow maps a frame draws, reuses or skips, and the depth encodings they hold."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.analytic import iou
from devkit.render import engine_frame, render


def test_light_without_shadow_gets_no_shadow_map(penumbra, gpu_call):
    scene = scenes.demo_scene(64, 36)
    stats, _ = engine_frame(gpu_call, scene, 64, 36)
    assert stats.shadow_maps == 2  # the sun and the spot
    scene.objects["Sun"].data.use_shadow = False
    stats, _ = engine_frame(gpu_call, scene, 64, 36)
    assert stats.shadow_maps == 1
    scene.objects["Spot"].data.use_shadow = False
    stats, _ = engine_frame(gpu_call, scene, 64, 36)
    assert stats.shadow_maps == 0 and stats.passes == 1 + stats.post_passes


def test_point_light_skips_cube_faces_without_casters(shadow_scene, gpu_call):
    """A face gets a map only when a caster it can see may shadow something: the flat plane
    shadows nothing (nothing lies below it), so only the faces that see the box draw one."""
    from penumbra.engine.shadows import lightspace

    scene = shadow_scene("POINT", "PCF")
    stats, _ = engine_frame(gpu_call, scene, 64, 36)
    light = np.array(scene.objects["L"].location)
    box = lightspace.box_corners((-0.5, -0.5, 1.0), (0.5, 0.5, 2.0))[None]
    seeing = sum(
        bool(
            lightspace.boxes_in_frustum(
                lightspace.perspective(np.pi / 2, 1, 0.01, 100) @ lightspace.look_at(light, f), box
            )[0]
        )
        for f in lightspace.CUBE_FORWARDS
    )
    assert 1 <= seeing < 5
    assert stats.shadow_maps == seeing
    # A solid ground (a box 1 m thick) can shadow itself: every face that sees a part of it in
    # view draws one (the camera now sees the whole ground).
    scene.camera.data.ortho_scale = 60.0
    scenes.box(scene, "Slab", center=(0.0, 0.0, -0.5), size=(30.0, 30.0, 1.0))
    bpy_remove(scene.objects["Plane"])
    stats, _ = engine_frame(gpu_call, scene, 64, 36)
    assert stats.shadow_maps == 5  # the +Z face sees nothing
    scene.objects["L"].location = (0.0, 0.0, 100.0)  # far above: the side faces see nothing either
    stats, _ = engine_frame(gpu_call, scene, 64, 36)
    assert stats.shadow_maps == 1


def bpy_remove(ob):
    import bpy

    bpy.data.objects.remove(ob)


def test_no_caster_no_shadow_map(penumbra, gpu_call):
    scene = scenes.empty_scene(32, 32)
    scenes.top_camera(scene)
    for kind in ("SUN", "SPOT", "POINT", "AREA"):
        scenes.light(scene, kind, kind, 10.0, location=(0, 0, 3))
    stats, img = engine_frame(gpu_call, scene, 64, 36)
    assert stats.shadow_maps == 0 and np.all(np.isfinite(img))
    # A spot pointing away from every mesh also gets no map.
    scenes.plane(scene, size=4.0)
    for name in ("SUN", "POINT", "AREA"):
        scene.objects[name].data.use_shadow = False
    scene.objects["SPOT"].rotation_euler = (math.pi, 0, 0)  # points up, the plane is below
    stats, _ = engine_frame(gpu_call, scene, 64, 36)
    assert stats.shadow_maps == 0


def _two_frames(gpu_call, scene, move):
    from penumbra.engine.scene.extract import camera_from_scene

    def job(engine, depsgraph):
        first = engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, 64, 64), 64, 64).stats
        move()
        depsgraph.update()
        second = engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, 64, 64), 64, 64).stats
        return first, second

    return gpu_call(job)


def test_camera_moves_redraw_sun_maps_only_when_the_fit_changes(shadow_scene, gpu_call):
    scene = shadow_scene("SUN", "PCF", size=64)
    scene.camera.data.ortho_scale = 60.0  # the camera sees the whole 30 m plane

    def nudge():
        scene.camera.location.x += 0.5

    first, second = _two_frames(gpu_call, scene, nudge)
    assert (first.shadow_maps, first.shadow_maps_reused) == (1, 0)
    assert (second.shadow_maps, second.shadow_maps_reused) == (0, 1)  # same receivers, same fit
    scene.camera.data.ortho_scale = 1.0  # now the view crops the box's shadow: the fit follows it
    first, second = _two_frames(gpu_call, scene, nudge)
    assert second.shadow_maps == 1
    scene.penumbra.shadow_sun_fit = "SCENE"  # camera-independent: never redrawn for moves
    first, second = _two_frames(gpu_call, scene, nudge)
    assert (second.shadow_maps, second.shadow_maps_reused) == (0, 1)


@pytest.mark.parametrize("fmt", ["FLOAT32", "FLOAT16", "RGBA8"])
def test_depth_encodings_cast_the_same_shadow(shadow_scene, analytic_shadow, fmt):
    scene = shadow_scene("SPOT", "NONE")
    scene.penumbra.shadow_depth_format = fmt
    _lum, visibility, on_plane, shadowed = analytic_shadow(scene, scene.objects["L"])
    lit = on_plane & ~shadowed
    measured = visibility < 0.5
    score = iou(measured[on_plane], shadowed[on_plane])
    acne = (lit & measured).sum() / lit.sum()
    assert score > 0.95 and acne < 0.01, f"{fmt}: IoU {score:.3f}, acne {acne:.2%}"


@pytest.mark.parametrize("kind", ["SUN", "POINT"])
@pytest.mark.parametrize("kernel", [3, 5, 9])
def test_gathered_pcf_equals_the_tap_by_tap_kernel(shadow_scene, kind, kernel):
    """PCF with taps one texel apart reads 2x2 texels per fetch (textureGather); any other
    spacing reads tap by tap. A spacing a hair above 1 takes the tap path over the same texels,
    so both must give the same visibility (up to the few pixels whose tap lands exactly on a
    texel edge). Point lights cover cube-face tiles with neighbours in the atlas."""
    scene = shadow_scene(kind, "PCF")
    scene.penumbra.pcf_kernel_size = kernel
    # Coarse texels, so the kernel spans a visible penumbra (maps cover only what the box can
    # shadow in view).
    scene.penumbra.shadow_map_size = 32 if kind == "SUN" else 64
    gathered = render(scene, passes=("Combined", "Shadow"))["Shadow"][..., 0]
    scene.penumbra.pcf_spacing = 1.0 + 1e-6
    tapped = render(scene, passes=("Combined", "Shadow"))["Shadow"][..., 0]
    penumbra = (tapped > 0.02) & (tapped < 0.98)
    assert penumbra.sum() > 100  # the comparison covers soft edges, not only flat regions
    differs = np.abs(gathered - tapped) > 1e-4
    assert differs.mean() < 0.002, f"{differs.sum()} pixels differ"
    np.testing.assert_allclose(np.median(np.abs(gathered - tapped)[penumbra]), 0.0, atol=1e-5)


@pytest.mark.parametrize("shadow_filter", ["PCF", "PCSS"])
def test_no_lit_seam_where_a_shadow_crosses_cube_faces(penumbra, analytic_shadow, shadow_filter):
    """A 6 m beam 1.5 m under a point light: its shadow on the ground runs from x = -6 to 6 and
    crosses the boundary between the downward cube face and the side faces at |x| = 3. Each
    face's map is widened by its filter's kernel, so inside the analytic shadow (more than
    2 px from its edge) no pixel is even a tenth lit, at the seam or anywhere. Before the faces
    were widened, PCF read "nothing there" past the face edge: 16 pixels at 0.30 across the
    shadow at the seams (measured with this test)."""
    scene = scenes.empty_scene(224, 112)
    scenes.plane(scene, "Ground", size=40.0, mat=scenes.white())
    lo, hi = (-3.0, -0.15, 1.4), (3.0, 0.15, 1.6)
    scenes.box(scene, "Beam", center=(0.0, 0.0, 1.5), size=(6.0, 0.3, 0.2), mat=scenes.white())
    light = scenes.light(scene, "L", "POINT", 2000.0, location=(0.0, 0.0, 3.0), shadow_soft_size=0.05)
    scenes.camera(scene, (0.0, 0.0, 20.0), (0.0, 0.0, 0.0), ortho_scale=15.0, clip=(1.0, 40.0))
    scene.penumbra.shadow_filter = shadow_filter
    scene.penumbra.shadow_map_size = 256  # coarse texels: a kernel past the face edge spans pixels
    _lum, visibility, on_plane, shadowed = analytic_shadow(scene, light, lo, hi)
    edge = np.zeros_like(shadowed)
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            edge |= np.roll(np.roll(shadowed, dy, axis=0), dx, axis=1) != shadowed
    core = shadowed & on_plane & ~edge
    assert core.sum() > 500  # the shadow is in view, across the seams
    columns = np.nonzero(core.any(axis=0))[0]
    assert columns.max() - columns.min() > 0.8 * 12.0 / 15.0 * 224  # from about x = -6 to 6
    assert (visibility[core] > 0.1).sum() == 0, np.sort(visibility[core])[-10:]
    assert iou((visibility < 0.5)[on_plane], shadowed[on_plane]) > 0.95


@pytest.mark.parametrize("depth_format", ["FLOAT32", "FLOAT16"])
def test_a_sun_shining_up_from_under_the_ground_is_blocked_by_it(penumbra, depth_format):
    """A sun below the horizon (as half the world's directions are): the ground between it and
    a box's front face shadows the face. The ground crosses the map's near plane; flattened
    onto it per vertex its depth was bent and it shadowed nothing (the face was as lit as with
    no shadow at all)."""
    from mathutils import Vector

    def frame(use_shadow):
        scene = scenes.empty_scene(96, 54)
        mat = scenes.white()
        scenes.plane(scene, size=30.0, mat=mat)
        scenes.box(scene, center=(0.0, 0.0, 0.5), size=(1.0, 1.0, 1.0), mat=mat)
        scenes.look_at(scene, (0.0, -6.0, 2.0), (0.0, 0.0, 0.5))
        sun = scenes.light(scene, "Sun", "SUN", 3.0, use_shadow=use_shadow)
        toward = Vector((0.0, -0.3, -1.0)).normalized()  # the sun is below and in front
        sun.rotation_euler = (-toward).to_track_quat("-Z", "Y").to_euler()
        scene.penumbra.shadow_depth_format = depth_format
        return render(scene)["Combined"][..., 0]

    open_face = frame(False)
    lit = open_face > 0.1  # only the box's front face faces a sun from below
    assert lit.sum() > 100
    shadowed = frame(True)[lit]
    # All dark but for the face's bottom row, where it meets the ground within the biases
    # (measured: 7/8 of the face 0, that row 0.05-0.7 of the light).
    assert np.mean(shadowed < 0.01 * open_face[lit].mean()) > 0.8, np.unique(shadowed.round(3))
    assert shadowed.mean() < 0.1 * open_face[lit].mean()
