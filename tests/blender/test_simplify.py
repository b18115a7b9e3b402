"""Render › Simplify › Penumbra › Merge Below (``engine/scene/simplify.py``): levels of detail by clustering.
Checked on geometry with a known surface (spheres: every vertex's distance to the sphere), on
the level a cell size in pixels asks for, and on frames: fewer triangles, nearly the same image,
and nothing simplified that needs more than positions and normals."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.render import engine_frame

WORLD = (0.2, 0.3, 0.4)


def _sphere_geometry(scene, radius=1.0, segments=256, rings=128, flat=False, offset=(0.0, 0.0, 0.0), materials=1):
    from mathutils import Matrix

    from penumbra.engine.scene.extract import geometry_from_mesh

    ob = scenes.uv_sphere(scene, "Sphere", radius=radius, segments=segments, rings=rings)
    me = ob.data
    me.transform(Matrix.Translation(offset))
    for poly in me.polygons:
        poly.use_smooth = not flat
        poly.material_index = int(poly.center.x > offset[0]) if materials > 1 else 0
    for i in range(materials):
        me.materials.append(scenes.material(f"M{i}", (0.8, 0.8, 0.8)))
    return geometry_from_mesh(me)


def test_level_for_is_the_coarsest_cell_within_the_pixels(penumbra):
    from penumbra.engine.scene import simplify

    # A 1 m mesh scaled 2x, 10 m away, pixels 1 cm wide there: 2 px cells are at most 2 cm,
    # so at least 2 m / 2 cm = 100 cells: 2^7.
    footprint = (0.001, 0.0)
    assert simplify.level_for(1.0, 2.0, 10.0, footprint, 2.0) == 7
    assert simplify.level_for(1.0, 2.0, 20.0, footprint, 2.0) == 6  # twice as far: one level coarser
    assert simplify.level_for(1.0, 2.0, 10.0, (0.0, 0.01), 2.0) == 7  # orthographic: 1 cm everywhere
    assert simplify.level_for(1.0, 2.0, 1e-3, footprint, 2.0) is None  # finer than MAX_LEVEL: whole
    assert simplify.level_for(1.0, 2.0, 1e6, footprint, 2.0) == simplify.MIN_LEVEL
    for bad in [(0.0, 2.0, 10.0, footprint, 2.0), (1.0, 2.0, 10.0, footprint, 0.0), (1.0, 2.0, 10.0, (0.0, 0.0), 2.0)]:
        assert simplify.level_for(*bad) is None
    assert simplify.level_for(float("inf"), 1.0, 10.0, footprint, 2.0) is None


@pytest.mark.parametrize("flat", [False, True], ids=["smooth", "flat"])
def test_levels_keep_the_sphere_and_its_materials(penumbra, flat):
    from penumbra.engine.scene import simplify

    scene = scenes.empty_scene(32, 32)
    geo = _sphere_geometry(scene, flat=flat, materials=2)
    counts = []
    for level in (3, 4, 5, 6):
        lod = simplify.cluster(geo, level)
        assert lod is not None, level
        cell = 2.0 / 2**level  # the sphere's bounds are 2 m wide
        radius = np.linalg.norm(lod.positions.astype(np.float64), axis=1)
        # Never further than a cell's diagonal from the surface; on a smooth sphere, the
        # quadric placement keeps vertices within a small part of a cell (measured 1-4 %).
        assert np.abs(radius - 1.0).max() <= cell * math.sqrt(3.0)
        assert np.abs(radius - 1.0).mean() <= 0.1 * cell
        normals = lod.normals.astype(np.float64)
        np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)
        # Normals point outwards; a flat level's are its own triangles'.
        centres = lod.positions[lod.indices].mean(axis=1).astype(np.float64)
        tri_normals = normals[lod.indices[:, 0]]
        assert np.mean(np.einsum("ij,ij->i", tri_normals, centres) > 0.0) > 0.99
        if flat:
            p = lod.positions.astype(np.float64)[lod.indices]
            face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
            face /= np.linalg.norm(face, axis=1)[:, None]
            np.testing.assert_allclose(np.einsum("ij,ij->i", face, tri_normals), 1.0, atol=1e-3)
        # Both materials keep their triangles, sorted and covering every triangle once.
        assert [m for m, _s, _c in lod.ranges] == [0, 1]
        assert sum(c for _m, _s, c in lod.ranges) == lod.triangle_count
        assert lod.ranges[1][1] == lod.ranges[0][2]
        assert lod.indices.min() >= 0 and lod.indices.max() < len(lod.positions)
        counts.append(lod.triangle_count)
    assert counts == sorted(counts) and counts[-1] < simplify.WORTH * geo.triangle_count
    assert simplify.cluster(geo, simplify.MAX_LEVEL) is None  # keeps nearly all: not worth it


def test_far_from_the_origin_and_tiny(penumbra):
    from penumbra.engine.scene import simplify

    scene = scenes.empty_scene(32, 32)
    for radius, offset in ((1.0, (1e5, -2e5, 3e4)), (1e-4, (0.0, 0.0, 0.0))):
        geo = _sphere_geometry(scene, radius=radius, segments=128, rings=64, offset=offset)
        lod = simplify.cluster(geo, 5)
        cell = 2.0 * radius / 32
        distance = np.linalg.norm(lod.positions.astype(np.float64) - offset, axis=1)
        # float32 positions: 1e5 m away they are 2^-7 m apart, which bounds what can be checked.
        slack = np.spacing(np.float32(np.abs(offset).max())) * 2 if max(offset) else 0.0
        assert np.abs(distance - radius).max() <= cell * math.sqrt(3.0) + slack
        assert lod.triangle_count < 0.5 * geo.triangle_count


def test_thin_parts_keep_both_sides(penumbra):
    """A 1 mm plate simplified with cells 30 times its thickness: its top and bottom do not
    merge into one folded sheet; both sides still face outwards."""
    import bmesh
    import bpy

    from penumbra.engine.scene import simplify
    from penumbra.engine.scene.extract import geometry_from_mesh

    me = bpy.data.meshes.new("Plate")
    bm = bmesh.new()
    bmesh.ops.create_cube(bm, size=1.0)
    bmesh.ops.scale(bm, vec=(1.0, 1.0, 0.001), verts=bm.verts)
    bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=40, use_grid_fill=True)
    bmesh.ops.triangulate(bm, faces=bm.faces[:])
    bm.to_mesh(me)
    bm.free()
    geo = geometry_from_mesh(me)
    lod = simplify.cluster(geo, 5)  # 3 cm cells
    assert lod is not None and lod.triangle_count < 0.5 * geo.triangle_count
    p = lod.positions.astype(np.float64)[lod.indices]
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    area = 0.5 * np.linalg.norm(face, axis=1)
    up = area[face[:, 2] > 0.9 * 2 * area].sum()
    down = area[face[:, 2] < -0.9 * 2 * area].sum()
    assert up == pytest.approx(1.0, rel=0.05) and down == pytest.approx(1.0, rel=0.05)
    assert np.all(np.abs(p[..., 2]) <= 0.0005 + 1e-6)  # inside the plate's bounds


def _sphere_field(count=9, segments=160, rings=80):
    scene = scenes.empty_scene(160, 90)
    scenes.set_world(scene, WORLD)
    white = scenes.material("White", (0.8, 0.8, 0.8))
    scenes.plane(scene, "Ground", size=30.0, mat=white)
    for i in range(count):
        x, y = (i % 3) * 2.5 - 2.5, (i // 3) * 2.5 - 2.5
        scenes.uv_sphere(scene, f"Ball{i}", center=(x, y, 1.0), segments=segments, rings=rings, mat=white)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(35), 0.0, math.radians(25)))
    scenes.look_at(scene, (0.0, -14.0, 9.0), (0.0, 0.0, 0.5))
    return scene


def test_frames_draw_fewer_triangles_and_look_the_same(penumbra, gpu_call):
    scene = _sphere_field()
    assert scene.penumbra.simplify_pixels == 2.0 and not scene.render.use_simplify  # the defaults
    # The world's ambient occlusion reads the depth of the merged triangles too (with it the
    # mean difference was 2.2e-3): what is measured here is the geometry's own.
    scene.penumbra.world_ao = False
    whole_stats, whole = engine_frame(gpu_call, scene, 160, 90)
    assert whole_stats.simplified == 0
    scene.penumbra.simplify_pixels = 0.0
    scene.render.use_simplify = True
    off_stats, off = engine_frame(gpu_call, scene, 160, 90)  # Simplify on, Merge Below 0
    assert off_stats.simplified == 0 and off_stats.triangles == whole_stats.triangles
    np.testing.assert_array_equal(off, whole)
    scene.penumbra.simplify_pixels = 2.0
    stats, simplified = engine_frame(gpu_call, scene, 160, 90)
    assert stats.simplified == 9  # every ball; the two-triangle ground is too small to simplify
    assert stats.triangles < 0.15 * whole_stats.triangles  # measured 0.094
    diff = np.abs(simplified[..., :3] - whole[..., :3]).max(axis=-1)
    # 2 px cells on smooth balls: outlines move by a fraction of a pixel (measured: mean 2.3e-4,
    # 0.06 % of pixels over 0.05, on outlines).
    assert diff.mean() < 1e-3
    assert np.mean(diff > 0.05) < 0.005
    assert np.abs(whole[..., :3] - WORLD).max(axis=-1).mean() > 0.1  # the scene covers the frame


def test_what_needs_more_than_normals_is_drawn_whole(penumbra, gpu_call):
    """A material reading UVs (an image texture) or with alpha keeps every triangle; so does an
    instance through the camera's near plane."""
    import bpy
    from mathutils import Vector

    scene = _sphere_field(count=3)
    scene.render.use_simplify = True
    scene.penumbra.simplify_pixels = 4.0
    balls = [ob for ob in scene.objects if ob.name.startswith("Ball")]
    textured = scenes.material("Textured", (0.8, 0.8, 0.8))
    tree = textured.node_tree
    image = bpy.data.images.new("Checker", 8, 8)
    node = tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    tree.links.new(node.outputs["Color"], tree.nodes["Principled BSDF"].inputs["Base Color"])
    balls[0].data.materials[0] = textured
    clear = scenes.material("Glass", (0.8, 0.8, 0.8))
    clear.node_tree.nodes["Principled BSDF"].inputs["Alpha"].default_value = 0.5
    balls[1].data = balls[1].data.copy()
    balls[1].data.materials[0] = clear
    stats, _image = engine_frame(gpu_call, scene, 160, 90)
    assert stats.simplified == 1  # the third ball only
    cam = scene.camera
    cam.location = balls[2].location + Vector((0.0, -0.5, 0.0))  # inside it
    bpy.context.view_layer.update()
    stats, _image = engine_frame(gpu_call, scene, 160, 90)
    assert stats.simplified == 0


def test_a_farther_view_draws_coarser_levels_and_keeps_only_its_own(penumbra, gpu_call):
    """One renderer, two frames: the camera pulled back three times as far draws coarser
    levels (fewer triangles), and the GPU batches of levels the new frame does not draw are
    released (a moving viewport does not pile up levels)."""
    import dataclasses

    from mathutils import Vector

    from penumbra.engine.scene.extract import camera_from_scene

    scene = _sphere_field()
    scene.render.use_simplify = True
    scene.penumbra.simplify_pixels = 2.0
    distance = float((scene.camera.location - Vector((0.0, 0.0, 0.5))).length)

    def job(engine, depsgraph):
        near = camera_from_scene(depsgraph, scene, 160, 90)
        back = np.eye(4)
        back[2, 3] = -2.0 * distance  # the world 2 distances further along the view axis
        far = dataclasses.replace(near, view=back @ near.view)
        first = engine.render_frame(depsgraph, near, 160, 90).stats
        near_levels = set(engine.renderer.batches.levels)
        second = engine.render_frame(depsgraph, far, 160, 90).stats
        return first, near_levels, second, set(engine.renderer.batches.levels)

    first, near_levels, second, far_levels = gpu_call(job)
    assert first.simplified == second.simplified == 9
    assert second.triangles < 0.5 * first.triangles
    assert {k[2] for k in far_levels}.isdisjoint({k[2] for k in near_levels})  # coarser levels
    assert 1 <= len(far_levels) <= 9 and far_levels.isdisjoint(near_levels)
