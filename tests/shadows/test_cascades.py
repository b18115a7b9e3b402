"""Sun maps fitted to the depth range the camera actually sees, split into cascades when that
range is deep: a small object on a huge ground keeps its shadow whatever the far clip.

The scene is the case that lost its shadow entirely: a 15 cm box on a 1 km ground, the camera
0.5 m away with clip_end 500 m. Shadows are compared with the analytic ray-box test."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.analytic import camera_matrices, iou, plane_hits, ray_hits_box
from devkit.render import render
from devkit.scenes import WHITE_ALBEDO as ALBEDO

BOX = 0.15
TILT = math.radians(40.0)


def small_box_scene(horizon, cascades=0, slab=False):
    """The box on the ground; ``horizon``: the camera looks nearly level, so the ground is
    seen out to the far clip (500 m), else down at it (seen out to about 1.3 m). ``slab``: the
    ground is a 1 m thick box (its top at z = 0), which casts shadows like any solid, so the
    sun maps must cover all of it that the camera sees; a flat ground casts none (nothing
    stands below it) and the maps crop to the box's footprint."""
    scene = scenes.empty_scene(160, 90)
    mat = scenes.white()
    if slab:
        scenes.box(scene, "Ground", center=(0.0, 0.0, -0.5), size=(1000.0, 1000.0, 1.0), mat=mat)
    else:
        scenes.plane(scene, "Ground", size=1000.0, mat=mat)
    scenes.box(scene, "Box", center=(0.0, 0.0, BOX / 2), size=(BOX,) * 3, mat=mat)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(TILT, 0.0, 0.0))
    eye, target = ((0.5, -0.2, 0.12), (0.0, 0.08, 0.04)) if horizon else ((0.5, -0.2, 0.35), (0.0, 0.08, 0.0))
    scenes.look_at(scene, eye, target)
    scene.camera.data.clip_start = 0.01
    scene.camera.data.clip_end = 500.0
    scene.penumbra.shadow_cascades = cascades
    return scene


def shadow_score(scene):
    """(IoU of the rendered and analytic shadows on the ground, false-shadow fraction of the
    lit ground farther than 2 px from the analytic edge)."""
    out = render(scene, passes=("Combined", "Depth"))
    color, depth = out["Combined"], out["Depth"][..., 0]
    view, proj, w, h = camera_matrices(scene)
    points, plane_depth = plane_hits(view, proj, w, h)
    on_ground = np.abs(depth - plane_depth) < 1e-3 * np.maximum(plane_depth, 1.0)
    d = np.array([0.0, math.sin(TILT), -math.cos(TILT)])
    analytic = ray_hits_box(points, -d, (-BOX / 2, -BOX / 2, 0.0), (BOX / 2, BOX / 2, BOX))
    lit = ALBEDO / math.pi * 3.0 * math.cos(TILT)
    shadow = color[..., 0] < 0.5 * lit
    near_edge = np.zeros_like(analytic)
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            near_edge |= np.roll(np.roll(analytic, dy, axis=0), dx, axis=1)
    lit_ground = on_ground & ~near_edge
    return iou(shadow[on_ground], analytic[on_ground]), (shadow & lit_ground).sum() / lit_ground.sum()


@pytest.mark.parametrize("cascades", [0, 1])
def test_small_object_keeps_its_shadow_under_a_far_clip_plane(penumbra, cascades):
    """Looking down at the ground, one map fitted to the seen depth range (0.46-1.3 m, not to
    the 500 m clip) is enough: IoU 0.987 measured (0.007 when the fit spanned the frustum)."""
    score, false = shadow_score(small_box_scene(horizon=False, cascades=cascades))
    assert score >= 0.95, f"IoU {score:.3f}"
    assert false < 0.002


def test_cascades_keep_the_shadow_when_the_ground_reaches_the_horizon(penumbra):
    """Seen out to 500 m, one map covers the whole visible (solid) ground and the box gets
    about one texel (IoU 0.013 measured with ``shadow_cascades = 1``); the automatic split (3
    cascades here) gives IoU 0.96, and the ground out to the horizon stays free of acne."""
    single, _false = shadow_score(small_box_scene(horizon=True, cascades=1, slab=True))
    score, false = shadow_score(small_box_scene(horizon=True, slab=True))
    assert single < 0.5  # the failure the cascades fix is real in this scene
    assert score >= 0.9, f"IoU {score:.3f}"
    assert false < 0.002


def test_flat_ground_casts_nothing_so_one_map_crops_to_the_caster(penumbra):
    """With a flat ground nothing stands below, so it shadows nothing: it is left out of the
    sun's map, which crops to the box's footprint; one map then gives the box its shadow out
    to the horizon (IoU 0.994 measured; 0.013 when the map covered the visible ground)."""
    score, false = shadow_score(small_box_scene(horizon=True, cascades=1))
    assert score >= 0.95, f"IoU {score:.3f}"
    assert false < 0.002


def test_cascade_planning(penumbra):
    """The visible depth range of a plane under a tilted camera is the analytic one, and the
    automatic count grows with the depth ratio (1 up to 20, then one more per factor 20)."""
    import bpy

    from penumbra.engine.scene.extract import camera_from_scene
    from penumbra.engine.shadows import lightspace

    scene = small_box_scene(horizon=False)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    camera = camera_from_scene(depsgraph, scene, 160, 90)
    ground = np.array([[x, y, 0.0] for z in (0, 1) for y in (-500.0, 500.0) for x in (-500.0, 500.0)])
    near, far = lightspace.view_depth_range(camera.projection, camera.view, ground[None], camera.is_ortho)
    # The analytic range: the view depths where the frustum's corner rays meet the ground.
    inverse = np.linalg.inv(camera.projection @ camera.view)
    depths = []
    for x in (-1.0, 1.0):
        for y in (-1.0, 1.0):
            a = inverse @ np.array([x, y, -1.0, 1.0])
            b = inverse @ np.array([x, y, 1.0, 1.0])
            a, b = a[:3] / a[3], b[:3] / b[3]
            hit = a + (b - a) * (a[2] / (a[2] - b[2]))
            depths.append(-(camera.view[2, :3] @ hit + camera.view[2, 3]))
    np.testing.assert_allclose((near, far), (min(depths), max(depths)), rtol=1e-6)
    assert [lightspace.cascade_count(1.0, r) for r in (5.0, 20.0, 21.0, 400.0, 401.0, 1e9)] == [1, 1, 2, 2, 3, 4]
    assert lightspace.cascade_count(1.0, 1e9, requested=2) == 2
    splits = lightspace.cascade_splits(0.5, 500.0, 3)
    np.testing.assert_allclose(splits, (0.5, 5.0, 50.0, 500.0))  # equal depth ratios


def test_sub_texel_camera_steps_leave_the_shadow_still(penumbra):
    """A top orthographic camera moved by whole pixels (each a fraction of a shadow-map texel
    of the fitted map) over a static box shadow: after shifting each frame back by the same
    pixels, only pixels next to the shadow's edge may change (the fit is snapped to texels and
    its extent quantised, so it moves in whole texels); none farther than 2 px from it."""
    size, view = 96, 6.0
    frames = []
    for step in range(4):
        scene = scenes.empty_scene(size, size)
        scenes.box_over_plane(scene, plane_size=40.0, box_center=(0.0, 0.0, 1.5), box_size=1.0)
        scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(30.0), 0.0, 0.0))
        scenes.top_camera(scene, height=20.0, ortho_scale=view)
        scene.camera.location.x += step * view / size  # one pixel a step
        scene.penumbra.shadow_map_size = 1024
        lum = render(scene)["Combined"][..., 0]
        frames.append(np.roll(lum, step, axis=1))  # back to the first frame's pixels
    lit = ALBEDO / math.pi * 3.0 * math.cos(math.radians(30.0))
    masks = [f < 0.5 * lit for f in frames]
    base = masks[0]
    boundary = np.zeros_like(base)
    for axis in (0, 1):
        for shift in (-1, 1):
            boundary |= base != np.roll(base, shift, axis=axis)
    edge = np.zeros_like(base)  # within 2 px of the first frame's shadow edge
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            edge |= np.roll(np.roll(boundary, dy, axis=0), dx, axis=1)
    edge[:, :4] = True  # the columns that rolled in from the other side
    assert base.sum() > 200  # the shadow is in view
    at_edge = []
    for m in masks[1:]:
        changed = (m != base) & ~edge
        assert changed.sum() == 0, changed.sum()
        at_edge.append(int(((m != base) & edge).sum()))
    # Along the edge, flips stay a small fraction of the edge pixels (measured: 0 of 132 per step).
    assert max(at_edge) <= 0.1 * boundary.sum(), (at_edge, int(boundary.sum()))


@pytest.mark.parametrize("depth_format", ["FLOAT32", "FLOAT16", "RGBA8"])
@pytest.mark.parametrize("ground", [1e3, 1e6])
def test_every_depth_format_holds_under_a_huge_ground(penumbra, depth_format, ground):
    """A 1 m box over a solid ground of 1 km and 1000 km: the sun map's depth range spans what the
    camera sees (casters nearer the light are flattened onto its near plane), so even half
    floats keep the shadow exact (FLOAT16 with a 1 km ground was 94 % false shadow when the
    range spanned the whole ground's light-space depth)."""
    scene = scenes.empty_scene(128, 128)
    # A solid ground (1 m thick, top at z = 0) is drawn into the map; a flat one would not be.
    mat = scenes.white()
    scenes.box(scene, "Ground", center=(0, 0, -0.5), size=(ground, ground, 1.0), mat=mat)
    scenes.box(scene, "Box", center=(0, 0, 1.5), size=(1.0, 1.0, 1.0), mat=mat)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(45.0), 0.0, 0.0))
    forward = np.array([0.0, math.sin(math.radians(35)), -math.cos(math.radians(35))])
    scenes.camera(
        scene, tuple(-forward * 15.0 + [0, 0.8, 0]), (math.radians(35), 0, 0), ortho_scale=7.0, clip=(0.1, 40)
    )
    scene.penumbra.shadow_depth_format = depth_format
    out = render(scene, passes=("Combined", "Depth"))
    color, depth = out["Combined"], out["Depth"][..., 0]
    view, proj, w, h = camera_matrices(scene)
    points, plane_depth = plane_hits(view, proj, w, h)
    on_ground = np.abs(depth - plane_depth) < 1e-2
    d = np.array([0.0, math.sin(math.radians(45.0)), -math.cos(math.radians(45.0))])
    analytic = ray_hits_box(points, -d, (-0.5, -0.5, 1.0), (0.5, 0.5, 2.0))
    shadow = color[..., 0] < 0.5 * ALBEDO / math.pi * 3.0 * math.cos(math.radians(45.0))
    assert on_ground.mean() > 0.9
    assert iou(shadow[on_ground], analytic[on_ground]) > 0.97
    assert (shadow & on_ground & ~analytic).sum() / (on_ground & ~analytic).sum() < 0.005


def test_visible_depth_range_is_computed_once_per_frame(penumbra, gpu_call, monkeypatch):
    """It and the visible receivers depend only on the unjittered camera and the instances'
    bounds: a frame of 4 samples (a soft sun, refitted every sample) computes them once, not
    per sample."""
    from penumbra.engine.shadows import lightspace

    calls, seen = [], []
    real = lightspace.view_depth_range
    monkeypatch.setattr(lightspace, "view_depth_range", lambda *a: calls.append(1) or real(*a))
    real_seen = lightspace.visible_receivers
    monkeypatch.setattr(lightspace, "visible_receivers", lambda *a: seen.append(1) or real_seen(*a))
    scene = small_box_scene(horizon=True)
    scene.objects["Sun"].data.angle = math.radians(5.0)

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, scene, 160, 90)
        out = engine.render_frame(depsgraph, camera, 160, 90, samples=(0, 4), sample_count=4)
        return out.stats.samples, out.stats.lights_sampled

    assert gpu_call(job) == (4, 1)
    assert len(calls) == 1
    assert len(seen) == 1  # what the camera sees, shared by every light's crop in every sample


def test_cascade_seams_blend_inside_the_overlap_both_maps_cover(penumbra):
    """Before each split the next cascade fades in over half the depth both maps cover (each
    slice is widened by CASCADE_OVERLAP of its depth), so a filter there reads inside both."""
    from penumbra.engine.shadows import lightspace
    from penumbra.engine.shadows import planning as shadows

    splits = lightspace.cascade_splits(0.5, 500.0, 3)
    blend = shadows.cascade_blend(splits[1:], (0.5, 500.0))
    assert len(blend) == 2
    for k, band in enumerate(blend):
        a, b, c = splits[k], splits[k + 1], splits[k + 2]
        both = min(shadows.CASCADE_OVERLAP * (b - a), shadows.CASCADE_OVERLAP * (c - b))
        assert 0.0 < band <= 0.5 * both + 1e-12
    assert shadows.cascade_blend([40.0]) == ()  # one map: no seam


def test_cascade_seams_change_no_shadow(penumbra):
    """The horizon scene with 4 cascades, blended across seams, against the analytic shadow:
    the blend never picks a map that does not cover the pixel (IoU and false shadow as with
    the automatic count)."""
    score, false = shadow_score(small_box_scene(horizon=True, cascades=4, slab=True))
    assert score >= 0.9, f"IoU {score:.3f}"
    assert false < 0.002
