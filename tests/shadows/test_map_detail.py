"""Casters drawn into each shadow map at that map's texel footprint (Shadows › Caster Detail,
``shadow_pass.map_levels``): a detailed caster's map is drawn with a fraction of its triangles,
its shadow unchanged; the lit pass keeps every triangle."""

import math

import bpy
import numpy as np
import pytest

from devkit import scenes

DETAIL = 2.0  # the setting's default: cells of one to two map texels


def _uv_sphere(scene, name, segments, rings, radius, center):
    """A smooth UV sphere of ``segments`` x ``rings`` (2 * segments * (rings - 1) triangles),
    built from arrays (fast for a million triangles)."""
    theta = np.linspace(0.0, math.pi, rings + 1)[1:-1]
    phi = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
    verts = np.concatenate([[(0.0, 0.0, 1.0)], ring, [(0.0, 0.0, -1.0)]]) * radius + np.asarray(center)
    idx = 1 + np.arange((rings - 1) * segments).reshape(rings - 1, segments)
    nxt = np.roll(idx, -1, axis=1)
    top = np.stack([np.zeros(segments, int), idx[0], nxt[0]], axis=1)
    bottom = np.stack([np.full(segments, len(verts) - 1), nxt[-1], idx[-1]], axis=1)
    a, b, c, d = idx[:-1], idx[1:], nxt[1:], nxt[:-1]
    quads = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    tris = np.concatenate([top, quads, bottom]).astype(np.int32)
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(verts))
    me.vertices.foreach_set("co", verts.astype(np.float32).ravel())
    me.loops.add(tris.size)
    me.loops.foreach_set("vertex_index", tris.ravel())
    me.polygons.add(len(tris))
    me.polygons.foreach_set("loop_start", np.arange(0, tris.size, 3, dtype=np.int32))
    me.update(calc_edges=True)
    me.shade_smooth()
    ob = bpy.data.objects.new(name, me)
    scene.collection.objects.link(ob)
    return ob, len(tris)


@pytest.fixture(scope="module")
def detailed_scene(penumbra):
    """A million-triangle sphere over a ground, a sharp sun, a 128-texel map: each map texel
    under the sphere covers tens of its triangles."""
    scene = scenes.empty_scene(256, 256)
    scenes.plane(scene, "Ground", size=8.0, mat=scenes.white())
    ball, triangles = _uv_sphere(scene, "Ball", 1024, 513, 0.6, (0.0, 0.0, 0.9))
    ball.data.materials.append(scenes.white())
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(35), 0.0, math.radians(20)), angle=0.0)
    scenes.top_camera(scene, height=10.0, ortho_scale=3.5)
    scene.penumbra.shadow_filter = "NONE"
    scene.penumbra.shadow_map_size = 128
    scene.penumbra.shadow_texels_per_pixel = 0.0  # maps of the set size, whatever the frame's
    return scene, triangles


def _frame(gpu_call, scene, detail):
    from penumbra.engine.scene.extract import camera_from_scene

    scene.penumbra.shadow_caster_detail = detail

    def job(engine, depsgraph):
        out = engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, 256, 256), 256, 256)
        return out.stats, out.shadow_array().copy(), out.color_array()[..., :3].copy()

    return gpu_call(job)


def test_a_detailed_casters_map_is_drawn_at_its_texel_footprint(gpu_call, detailed_scene):
    scene, triangles = detailed_scene
    assert triangles > 1_000_000
    full_stats, full_shadow, full_color = _frame(gpu_call, scene, 0.0)
    stats, shadow, color = _frame(gpu_call, scene, DETAIL)
    assert full_stats.shadow_simplified == 0 and stats.shadow_simplified == 1
    assert full_stats.shadow_triangles >= triangles  # every triangle into the map
    assert stats.shadow_triangles <= 0.10 * full_stats.shadow_triangles  # at most a tenth
    assert stats.triangles == full_stats.triangles  # the lit pass keeps every triangle
    dark, full_dark = shadow < 0.5, full_shadow < 0.5
    assert full_dark.mean() > 0.05  # the shadow is a large part of the frame
    iou = (dark & full_dark).sum() / (dark | full_dark).sum()
    assert iou >= 0.99
    # The sphere's lit side does not shadow itself (acne): its shading is the full map's.
    assert np.abs(color - full_color).max(axis=-1).mean() < 0.01


def test_the_level_follows_the_map_and_is_kept_between_frames(gpu_call, detailed_scene):
    """A finer map draws more of the caster's triangles; a second, unchanged frame of the same
    engine redraws no map and keeps the level's batch."""
    from penumbra.engine.scene.extract import camera_from_scene

    scene, triangles = detailed_scene
    scene.penumbra.shadow_caster_detail = DETAIL
    counts = {}
    for size in (512, 128):
        scene.penumbra.shadow_map_size = size

        def job(engine, depsgraph):
            camera = camera_from_scene(depsgraph, scene, 64, 64)
            first = engine.render_frame(depsgraph, camera, 64, 64).stats
            batches = dict(engine.renderer.batches.levels)
            second = engine.render_frame(depsgraph, camera, 64, 64).stats
            return first, second, batches, dict(engine.renderer.batches.levels)

        first, second, batches, batches_after = gpu_call(job)
        counts[size] = first.shadow_triangles
        assert second.shadow_maps == 0 and second.shadow_maps_reused == 1
        assert batches.keys() == batches_after.keys()
        assert all(batches[k] is batches_after[k] for k in batches)
    assert counts[128] < counts[512] <= triangles


@pytest.mark.parametrize("detail", [1e-9, 1e6])
def test_caster_detail_at_its_extremes(gpu_call, detailed_scene, detail):
    """A vanishing cell draws every triangle (no level is worth it); a cell wider than the map
    draws the coarsest level: a finite frame, a shadow still there, far fewer triangles."""
    scene, triangles = detailed_scene
    stats, shadow, color = _frame(gpu_call, scene, detail)
    assert np.isfinite(shadow).all() and np.isfinite(color).all()
    if detail < 1.0:
        assert stats.shadow_simplified == 0 and stats.shadow_triangles == triangles
    else:
        assert stats.shadow_simplified == 1 and stats.shadow_triangles < 0.01 * triangles
        assert (shadow < 0.5).mean() > 0.02  # the coarse ball still casts
