"""The shared real meshes (``../shared/assets/`` next to the project root; see its README for
each mesh's source and terms). Nothing here ships in the extension."""

import bpy
import numpy as np
from mathutils import Matrix, Vector

from devkit.session import ROOT, stdout_to_stderr

ASSETS = ROOT.parent / "shared" / "assets"
BUNNY = ASSETS / "stanford-bunny.obj"  # 69,451 triangles
SPOT = ASSETS / "spot.obj"  # 5,856 triangles


def import_mesh(scene, path, height=1.0, name=None):
    """Import an OBJ file into ``scene``'s master collection as one object, scaled to
    ``height`` and standing on z = 0 at the origin. Returns the object."""
    if not path.exists():
        raise FileNotFoundError(f"{path}: the shared assets folder is missing")
    before = set(bpy.data.objects)
    with stdout_to_stderr():  # the importer prints its timing to stdout
        bpy.ops.wm.obj_import(filepath=str(path))
    ob = next(o for o in bpy.data.objects if o not in before and o.type == "MESH")
    if name:
        ob.name = ob.data.name = name
    for collection in list(ob.users_collection):
        collection.objects.unlink(ob)
    scene.collection.objects.link(ob)
    me = ob.data
    me.transform(ob.matrix_world)  # the importer's Y-up to Z-up rotation, baked in
    ob.matrix_world = Matrix.Identity(4)
    co = np.empty(len(me.vertices) * 3, np.float64)
    me.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    lo, hi = co.min(axis=0), co.max(axis=0)
    scale = height / max(hi[2] - lo[2], 1e-12)
    foot = Vector(((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]))
    me.transform(Matrix.Diagonal((scale, scale, scale, 1.0)) @ Matrix.Translation(-foot))
    me.update()
    return ob
