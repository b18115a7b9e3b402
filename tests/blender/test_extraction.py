"""Mesh extraction (engine/scene/extract.py ``geometry_from_mesh``): the indexed buffers read through
the attribute API hold exactly the triangles, corner normals and material slots Blender's own
per-triangle data gives."""

import bpy
import numpy as np

from devkit import scenes


def _reference(mesh):
    """Per material: sorted rows of (triangle corner positions, corner normals), from
    Blender's per-triangle RNA data (``loop_triangles``: vertices, split normals)."""
    mesh.calc_loop_triangles()
    co = np.array([v.co[:] for v in mesh.vertices])
    out = {}
    for tri in mesh.loop_triangles:
        row = np.concatenate([co[list(tri.vertices)].ravel(), np.array(tri.split_normals).ravel()])
        out.setdefault(tri.material_index, []).append(row)
    return {m: np.array(sorted(map(tuple, rows))) for m, rows in out.items()}


def _extracted(geo):
    out = {}
    for mat, first, count in geo.ranges:
        tris = geo.indices[first : first + count]
        rows = np.concatenate([geo.positions[tris].reshape(count, 9), geo.normals[tris].reshape(count, 9)], axis=1)
        out[mat] = np.array(sorted(map(tuple, rows)))
    return out


def _sphere(smooth):
    scene = scenes.empty_scene(32, 32)
    ob = scenes.uv_sphere(scene, "Ball", radius=1.0, segments=12, rings=6)
    me = ob.data
    for i, poly in enumerate(me.polygons):
        poly.material_index = i % 3
        poly.use_smooth = smooth is True or (smooth == "mixed" and i % 2 == 0)
    for _ in range(3):
        me.materials.append(scenes.white())
    me.update()
    return me


def test_extraction_matches_blenders_triangles_normals_and_slots(penumbra):
    from penumbra.engine.scene.extract import geometry_from_mesh

    for smooth in (True, False, "mixed"):
        me = _sphere(smooth)
        geo = geometry_from_mesh(me)
        ref, got = _reference(me), _extracted(geo)
        assert sorted(got) == sorted(ref) == [0, 1, 2]
        for mat in ref:
            np.testing.assert_allclose(got[mat], ref[mat], atol=1e-6, err_msg=f"smooth={smooth} slot {mat}")
        assert geo.triangle_count == len(me.loop_triangles)
        # Smooth meshes share one vertex per mesh vertex; others get one per face corner.
        assert len(geo.positions) == (len(me.vertices) if smooth is True else len(me.loops))


def test_bounds_ignore_loose_vertices_and_broken_triangles_are_dropped(penumbra):
    from penumbra.engine.scene.extract import geometry_from_mesh

    me = _sphere(True)
    me.vertices.add(1)
    me.vertices[-1].co = (100.0, 0.0, 0.0)  # a loose vertex: drawn by nothing
    me.update()
    geo = geometry_from_mesh(me)
    np.testing.assert_allclose(geo.bounds, [[-1, -1, -1], [1, 1, 1]], atol=1e-6)
    tris_before = geo.triangle_count
    me.vertices[1].co = (float("nan"), 0.0, 0.0)
    geo = geometry_from_mesh(me)
    assert 0 < geo.triangle_count < tris_before
    assert np.isfinite(geo.positions[geo.indices]).all()
    bpy.data.meshes.remove(me)


def test_closed_outward_surfaces_are_told_apart(penumbra):
    """``Geometry.closed``: closed and consistently outward only; an open mesh, a flipped or
    partly flipped one and a cavity (an inward inner shell) are drawn whole."""
    import bmesh

    from devkit import assets
    from penumbra.engine.scene.extract import geometry_from_mesh

    scene = scenes.empty_scene(32, 32)

    def mesh(build):
        me = bpy.data.meshes.new("M")
        bm = bmesh.new()
        build(bm)
        bm.to_mesh(me)
        bm.free()
        return me

    def cube(bm, size=1.0, offset=(0.0, 0.0, 0.0)):
        verts = bmesh.ops.create_cube(bm, size=size)["verts"]
        bmesh.ops.translate(bm, verts=verts, vec=offset)
        return list({f for v in verts for f in v.link_faces})

    def flipped(bm):
        bmesh.ops.reverse_faces(bm, faces=cube(bm))

    def one_flipped(bm):
        bmesh.ops.reverse_faces(bm, faces=cube(bm)[:1])

    def cavity(bm):
        cube(bm, 2.0)
        bmesh.ops.reverse_faces(bm, faces=cube(bm, 1.0))

    def two(bm):
        cube(bm)
        cube(bm, offset=(3.0, 0.0, 0.0))

    def far(bm):
        cube(bm, offset=(1e5, 1e5, 0.0))

    def grid(bm):
        bmesh.ops.create_grid(bm, x_segments=3, y_segments=3, size=1.0)

    expect = {cube: True, two: True, far: True, flipped: False, one_flipped: False, cavity: False, grid: False}
    for build, closed in expect.items():
        assert geometry_from_mesh(mesh(build)).closed is closed, build.__name__
    assert geometry_from_mesh(assets.import_mesh(scene, assets.SPOT).data).closed
    assert not geometry_from_mesh(assets.import_mesh(scene, assets.BUNNY).data).closed  # holes underneath


def test_tangents_are_kept_by_content_between_extractions(penumbra, monkeypatch):
    """MikkTSpace tangents are remembered by what they are made from (every F12 render extracts
    anew): a second extraction of the same mesh reuses them, bit for bit what Blender computes;
    moved UVs, or another mesh of the same content but with n-gons named, compute or say anew."""
    from penumbra.engine.scene import extract

    scene = scenes.empty_scene(32, 32)
    me = scenes.uv_sphere(scene, "Ball", radius=1.0, segments=16, rings=8).data
    uv = me.uv_layers.new(name="UVMap")
    n = len(me.loops)
    rng = np.random.default_rng(3)
    uv.data.foreach_set("uv", rng.random(2 * n).astype(np.float32))
    needs = extract.Needs(uv_map="", tangents=True)
    extract._TANGENTS.clear()
    computed = []
    original = extract._tangents
    monkeypatch.setattr(extract, "_tangents", lambda *a: computed.append(1) or original(*a))
    first = extract.geometry_from_mesh(me, needs).tangents
    again = extract.geometry_from_mesh(me, needs).tangents
    assert len(computed) == 1 and np.array_equal(first, again) and np.abs(first[:, 3]).min() == 1.0
    moved = rng.random(2 * n).astype(np.float32)
    uv.data.foreach_set("uv", moved)
    changed = extract.geometry_from_mesh(me, needs).tangents
    assert len(computed) == 2 and not np.array_equal(changed, first)
    extract._TANGENTS.clear()
    assert np.array_equal(extract.geometry_from_mesh(me, needs).tangents, changed)

    hexagon = bpy.data.meshes.new("Hexagon")
    verts = [(-1, -1, 0), (0, -1, 0), (1, -1, 0), (1, 1, 0), (0, 1, 0), (-1, 1, 0)]
    hexagon.from_pydata(verts, [], [tuple(range(6))])
    hexagon.uv_layers.new(name="UVMap")
    twin = hexagon.copy()
    twin.name = "Twin"
    said = []
    for mesh in (hexagon, twin):
        extract.geometry_from_mesh(mesh, needs)
    extract._corner_uvs(twin, needs, 6, said, *(lambda g: (g.positions, g.normals))(extract.geometry_from_mesh(twin)))
    assert said == [extract.NGON_TANGENTS.format(name="Twin")]
