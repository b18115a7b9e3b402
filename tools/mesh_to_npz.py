"""Convert a triangle mesh (OBJ, read by Blender's own importer) to the compact form the test
meshes are kept in (``devkit/meshes/*.npz``): ``positions`` float32 (n, 3) in Blender's Z-up
axes (the importer's Y-up conversion baked in), ``triangles`` int32 (m, 3) and, when the file
has texture coordinates, ``uv`` float32 (3 m, 2) per face corner. Faces are flat-shaded, as the
importer leaves a file without smoothing groups.

    .venv/blender-5.2/bin/python -m tools.mesh_to_npz model.obj devkit/meshes/model.npz
"""

import argparse
from pathlib import Path

import numpy as np

from devkit import session


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("source", type=Path, help="an OBJ file of triangles")
    parser.add_argument("target", type=Path, help="the .npz to write")
    args = parser.parse_args()
    session.isolate()
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    with session.stdout_to_stderr():
        bpy.ops.wm.obj_import(filepath=str(args.source.resolve()))
    ob = next(o for o in bpy.data.objects if o.type == "MESH")
    me = ob.data
    me.transform(ob.matrix_world)
    if any(len(p.vertices) != 3 for p in me.polygons):
        raise SystemExit(f"{args.source}: only triangle meshes are converted")
    positions = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", positions)
    triangles = np.empty(len(me.polygons) * 3, np.int32)
    me.polygons.foreach_get("vertices", triangles)
    arrays = {"positions": positions.reshape(-1, 3), "triangles": triangles.reshape(-1, 3)}
    if me.uv_layers:
        uv = np.empty(len(me.loops) * 2, np.float32)
        me.uv_layers[0].data.foreach_get("uv", uv)
        arrays["uv"] = uv.reshape(-1, 2)
    args.target.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(args.target, **arrays)
    sizes = ", ".join(f"{k} {v.shape}" for k, v in arrays.items())
    print(f"{args.target}: {sizes}, {args.target.stat().st_size} bytes")


if __name__ == "__main__":
    main()
