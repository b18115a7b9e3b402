"""Depsgraph -> a plain scene snapshot (dataclasses and numpy arrays).

Geometry is the expensive part, so it is cached per mesh datablock (or per object when
modifiers make its mesh unique) and rebuilt only when a depsgraph update says that geometry
changed. Matrices, materials, lights and the camera are cheap and read every frame.
"""

import math
import sys
from dataclasses import dataclass

import numpy as np

GEOMETRY_TYPES = {"MESH", "CURVE", "SURFACE", "FONT", "META"}


@dataclass
class Material:
    base_color: tuple = (0.8, 0.8, 0.8, 1.0)
    roughness: float = 0.5
    specular: float = 0.5
    metallic: float = 0.0


@dataclass
class Geometry:
    """Triangles of one mesh as an indexed vertex buffer, the triangles sorted by material slot.

    A vertex is a mesh vertex when the mesh is smooth throughout (normals on points), else a
    face corner (flat or mixed shading: normals on faces or corners), as Blender's own draw
    code does; triangles index those vertices."""

    positions: np.ndarray  # (vertices, 3) float32
    normals: np.ndarray  # (vertices, 3) float32
    indices: np.ndarray  # (triangles, 3) int32 into positions
    ranges: list  # (material index, first triangle, triangle count)
    bounds: np.ndarray  # (2, 3) local min/max of the drawn vertices; NaN when empty
    deps: frozenset = frozenset()
    serial: int = 0  # distinguishes rebuilt geometry of the same key (GPU batches key on it)

    @property
    def triangle_count(self):
        return len(self.indices)


@dataclass
class MeshInstance:
    key: tuple
    matrix: np.ndarray  # (4, 4) world matrix
    materials: list  # Material per slot (index = material index)


@dataclass
class Light:
    type: str
    color: np.ndarray  # colour * energy * 2^exposure
    matrix: np.ndarray
    radius: float
    spot_size: float = math.pi / 4
    spot_blend: float = 0.15
    angle: float = 0.0
    use_shadow: bool = True
    size: float = 0.0  # area lights: the larger side (for PCSS softness)
    bias_scale: float = 1.0  # light.penumbra.bias_scale
    size_x: float = 0.0  # area lights: the sides along the light's local X and Y
    size_y: float = 0.0
    shape: str = "SQUARE"  # area lights: SQUARE, RECTANGLE, DISK or ELLIPSE
    penumbra_scale: float = 1.0  # the light size PCSS sees, relative (1/sqrt(samples) when sampled)
    sampled: bool = False  # moves between samples: its shadow is PCSS of its per-sample size

    @property
    def shadow_radius(self):
        """Radius of the emitter for soft shadows: Blender's shadow_soft_size, or half an area
        light's size."""
        return 0.5 * self.size if self.type == "AREA" else self.radius

    @property
    def position(self):
        return self.matrix[:3, 3].copy()

    @property
    def direction(self):
        d = -self.matrix[:3, 2]
        n = np.linalg.norm(d)
        return d / n if n > 0 and np.isfinite(n) else np.array([0.0, 0.0, -1.0])


@dataclass
class Camera:
    view: np.ndarray  # world -> view
    projection: np.ndarray
    is_ortho: bool = False

    @property
    def position(self):
        try:
            return np.linalg.inv(self.view)[:3, 3]
        except np.linalg.LinAlgError:
            return np.zeros(3)

    @property
    def forward(self):
        f = -self.view[2, :3]
        n = np.linalg.norm(f)
        return f / n if n > 0 else np.array([0.0, 0.0, -1.0])


@dataclass
class Snapshot:
    instances: list
    lights: list
    world_color: np.ndarray
    geometry: dict  # key -> Geometry (shared with the cache)


def matrix_np(m):
    return np.array(m, dtype=np.float64).reshape(4, 4)


def camera_from_scene(depsgraph, scene, width, height, matrix_world=None, shift_x=None):
    """The active scene camera's matrices for a final render of ``width`` x ``height``.
    ``matrix_world`` and ``shift_x`` override the camera's own for one view of a multiview
    render (Blender's ``RenderEngine.camera_model_matrix`` / ``camera_shift_x``)."""
    cam_ob = scene.camera.evaluated_get(depsgraph)
    aspect_x, aspect_y = scene.render.pixel_aspect_x, scene.render.pixel_aspect_y
    proj = matrix_np(cam_ob.calc_matrix_camera(depsgraph, x=width, y=height, scale_x=aspect_x, scale_y=aspect_y))
    ortho = cam_ob.data.type == "ORTHO"
    if shift_x is not None and shift_x != cam_ob.data.shift_x:
        delta = (shift_x - cam_ob.data.shift_x) * shift_scale(
            cam_ob.data.sensor_fit, width * aspect_x, height * aspect_y
        )
        if ortho:
            proj[0, 3] -= delta
        else:
            proj[0, 2] += delta
    world = cam_ob.matrix_world if matrix_world is None else matrix_world
    view = matrix_np(world.inverted_safe())
    return Camera(view=view, projection=proj, is_ortho=ortho)


def shift_scale(sensor_fit, width, height):
    """How far (in NDC x) a camera shift of 1 moves the frame: Blender measures shift in units
    of the fitted sensor side (the larger image side for AUTO)."""
    side = {"HORIZONTAL": width, "VERTICAL": height}.get(sensor_fit, max(width, height))
    return 2.0 * side / width


def camera_from_view(view_matrix, window_matrix):
    """The viewport's camera from a RegionView3D's ``view_matrix`` and ``window_matrix``."""
    proj = matrix_np(window_matrix)
    return Camera(view=matrix_np(view_matrix), projection=proj, is_ortho=abs(proj[3, 3] - 1.0) < 1e-9)


# --- materials ---------------------------------------------------------------------------

_SPECULAR_INPUTS = ("Specular IOR Level", "Specular")


def _input_value(node, name, default):
    sock = node.inputs.get(name)
    if sock is None:
        return default
    return sock.default_value


def _principled(mat):
    tree = getattr(mat, "node_tree", None)
    if tree is None:
        return None
    nodes = tree.nodes
    for out in nodes:
        if out.bl_idname == "ShaderNodeOutputMaterial" and out.is_active_output:
            surface = out.inputs.get("Surface")
            if surface is not None and surface.is_linked:
                node = surface.links[0].from_node
                if node.bl_idname == "ShaderNodeBsdfPrincipled":
                    return node
    for node in nodes:
        if node.bl_idname == "ShaderNodeBsdfPrincipled":
            return node
    return None


def material_from_blender(mat):
    if mat is None:
        return Material()
    node = _principled(mat) if getattr(mat, "use_nodes", True) else None
    if node is not None:
        spec = 0.5
        for name in _SPECULAR_INPUTS:
            if name in node.inputs:
                spec = float(_input_value(node, name, 0.5))
                break
        return Material(
            base_color=tuple(_input_value(node, "Base Color", (0.8, 0.8, 0.8, 1.0))),
            roughness=float(_input_value(node, "Roughness", 0.5)),
            specular=spec,
            metallic=float(_input_value(node, "Metallic", 0.0)),
        )
    return Material(
        base_color=tuple(mat.diffuse_color),
        roughness=float(mat.roughness),
        specular=float(mat.specular_intensity),
        metallic=float(mat.metallic),
    )


def world_color(scene):
    world = scene.world
    if world is None:
        return np.zeros(3)
    tree = getattr(world, "node_tree", None)
    if tree is not None and getattr(world, "use_nodes", True):
        for node in tree.nodes:
            if node.bl_idname == "ShaderNodeBackground":
                color = node.inputs["Color"].default_value
                strength = node.inputs["Strength"].default_value
                return np.array(color[:3], dtype=np.float64) * float(strength)
    return np.array(world.color[:3], dtype=np.float64)


# --- geometry ----------------------------------------------------------------------------


def _read(collection, attr, count, dtype, width=1):
    out = np.empty(count * width, dtype)
    collection.foreach_get(attr, out)
    return out.reshape(-1, width) if width > 1 else out


def _attribute(mesh, name, prop, count, dtype, width=1):
    """A mesh attribute's values through the attribute API (a plain copy of Blender's array,
    many times faster than the per-element RNA collections), or None when it is absent."""
    attr = mesh.attributes.get(name)
    if attr is None:
        return None
    return _read(attr.data, prop, count, dtype, width)


def geometry_from_mesh(mesh):
    """A Blender mesh as an indexed triangle buffer (``Geometry``), read with ``foreach_get``
    from Blender's own arrays (the attribute API): positions, corner vertices, each triangle's
    corners and face, the faces' material indices, and normals on points (smooth meshes) or
    corners (``Mesh.normals_domain``).

    Triangles with a non-finite vertex are dropped (NaN/Inf positions must not reach the GPU).
    """
    mesh.calc_loop_triangles()
    n = len(mesh.loop_triangles)
    if n == 0:
        empty = np.zeros((0, 3), np.float32)
        return Geometry(empty, empty, np.zeros((0, 3), np.int32), [], np.full((2, 3), np.nan))
    nv, nc = len(mesh.vertices), len(mesh.loops)
    co = _attribute(mesh, "position", "vector", nv, np.float32, 3)
    if co is None:
        co = _read(mesh.vertices, "co", nv, np.float32, 3)
    corner_vert = _attribute(mesh, ".corner_vert", "value", nc, np.int32)
    if corner_vert is None:
        corner_vert = _read(mesh.loops, "vertex_index", nc, np.int32)
    corners = _read(mesh.loop_triangles, "loops", n, np.int32, 3)
    face_material = _attribute(mesh, "material_index", "value", len(mesh.polygons), np.int32)
    if face_material is None:
        mat = np.zeros(n, np.int32)  # no attribute: every face uses the first slot
    else:
        mat = face_material[_read(mesh.loop_triangle_polygons, "value", n, np.int32)]
    if mesh.normals_domain == "POINT":  # smooth throughout: one vertex per mesh vertex
        positions = co
        normals = _read(mesh.vertex_normals, "vector", nv, np.float32, 3)
        tris = corner_vert[corners]
    else:  # flat or mixed: one vertex per face corner
        positions = co[corner_vert]
        normals = _read(mesh.corner_normals, "vector", nc, np.float32, 3)
        tris = corners
    dropped = False
    if not np.isfinite(positions).all():
        vertex_ok = np.isfinite(positions).all(axis=1)
        good = vertex_ok[tris].all(axis=1)
        print(
            f"Penumbra: mesh '{mesh.name}': skipped {int((~good).sum())} triangle(s) with non-finite vertices",
            file=sys.stderr,
        )
        tris, mat = tris[good], mat[good]
        positions = np.where(vertex_ok[:, None], positions, 0.0).astype(np.float32)
        dropped = True
    if not np.isfinite(normals).all():
        normals = np.where(np.isfinite(normals), normals, 0.0).astype(np.float32)
    ranges = []
    if len(mat):
        lo_mat, hi_mat = (0, 0) if face_material is None else (int(mat.min()), int(mat.max()))
        if lo_mat == hi_mat:  # one material: already in order
            ranges = [(lo_mat, 0, len(mat))]
        else:
            order = np.argsort(mat, kind="stable")
            tris, mat = tris[order], mat[order]
            counts = np.bincount(mat - lo_mat)
            starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
            ranges = [(lo_mat + i, int(starts[i]), int(c)) for i, c in enumerate(counts) if c]
    drawn = positions
    if dropped or len(positions) == nv:  # mesh vertices may be loose (in no triangle)
        used = np.zeros(len(positions), bool)
        used[tris.ravel()] = True
        drawn = positions[used]
    bounds = np.array([drawn.min(axis=0), drawn.max(axis=0)]) if len(drawn) else np.full((2, 3), np.nan)
    return Geometry(
        np.ascontiguousarray(positions, np.float32),
        np.ascontiguousarray(normals, np.float32),
        np.ascontiguousarray(tris, np.int32),
        ranges,
        bounds.astype(np.float64),
    )


def _geometry_key(inst, ob, own_data):
    """Cache key and the datablock names whose geometry updates invalidate it.

    ``own_data(orig)`` is the pointer of the evaluated geometry of object ``orig`` itself. An
    instance that draws exactly that geometry (a collection instance, dupli-verts, a particle
    instance) shares the object's key, so its geometry is extracted once whatever the number
    of instances; an instance with other geometry (made by a geometry-nodes modifier) is keyed
    by that geometry."""
    orig = ob.original if ob.original is not None else ob
    data = ob.data
    data_name = data.original.name_full if data is not None and data.original is not None else ""
    name = orig.name_full
    if inst.is_instance and data is not None and data.as_pointer() != own_data(orig):
        # Geometry made by the object's modifiers for its instances: shared by every instance
        # of that same geometry, rebuilt when the object's geometry changes.
        return ("GN", name, data_name, data.as_pointer()), frozenset({name, data_name})
    if ob.type == "MESH" and len(orig.modifiers) == 0 and not _has_shape_keys(orig):
        return ("ME", data_name), frozenset({data_name, name})
    return ("OB", name), frozenset({name, data_name})


def _has_shape_keys(ob):
    data = ob.data
    return getattr(data, "shape_keys", None) is not None


class SceneCache:
    """Geometry cache of one engine instance, keyed by datablock, invalidated by updates."""

    def __init__(self):
        self.geometry = {}
        self.built = 0  # geometries extracted since creation (tests and stats read it)
        self.materials = {}  # material name -> Material, until an update changes it
        self.materials_read = 0

    def apply_updates(self, depsgraph):
        """Drop the geometry of every datablock whose geometry the depsgraph says changed, and
        the material read of every material (or, for a node group, every material) that
        changed."""
        changed = set()
        for update in depsgraph.updates:
            id_orig = update.id.original if update.id.original is not None else update.id
            kind = getattr(id_orig, "id_type", "")
            if kind == "MATERIAL":
                self.materials.pop(id_orig.name_full, None)
            elif kind == "NODETREE" and not getattr(id_orig, "is_embedded_data", False):
                self.materials.clear()  # a node group may feed any material (a material's own
                # tree is embedded data: its material is updated too)
            if update.is_updated_geometry:
                changed.add(id_orig.name_full)
        if changed:
            self.invalidate(changed)

    def _material(self, mat):
        """A material's shading values, read once per material datablock (not per object)
        until a depsgraph update says it changed."""
        if mat is None:
            return None
        key = mat.original.name_full if mat.original is not None else mat.name_full
        cached = self.materials.get(key)
        if cached is None:
            cached = self.materials[key] = material_from_blender(mat)
            self.materials_read += 1
        return cached

    def invalidate(self, names):
        for key in [k for k, g in self.geometry.items() if g.deps & names]:
            del self.geometry[key]

    def clear(self):
        self.geometry.clear()
        self.materials.clear()

    def _geometry_for(self, inst, ob, key, deps):
        geo = self.geometry.get(key)
        if geo is not None:
            return geo
        if ob.type == "MESH":
            geo = geometry_from_mesh(ob.data)
        else:
            mesh = ob.to_mesh()
            try:
                geo = geometry_from_mesh(mesh) if mesh is not None else None
            finally:
                ob.to_mesh_clear()
            if geo is None:
                return None
        geo.deps = deps
        self.geometry[key] = geo
        self.built += 1
        geo.serial = self.built
        return geo

    def snapshot(self, depsgraph):
        scene = depsgraph.scene
        instances = []
        lights = []
        used = set()
        own = {}

        def own_data(orig):
            """Pointer of ``orig``'s own evaluated geometry (cached for this snapshot)."""
            key = orig.name_full
            if key not in own:
                data = orig.evaluated_get(depsgraph).data
                own[key] = data.as_pointer() if data is not None else 0
            return own[key]

        for inst in depsgraph.object_instances:
            ob = inst.object
            if ob.type == "LIGHT":
                light = light_from_blender(ob.data, matrix_np(inst.matrix_world))
                if light is not None:
                    lights.append(light)
                continue
            if ob.type not in GEOMETRY_TYPES:
                continue
            matrix = matrix_np(inst.matrix_world)
            if not np.all(np.isfinite(matrix)):
                print(f"Penumbra: object '{ob.name}' has a non-finite matrix; skipped", file=sys.stderr)
                continue
            key, deps = _geometry_key(inst, ob, own_data)
            geo = self._geometry_for(inst, ob, key, deps)
            if geo is None or geo.triangle_count == 0:
                continue
            used.add(key)
            materials = [self._material(slot.material) for slot in ob.material_slots]
            instances.append(MeshInstance(key=key, matrix=matrix, materials=materials))
        # Forget geometry no longer in the scene so its GPU buffers are freed.
        for key in [k for k in self.geometry if k not in used]:
            del self.geometry[key]
        return Snapshot(
            instances=instances,
            lights=lights,
            world_color=world_color(scene),
            geometry=self.geometry,
        )


def light_from_blender(data, matrix):
    color = np.array(data.color[:3], dtype=np.float64) * float(data.energy)
    color *= 2.0 ** float(getattr(data, "exposure", 0.0))
    if not np.all(np.isfinite(color)) or not np.all(np.isfinite(matrix)):
        return None
    radius = float(getattr(data, "shadow_soft_size", 0.0))
    if not getattr(data, "use_soft_falloff", True):
        radius = 0.0
    light = Light(type=data.type, color=color, matrix=matrix, radius=radius, use_shadow=bool(data.use_shadow))
    if data.type == "SPOT":
        light.spot_size = float(data.spot_size)
        light.spot_blend = float(data.spot_blend)
    elif data.type == "SUN":
        light.angle = float(data.angle)
    elif data.type == "AREA":
        light.radius = 0.0
        light.shape = data.shape
        light.size_x = float(data.size)
        light.size_y = float(data.size_y) if data.shape in {"RECTANGLE", "ELLIPSE"} else light.size_x
        light.size = max(light.size_x, light.size_y)
    settings = getattr(data, "penumbra", None)
    if settings is not None:
        light.bias_scale = float(settings.bias_scale)
    return light
