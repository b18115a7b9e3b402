"""Real meshes for the reference kit, the benchmarks and tests, kept in this repository in a
compact form (``devkit/meshes/*.npz``: see the README there for each mesh's source and terms,
and ``tools/mesh_to_npz.py`` for the format). Nothing here ships in the extension."""

from pathlib import Path

import bpy
import numpy as np
from mathutils import Matrix, Vector

MESHES = Path(__file__).resolve().parent / "meshes"
BUNNY = MESHES / "stanford-bunny.npz"  # 69,451 triangles
SPOT = MESHES / "spot.npz"  # 5,856 triangles


def mesh_from_file(path, name):
    """A new flat-shaded mesh datablock ``name`` from a ``.npz`` of ``positions``,
    ``triangles`` and (optionally) per-corner ``uv``."""
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such test mesh (see {MESHES / 'README.md'})")
    with np.load(path) as data:
        positions = np.ascontiguousarray(data["positions"], np.float32)
        triangles = np.ascontiguousarray(data["triangles"], np.int32)
        uv = np.ascontiguousarray(data["uv"], np.float32) if "uv" in data.files else None
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(positions))
    me.vertices.foreach_set("co", positions.ravel())
    me.loops.add(triangles.size)
    me.loops.foreach_set("vertex_index", triangles.ravel())
    me.polygons.add(len(triangles))
    me.polygons.foreach_set("loop_start", np.arange(0, triangles.size, 3, dtype=np.int32))
    if uv is not None:
        me.uv_layers.new(name="UVMap").data.foreach_set("uv", uv.ravel())
    me.update(calc_edges=True)
    me.shade_flat()
    if me.validate(verbose=False):
        raise ValueError(f"{path}: the mesh did not validate")
    return me


def import_mesh(scene, path, height=1.0, name=None):
    """Add the mesh in ``path`` (one of the constants above) to ``scene``'s master collection
    as one object, scaled to ``height`` and standing on z = 0 at the origin. Returns the object."""
    name = name or path.stem
    me = mesh_from_file(path, name)
    ob = bpy.data.objects.new(name, me)
    scene.collection.objects.link(ob)
    co = np.empty(len(me.vertices) * 3, np.float64)
    me.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    lo, hi = co.min(axis=0), co.max(axis=0)
    scale = height / max(hi[2] - lo[2], 1e-12)
    foot = Vector(((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]))
    me.transform(Matrix.Diagonal((scale, scale, scale, 1.0)) @ Matrix.Translation(-foot))
    me.update()
    return ob
