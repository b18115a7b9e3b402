"""Real meshes for the reference kit, the benchmarks and tests, kept in this repository in a
compact form (``devkit/meshes/*.npz``: see the README there for each mesh's source and terms,
and ``tools/mesh_to_npz.py`` for the format). Nothing here ships in the extension."""

import math
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


# --- glTF assets ----------------------------------------------------------------------------

GLTF = Path(__file__).resolve().parent / "gltf"
# The assets of devkit/gltf/ (tools/make_assets.py writes them; the README there says what each
# one holds and its terms).
GLTF_ASSETS = ("spot_pbr", "spot_alpha", "spot_specgloss", "spot_lines")


def import_gltf(scene, path, height=1.0):
    """Import the glTF file ``path`` into ``scene`` with Blender's own importer (enabling it),
    as a user would, then scale the import to ``height`` standing on z = 0, centred on the
    origin, through an empty that becomes the parent of its top-level objects. Returns the
    imported objects."""
    if bpy.ops.preferences.addon_enable(module="io_scene_gltf2") != {"FINISHED"}:
        raise RuntimeError("Blender's glTF importer (io_scene_gltf2) could not be enabled")
    before = set(bpy.data.objects)
    with bpy.context.temp_override(scene=scene, view_layer=scene.view_layers[0]):
        bpy.ops.import_scene.gltf(filepath=str(path))
    imported = [ob for ob in bpy.data.objects if ob not in before]
    bpy.context.view_layer.update()
    corners = [ob.matrix_world @ Vector(c) for ob in imported if ob.type == "MESH" for c in ob.bound_box]
    if not corners:
        raise ValueError(f"{path}: no mesh imported")
    co = np.array([tuple(c) for c in corners])
    lo, hi = co.min(axis=0), co.max(axis=0)
    scale = height / max(hi[2] - lo[2], 1e-12)
    root = bpy.data.objects.new(f"{Path(path).stem}_root", None)
    scene.collection.objects.link(root)
    for ob in imported:
        if ob.parent is None:
            ob.parent = root
    root.scale = (scale, scale, scale)
    root.location = (-scale * (lo[0] + hi[0]) / 2, -scale * (lo[1] + hi[1]) / 2, -scale * lo[2])
    bpy.context.view_layer.update()
    return imported


def gltf_scene(name, width=240, height=135):
    """A scene to render glTF asset ``name`` (one of ``GLTF_ASSETS``) as a new user would: the
    file imported with Blender's importer, one unit tall on a grey ground, a sun (2 degrees) and
    a soft area light, a dim grey world, a camera at three-quarter view of its front."""
    from devkit import scenes

    scene = scenes.empty_scene(width, height)
    scenes.set_world(scene, (0.05, 0.05, 0.05))
    scenes.plane(scene, "Ground", size=12.0, mat=scenes.material("Ground", (0.45, 0.45, 0.45), roughness=0.8))
    import_gltf(scene, GLTF / f"{name}.glb")
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(45), 0.0, math.radians(215)), angle=math.radians(2))
    area = scenes.light(scene, "Area", "AREA", 60.0, location=(2.0, 1.5, 2.5), size=1.0)
    scenes.aim(area, (0.0, 0.0, 0.4))
    scenes.look_at(scene, (-1.9, 2.6, 1.3), (0.0, 0.0, 0.45), lens=45.0)  # Spot looks along +Y
    return scene
