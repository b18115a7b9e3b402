"""Depsgraph -> a plain scene snapshot (dataclasses and numpy arrays).

Geometry is the expensive part, so it is cached per mesh datablock (or per object when
modifiers make its mesh unique) and rebuilt only when a depsgraph update says that geometry
changed. Matrices, materials, lights and the camera are cheap and read every frame.
"""

import dataclasses
import math
import sys
from dataclasses import dataclass

import numpy as np

from ..store import Kind
from . import hair, volumes
from .geometry import Geometry, content_key
from .materials import material_from_blender, world_from_blender
from .terminator import Terminator

GEOMETRY_TYPES = {"MESH", "CURVE", "SURFACE", "FONT", "META"}
# Object types Blender's own engines render that Penumbra does not: named in the report.
_NOT_DRAWN = {
    "POINTCLOUD": "point cloud object",
    "VOLUME": "volume object",
    "GREASEPENCIL": "Grease Pencil object",
    "GPENCIL": "Grease Pencil object",
}


@dataclass(frozen=True)
class Needs:
    """Vertex data beyond positions and normals that an object's materials read."""

    uv_map: str | None = None  # "" = the active render UV map
    color_attribute: str | None = None  # "" = the active render colour attribute
    tangents: bool = False  # MikkTSpace tangents of ``uv_map`` (normal maps)
    uv_pass_only: bool = False  # the UV map is read for the UV pass alone (no texture reads it)

    @classmethod
    def of(cls, materials, data=None):
        """What ``materials`` read of an object whose geometry is ``data`` (a Mesh, or None),
        and what more they ask that is not drawn: (uv maps, colour attributes) beyond the
        first. A map or attribute named as the mesh's active render one is that one ("" too):
        glTF's importer names the UV map on its Normal Map nodes and not on its images."""
        active_uv, active_color = _active_layers(data)
        uv_maps, colors, tangents = [], [], False
        for mat in materials:
            if mat is None:
                continue
            maps = ["" if m == active_uv else m for m in mat.uv_maps]
            uv_maps += [m for m in dict.fromkeys(maps) if m not in uv_maps]
            color = (
                "" if mat.color_attribute is not None and mat.color_attribute == active_color else mat.color_attribute
            )
            if color is not None and color not in colors:
                colors.append(color)
            tangents |= "normal" in mat.textures
        return cls(uv_maps[0] if uv_maps else None, colors[0] if colors else None, tangents), (
            uv_maps[1:],
            colors[1:],
        )

    @property
    def any(self):
        return self.uv_map is not None or self.color_attribute is not None


def _active_layers(data):
    """Names of the active render UV map and colour attribute of mesh ``data`` (None each
    where it has none, or is no mesh)."""
    uv = color = None
    layers = getattr(data, "uv_layers", None)
    if layers is not None:
        uv = next((u.name for u in layers if u.active_render), None)
    attrs = getattr(data, "color_attributes", None)
    if attrs is not None and 0 <= attrs.render_color_index < len(attrs):
        color = attrs[attrs.render_color_index].name
    return uv, color


@dataclass
class MeshInstance:
    key: tuple
    matrix: np.ndarray  # (4, 4) world matrix
    materials: list  # Material per slot (index = material index)
    shadow: bool = True  # casts shadows (Object > Visibility > Ray Visibility > Shadow)
    camera: bool = True  # seen by the camera (Ray Visibility > Camera)
    holdout: bool = False  # Object > Visibility > Holdout: alpha 0 where it covers
    names: tuple = ()  # the object's name and its instancer's: what light linking matches
    terminator: Terminator = Terminator()  # Object > Shading > Shadow Terminator
    color: tuple = (1.0, 1.0, 1.0, 1.0)  # Object > Viewport Display > Color (the Object Info node's)
    random: float = 0.0  # the Object Info node's Random: Blender's per-object (or per-instance) hash
    hair: str | None = None  # hair strips (``Geometry.strands``): Render > Curves > Shape (STRAND, STRIP)
    motion_key: tuple = ()  # which instance it is at another time of the shutter (``motion_key``)
    pass_index: int = 0  # Object > Relations > Pass Index (the Object Index pass)
    crypto_names: tuple = ("", "")  # its Cryptomatte object and asset (topmost parent) names
    lightgroup: str = ""  # Object > Shading > Light Group: the light group its emission is in


@dataclass(frozen=True)
class LinkSet:
    """A light's receiver or blocker collection, as Blender's light linking reads it: objects
    set to Include and to Exclude (a child collection's state holds for everything in it).
    With any Include, only those are linked; otherwise all but the excluded."""

    include: frozenset = frozenset()
    exclude: frozenset = frozenset()

    def links(self, names):
        if any(n in self.exclude for n in names):
            return False
        return not self.include or any(n in self.include for n in names)


def _hash_string(text):
    """The string hash Cycles seeds an object's random number with (h = 37 h + byte), 32-bit."""
    h = 0
    for b in text.encode("utf-8"):
        h = (h * 37 + b) & 0xFFFFFFFF
    return h


def _hash_int_2d(kx, ky):
    """Bob Jenkins' final mix of two 32-bit integers (Blender's BLI_hash_int_2d)."""
    m = 0xFFFFFFFF

    def rot(x, k):
        return ((x << k) | (x >> (32 - k))) & m

    a = b = c = (0xDEADBEEF + (2 << 2) + 13) & m
    a = (a + kx) & m
    b = (b + ky) & m
    c ^= b
    c = (c - rot(b, 14)) & m
    a ^= c
    a = (a - rot(c, 11)) & m
    b ^= a
    b = (b - rot(a, 25)) & m
    c ^= b
    c = (c - rot(b, 16)) & m
    a ^= c
    a = (a - rot(c, 4)) & m
    b ^= a
    b = (b - rot(a, 14)) & m
    c ^= b
    c = (c - rot(b, 24)) & m
    return c


def object_random(name, inst=None):
    """The Object Info node's Random of object ``name``, or of depsgraph instance ``inst``
    when it is an instance (its random_id), in [0, 1], as Cycles gives it (a hash of the
    name mixed by Bob Jenkins' final mix; EEVEE's differs from it by up to 0.015)."""
    if inst is not None and inst.is_instance:
        return (int(inst.random_id) & 0xFFFFFFFF) / float(0xFFFFFFFF)
    return _hash_int_2d(_hash_string(name), 0) / float(0xFFFFFFFF)


def link_set(collection):
    """The ``LinkSet`` of a light linking collection (None: no collection, so everything)."""
    if collection is None:
        return None
    include, exclude = set(), set()

    def walk(coll, state, depth):
        for entry, ob in zip(coll.collection_objects, coll.objects, strict=False):
            own = state or entry.light_linking.link_state
            (include if own == "INCLUDE" else exclude).add(ob.name_full)
        if depth < 64:
            for entry, child in zip(coll.collection_children, coll.children, strict=False):
                walk(child, state or entry.light_linking.link_state, depth + 1)

    walk(collection, None, 0)
    return LinkSet(frozenset(include), frozenset(exclude))


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
    offset_scale: float = 1.0  # and of the normal offset alone (shrinks with the samples when maps are jittered)
    size_x: float = 0.0  # area lights: the sides along the light's local X and Y
    size_y: float = 0.0
    shape: str = "SQUARE"  # area lights: SQUARE, RECTANGLE, DISK or ELLIPSE
    penumbra_scale: float = 1.0  # the light size PCSS sees, relative (1/sqrt(samples) when sampled)
    sampled: bool = False  # moves between samples: its shadow is PCSS of its per-sample size
    map_jitter: tuple = (0.0, 0.0)  # this sample's shift of its maps' texel grid, in texels
    jittered: bool = False  # its maps are shifted per sample (sampling.map_jitter) in this frame
    diffuse_factor: float = 1.0  # Light > Influence: how much it adds to diffuse and specular
    specular_factor: float = 1.0
    volume_factor: float = 1.0  # Light > Influence > Volume: how much it adds to media's scattering
    receivers: LinkSet | None = None  # light linking: what it lights (None: everything)
    blockers: LinkSet | None = None  # shadow linking: what casts its shadow (None: everything)
    name: str = ""  # the light object's name (what the SHADOW_MAPS debug view labels its maps with)
    lightgroup: str = ""  # Object > Shading > Light Group (its light group pass)
    motion_key: tuple = ()  # which light it is at another time of the shutter (``motion_key``)
    # A direction of the world's light (``frame/world/directions.py``): a sun whose ``color`` is
    # the world's radiance from it over its probability.
    world: bool = False

    @property
    def spot_axes(self):
        """(right, up, (scale_x, scale_y)): the light's unit X and Y axes and how much its
        object scale stretches a spot's cone along them (X and Y scale over Z scale, as in
        Blender's engines: a non-uniformly scaled spot lights an ellipse)."""
        m = np.asarray(self.matrix, np.float64)[:3, :3]
        lengths = np.linalg.norm(m, axis=0)
        if not (np.all(np.isfinite(lengths)) and lengths.min() > 1e-12 * max(lengths.max(), 1e-300)):
            return np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), (1.0, 1.0)
        scale = (float(lengths[0] / lengths[2]), float(lengths[1] / lengths[2]))
        return m[:, 0] / lengths[0], m[:, 1] / lengths[1], scale

    @property
    def cone_size(self):
        """The full angle of the round cone around a spot's (possibly elliptical) cone."""
        half = 0.5 * min(max(self.spot_size, 0.0), math.pi)
        if half >= 0.5 * math.pi - 1e-9:
            return 2.0 * half
        widest = max(self.spot_axes[2])
        return min(2.0 * math.atan(math.tan(half) * widest), math.pi)

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
        n = math.sqrt(float(d @ d))  # np.linalg.norm's value, without its dispatch
        return d / n if n > 0 and math.isfinite(n) else np.array([0.0, 0.0, -1.0])


@dataclass(frozen=True)
class Lens:
    """A camera's thin lens, Camera > Depth of Field as Cycles reads it: ``radius`` of the
    aperture in world units (focal length / (2 f-stop), the focal length in mm read as
    millimetres of a metre; 1 / (2 f-stop) for an orthographic camera), ``focus`` the distance
    along the view axis that stays sharp (Focus Distance, or the Focus Object's distance along
    it), ``blades`` (0: a disc; else a regular polygon of that many corners, at least 3) and
    their ``rotation``, and ``ratio``: the aperture's x is divided by it (anamorphic bokeh)."""

    radius: float
    focus: float
    blades: int = 0
    rotation: float = 0.0
    ratio: float = 1.0


@dataclass
class Camera:
    view: np.ndarray  # world -> view
    projection: np.ndarray
    is_ortho: bool = False
    lens: Lens | None = None  # depth of field (``frame/lens.py``); None: a pinhole

    @property
    def position(self):
        # Read many times a sample: inverted once per view (a copy, so a caller may change it).
        key = self.view.tobytes()
        memo = self.__dict__.get("_position")
        if memo is None or memo[0] != key:
            try:
                position = np.linalg.inv(self.view)[:3, 3]
            except np.linalg.LinAlgError:
                position = np.zeros(3)
            memo = self.__dict__["_position"] = (key, position)
        return memo[1].copy()

    @property
    def forward(self):
        f = -self.view[2, :3]
        n = math.sqrt(float(f @ f))
        return f / n if n > 0 else np.array([0.0, 0.0, -1.0])


@dataclass
class Snapshot:
    instances: list
    lights: list
    world_color: np.ndarray  # the world's mean radiance (and the background colour)
    geometry: dict  # key -> Geometry (shared with the cache)
    world: object = None  # materials.World: the world's light as spherical harmonics
    messages: tuple = ()  # what the scene uses that is not drawn (materials, world, objects)
    images_changed: frozenset = frozenset()  # images updated since the last snapshot
    # Cycles' light portals (area lights flagged Portal): where the world's light comes in,
    # as (matrix, size x, size y); they guide the world's directions and emit nothing.
    portals: tuple = ()
    # Plane Light Probes (``PlaneProbe``): planar reflections (``frame/features/planar.py``).
    planes: tuple = ()
    # Sphere Light Probes (``SphereProbe``): cube maps by the lit pass (``frame/features/cubes.py``).
    spheres: tuple = ()
    # Participating media (``volumes.Medium``): the world's Volume and meshes' interiors
    # (``frame/features/volumes.py``); empty with View Layer > Filter > Volumes off.
    media: tuple = ()


@dataclass(frozen=True)
class PlaneProbe:
    """A Plane Light Probe as EEVEE reads it: the object's ``matrix`` (its local XY square,
    -1..1, is the mirror; its local Z the plane's normal), ``influence_distance`` (how far from
    the plane a surface takes its reflection, world units), ``clip_start`` (Clipping Offset:
    what lies less than this above the plane, the mirror's own surface, is not reflected) and its object's ``name``."""

    matrix: np.ndarray
    influence_distance: float
    clip_start: float
    name: str = ""

    @property
    def normal(self):
        """The plane's unit normal (its local Z in world space); None where degenerate."""
        m = np.asarray(self.matrix, np.float64)
        z = m[:3, 2]
        n = np.linalg.norm(z)
        if not (np.isfinite(n) and n > 0.0) or not np.all(np.isfinite(m)):
            return None
        return z / n

    @property
    def point(self):
        return np.asarray(self.matrix, np.float64)[:3, 3].copy()

    @property
    def corners(self):
        """The mirror's four corners (4, 3) in world space."""
        m = np.asarray(self.matrix, np.float64)
        local = np.array([[-1, -1, 0, 1], [1, -1, 0, 1], [1, 1, 0, 1], [-1, 1, 0, 1]], np.float64)
        return (local @ m.T)[:, :3]


@dataclass(frozen=True)
class SphereProbe:
    """A Sphere Light Probe as EEVEE reads it: the object's ``matrix`` (its origin is where the
    cube map is captured), its influence (``box``: a box, else a sphere, of ``influence_distance``
    in the object's local units, fading over ``falloff`` of it), ``clip_start`` and
    ``clip_end`` (the capture's clip range) and its object's ``name``."""

    matrix: np.ndarray
    influence_distance: float
    falloff: float
    clip_start: float
    clip_end: float
    box: bool = False
    name: str = ""

    @property
    def position(self):
        return np.asarray(self.matrix, np.float64)[:3, 3].copy()

    @property
    def radius(self):
        """The influence's largest reach from its centre in world units."""
        scale = np.linalg.norm(np.asarray(self.matrix, np.float64)[:3, :3], axis=0)
        r = float(self.influence_distance * scale.max() * (np.sqrt(3.0) if self.box else 1.0))
        return r if np.isfinite(r) else 0.0


# Light Probes Penumbra does not use, by type: what the report says once.
_PROBES_NOT_USED = {
    "VOLUME": "Volume Light Probe '{}' is not used: Penumbra bakes no indirect light",
    "GRID": "Volume Light Probe '{}' is not used: Penumbra bakes no indirect light",
}


def sphere_probe(ob, matrix):
    """The ``SphereProbe`` of Sphere Light Probe object ``ob`` at ``matrix``, or a message."""
    data = ob.data
    if not np.all(np.isfinite(matrix)):
        return f"Sphere Light Probe '{ob.name}' has a non-finite matrix: not used"
    near = max(float(getattr(data, "clip_start", 0.1)), 1e-6)
    far = max(float(getattr(data, "clip_end", 40.0)), near * 2.0)
    return SphereProbe(
        matrix,
        max(float(getattr(data, "influence_distance", 2.5)), 0.0),
        min(max(float(getattr(data, "falloff", 0.2)), 0.0), 1.0),
        near,
        far,
        str(getattr(data, "influence_type", "ELIPSOID")) == "BOX",
        ob.name,
    )


def plane_probe(ob, matrix):
    """The ``PlaneProbe`` of Light Probe object ``ob`` (evaluated) at ``matrix`` (4x4 numpy),
    a Sphere probe's ``SphereProbe``, or the message saying why it is not used (a Volume
    probe)."""
    data = ob.data
    kind = str(getattr(data, "type", ""))
    if kind in ("SPHERE", "CUBEMAP"):
        return sphere_probe(ob, matrix)
    if kind not in ("PLANE", "PLANAR"):
        return _PROBES_NOT_USED.get(kind, "Light Probe '{}' is not used").format(ob.name)
    if not np.all(np.isfinite(matrix)):
        return f"Plane Light Probe '{ob.name}' has a non-finite matrix: not used"
    distance = float(getattr(data, "influence_distance", 0.1))
    clip = float(getattr(data, "clip_start", 0.0))
    if getattr(data, "visibility_collection", None) is not None:
        return (
            f"Plane Light Probe '{ob.name}': its Visibility Collection is not honoured (it reflects every object)",
            PlaneProbe(matrix, max(distance, 0.0), max(clip, 0.0), ob.name),
        )
    return PlaneProbe(matrix, max(distance, 0.0), max(clip, 0.0), ob.name)


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
    exact_depth_rows(proj, cam_ob.data.clip_start, cam_ob.data.clip_end, ortho)
    if shift_x is not None and shift_x != cam_ob.data.shift_x:
        delta = (shift_x - cam_ob.data.shift_x) * shift_scale(
            cam_ob.data.sensor_fit, width * aspect_x, height * aspect_y
        )
        if ortho:
            proj[0, 3] -= delta
        else:
            proj[0, 2] += delta
    # Blender's engines ignore the camera object's scale (a scaled rig must not scale the view,
    # the clip distances or the Depth pass): its axes are normalised, as Blender does.
    world = cam_ob.matrix_world if matrix_world is None else matrix_world
    if any(abs(world.col[i].xyz.length - 1.0) > 1e-6 for i in range(3)):  # unscaled: as it is, to the bit
        world = world.normalized()
    view = matrix_np(world.inverted_safe())
    return Camera(view=view, projection=proj, is_ortho=ortho, lens=camera_lens(cam_ob, view))


# The nearest focus a lens takes (world units): a Focus Distance of 0 would put every depth
# infinitely out of focus.
MIN_FOCUS = 1e-6


def camera_lens(cam_ob, view):
    """The thin lens (``Lens``) of camera object ``cam_ob`` (evaluated) whose world -> view
    matrix is ``view``, or None: Depth of Field off, or a panoramic camera (not rendered)."""
    data = cam_ob.data
    dof = data.dof
    if not dof.use_dof or data.type == "PANO":
        return None
    fstop = max(float(dof.aperture_fstop), 1e-5)
    radius = 1.0 / (2.0 * fstop) if data.type == "ORTHO" else float(data.lens) * 1e-3 / (2.0 * fstop)
    focus = float(dof.focus_distance)
    target = dof.focus_object
    if target is not None:
        point = np.array(target.matrix_world.translation, np.float64)
        bone = target.pose.bones.get(dof.focus_subtarget) if target.pose and dof.focus_subtarget else None
        if bone is not None:
            point = np.array((target.matrix_world @ bone.matrix).translation, np.float64)
        focus = abs(float((view[:3, :3] @ point + view[:3, 3])[2]))  # its distance along the view axis
    blades = int(dof.aperture_blades)
    return Lens(
        radius=radius,
        focus=max(focus, MIN_FOCUS) if np.isfinite(focus) else 1e30,
        blades=blades if blades >= 3 else 0,
        rotation=float(dof.aperture_rotation),
        ratio=max(float(dof.aperture_ratio), 1e-6),
    )


def exact_depth_rows(proj, near, far, ortho):
    """Put back the depth terms of ``proj`` (Blender's float32 camera matrix) in float64 from
    the clip distances, when they are the same numbers rounded: at a near/far ratio beyond
    about 1e7 float32 rounds a perspective matrix's -(f + n) / (f - n) to -1 and the far plane
    is lost, though the GPU still draws with it. Changes ``proj`` in place."""
    near, far = float(near), float(far)
    if not (far > near and (ortho or near > 0.0)):
        return
    if ortho:
        exact = (-2.0 / (far - near), -(far + near) / (far - near))
    else:
        exact = (-(far + near) / (far - near), -2.0 * far * near / (far - near))
    given = (proj[2, 2], proj[2, 3])
    if all(abs(np.float32(e) - np.float32(g)) <= 2.0 * abs(np.spacing(np.float32(e))) for e, g in zip(exact, given)):
        proj[2, 2], proj[2, 3] = exact


def shift_scale(sensor_fit, width, height):
    """How far (in NDC x) a camera shift of 1 moves the frame: Blender measures shift in units
    of the fitted sensor side (the larger image side for AUTO)."""
    side = {"HORIZONTAL": width, "VERTICAL": height}.get(sensor_fit, max(width, height))
    return 2.0 * side / width


def camera_from_view(view_matrix, window_matrix):
    """The viewport's camera from a RegionView3D's ``view_matrix`` and ``window_matrix``."""
    proj = matrix_np(window_matrix)
    return Camera(view=matrix_np(view_matrix), projection=proj, is_ortho=abs(proj[3, 3] - 1.0) < 1e-9)


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


def geometry_from_mesh(mesh, needs=None):
    """A Blender mesh as an indexed triangle buffer (``Geometry``), read with ``foreach_get``
    from Blender's own arrays (the attribute API): positions, corner vertices, each triangle's
    corners and face, the faces' material indices, and normals on points (smooth meshes) or
    corners (``Mesh.normals_domain``).

    ``needs`` (``Needs``): also read a UV map, a colour attribute and MikkTSpace tangents
    (Blender's ``Mesh.calc_tangents``); vertices are then face corners, where those live.

    Triangles with a non-finite vertex are dropped (NaN/Inf positions must not reach the GPU).
    """
    mesh.calc_loop_triangles()
    n = len(mesh.loop_triangles)
    if n == 0:
        empty = np.zeros((0, 3), np.float32)
        return Geometry(empty, empty, np.zeros((0, 3), np.int32), [], np.full((2, 3), np.nan))
    nv, nc = len(mesh.vertices), len(mesh.loops)
    co, corner_vert = _positions_and_corners(mesh)
    corners = _read(mesh.loop_triangles, "loops", n, np.int32, 3)
    face_material = _attribute(mesh, "material_index", "value", len(mesh.polygons), np.int32)
    if face_material is None:
        mat = np.zeros(n, np.int32)  # no attribute: every face uses the first slot
    else:
        mat = face_material[_read(mesh.loop_triangle_polygons, "value", n, np.int32)]
    extras = needs is not None and needs.any
    if mesh.normals_domain == "POINT" and not extras:  # smooth throughout: one vertex per mesh vertex
        positions = co
        normals = _read(mesh.vertex_normals, "vector", nv, np.float32, 3)
        tris = corner_vert[corners]
        tris_are_vertices = True
    else:  # flat or mixed: one vertex per face corner
        positions = co[corner_vert]
        if mesh.normals_domain == "POINT":
            normals = _read(mesh.vertex_normals, "vector", nv, np.float32, 3)[corner_vert]
        else:
            normals = _read(mesh.corner_normals, "vector", nc, np.float32, 3)
        tris = corners
        tris_are_vertices = False
    uvs = colors = tangents = None
    messages = []
    if extras:
        uvs, tangents = _corner_uvs(mesh, needs, nc, messages, positions, normals)
        if needs.color_attribute is not None:
            colors = _corner_colors(mesh, needs.color_attribute, corner_vert, nc, messages)
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
    # Closedness is a property of the surface: test it on mesh vertices, not face corners.
    closed = not dropped and _closed_cached(tris if tris_are_vertices else corner_vert[tris], co)
    return Geometry(
        np.ascontiguousarray(positions, np.float32),
        np.ascontiguousarray(normals, np.float32),
        np.ascontiguousarray(tris, np.int32),
        ranges,
        bounds.astype(np.float64),
        uvs=uvs,
        colors=colors,
        tangents=tangents,
        closed=closed,
        smooth=mesh.normals_domain != "FACE",
        messages=tuple(messages),
    )


def _positions_and_corners(mesh):
    """A mesh's vertex positions (nv, 3) and each face corner's vertex (nc,), from Blender's
    attribute arrays where it has them."""
    nv, nc = len(mesh.vertices), len(mesh.loops)
    co = _attribute(mesh, "position", "vector", nv, np.float32, 3)
    if co is None:
        co = _read(mesh.vertices, "co", nv, np.float32, 3)
    corner_vert = _attribute(mesh, ".corner_vert", "value", nc, np.int32)
    if corner_vert is None:
        corner_vert = _read(mesh.loops, "vertex_index", nc, np.int32)
    return co, corner_vert


def mesh_content_key(mesh, needs=None):
    """A digest of all that ``geometry_from_mesh(mesh, needs)`` reads: positions, the corners'
    vertices, the faces' first corners and material indices, the normals it takes (on points
    or corners), the UV map and colour attribute ``needs`` asks for, and the mesh's name (its
    messages name it). Reading these costs a small part of an extraction (no triangulation,
    no tangents, no re-indexing): final renders find the geometry in the store by it."""
    nv, nc, nf = len(mesh.vertices), len(mesh.loops), len(mesh.polygons)
    co, corner_vert = _positions_and_corners(mesh)
    loop_start = _read(mesh.polygons, "loop_start", nf, np.int32) if nf else np.zeros(0, np.int32)
    material = _attribute(mesh, "material_index", "value", nf, np.int32)
    if mesh.normals_domain == "POINT":
        normals = _read(mesh.vertex_normals, "vector", nv, np.float32, 3)
    else:
        normals = _read(mesh.corner_normals, "vector", nc, np.float32, 3)
    arrays = [co, corner_vert, loop_start, np.zeros(0, np.int32) if material is None else material, normals]
    header = [mesh.name, mesh.normals_domain, needs]
    if needs is not None and needs.uv_map is not None:
        layers = mesh.uv_layers
        layer = layers.get(needs.uv_map) if needs.uv_map else next((u for u in layers if u.active_render), None)
        header.append(None if layer is None else layer.name)
        if layer is not None:
            arrays.append(_read(layer.uv, "vector", nc, np.float32, 2))
    if needs is not None and needs.color_attribute is not None:
        attrs, name = mesh.color_attributes, needs.color_attribute
        attr = attrs.get(name) if name else None
        if attr is None and not name and 0 <= attrs.render_color_index < len(attrs):
            attr = attrs[attrs.render_color_index]
        header.append(None if attr is None else (attr.name, attr.domain))
        if attr is not None and attr.domain in {"POINT", "CORNER"}:
            arrays.append(_read(attr.data, "color", nv if attr.domain == "POINT" else nc, np.float32, 4))
    return content_key(np.frombuffer(repr(header).encode(), np.uint8), *arrays)


_CLOSED = Kind("closed")  # content digest of (triangles, positions) -> closed_outward


def _closed_cached(tris, co):
    """``closed_outward``, remembered by content: its test costs about an extraction's time on
    a large closed mesh, while hashing the arrays costs a few percent of it."""
    key = content_key(np.asarray(tris, np.int32), np.asarray(co, np.float32))
    closed = _CLOSED.get(key)
    if closed is None:
        closed = _CLOSED.put(key, closed_outward(tris, co), 64)
    return closed


def closed_outward(tris, co):
    """Whether triangles ``tris`` (indices into positions ``co``) bound solids seen from outside:
    the directed edges are exactly their own reverses, as a multiset (a closed, consistently
    oriented surface; an edge may join more than two faces if they pair up), and each connected
    piece encloses a positive volume (its normals point outward).

    Seen from a point outside the surface's bounds, every back face of such a surface lies
    behind one of its front faces (a ray from outside meets a face it leaves through only
    after one it enters through), so back faces can be skipped without changing the image.
    Open meshes, unwelded seams, flipped or inconsistent normals and inward pieces (cavities
    modelled as inner shells) all give False: they are drawn whole."""
    if len(tris) < 4:
        return False
    t = np.asarray(tris, np.int64)
    count = int(t.max()) + 1
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    # Multiset equality of the directed edges and their reverses, by two random per-vertex
    # hashes: sum H(from) G(to) over the edges equals the sum over the reversed edges (exact
    # wrapping integer arithmetic; unequal multisets agree with probability about 2^-64).
    rng = np.random.default_rng(0x5EED)
    h, g = rng.integers(0, 2**64 - 1, size=(2, count), dtype=np.uint64, endpoint=True)
    with np.errstate(over="ignore"):
        ha, hb, hc, ga, gb, gc = h[a], h[b], h[c], g[a], g[b], g[c]
        forward = np.sum(ha * gb + hb * gc + hc * ga, dtype=np.uint64)
        backward = np.sum(hb * ga + hc * gb + ha * gc, dtype=np.uint64)
    if forward != backward:
        return False
    labels = _components(np.concatenate([a, b]), np.concatenate([b, c]), count)
    if labels is None:
        return False
    p = np.asarray(co, np.float64)[:count]
    p = p - (p.min(axis=0) + p.max(axis=0)) / 2.0  # near the origin: the volume sum keeps its digits
    pa, pb, pc = p[a], p[b], p[c]
    volume = np.einsum("ij,ij->i", pa, np.cross(pb, pc))
    piece = labels[a]
    total = np.bincount(piece, weights=volume, minlength=count)
    size = np.bincount(piece, weights=np.abs(volume), minlength=count)
    used = size > 0.0
    return bool(used.any() and np.all(total[used] > 1e-6 * size[used]))


def _components(u, v, count, rounds=64):
    """Connected-component label (its smallest vertex) of every vertex of the graph with edges
    (u, v): hooking roots onto smaller roots, then pointer jumping. None if it has not settled
    after ``rounds`` hooking rounds (the caller then assumes nothing)."""
    parent = np.arange(count)
    for _ in range(rounds):
        pu, pv = parent[u], parent[v]
        lo, hi = np.minimum(pu, pv), np.maximum(pu, pv)
        moved = lo < hi
        if not moved.any():
            return parent
        np.minimum.at(parent, hi[moved], lo[moved])
        while True:
            jumped = parent[parent]
            if np.array_equal(jumped, parent):
                break
            parent = jumped
    return None


def _corner_uvs(mesh, needs, nc, messages, positions=None, normals=None):
    """(uvs, tangents) per face corner for ``needs.uv_map`` ("" = the active render map);
    zeros (and a message) when the mesh has no such map. With the corners' ``positions`` and
    ``normals`` the tangents are remembered by content (``_tangents_cached``)."""
    if needs.uv_map is None:
        return None, None
    layers = mesh.uv_layers
    layer = layers.get(needs.uv_map) if needs.uv_map else next((u for u in layers if u.active_render), None)
    if layer is None:
        want = f"UV map '{needs.uv_map}'" if needs.uv_map else "UV map"
        if not needs.uv_pass_only:  # (the UV pass holds (0, 0) there, as Cycles')
            messages.append(f"mesh '{mesh.name}' has no {want}: its textures read UV (0, 0)")
        zeros = np.zeros((nc, 2), np.float32)
        return zeros, (np.zeros((nc, 4), np.float32) if needs.tangents else None)
    uvs = _read(layer.uv, "vector", nc, np.float32, 2)
    tangents = None
    if needs.tangents:
        if positions is not None and normals is not None and len(positions) == nc and len(normals) == nc:
            tangents = _tangents_cached(mesh, layer, uvs, positions, normals, nc, messages)
        else:
            tangents = _tangents(mesh, layer, nc, messages)
    if not np.isfinite(uvs).all():
        uvs = np.where(np.isfinite(uvs), uvs, 0.0).astype(np.float32)
    return uvs, tangents


NGON_TANGENTS = "mesh '{name}': tangents from UV derivatives (it has n-gons)"


def _tangents(mesh, layer, nc, messages):
    """MikkTSpace tangents and signs (nc, 4) of UV map ``layer`` (Blender's ``calc_tangents``);
    w 0 where the mesh has n-gons, with a message."""
    tangents = np.zeros((nc, 4), np.float32)
    try:
        mesh.calc_tangents(uvmap=layer.name)
    except RuntimeError:
        # N-gons: MikkTSpace needs triangles and quads; the shader then derives the tangent
        # frame from screen-space derivatives of the UVs (w = 0).
        messages.append(NGON_TANGENTS.format(name=mesh.name))
    else:
        tangents[:, :3] = _read(mesh.loops, "tangent", nc, np.float32, 3)
        tangents[:, 3] = _read(mesh.loops, "bitangent_sign", nc, np.float32)
        mesh.free_tangents()
    return tangents


_TANGENTS = Kind("tangents")  # content digest -> (tangents, n-gons): final renders extract anew


def _tangents_cached(mesh, layer, uvs, positions, normals, nc, messages):
    """``_tangents``, remembered by the content of what MikkTSpace reads: the corners'
    positions, normals and UVs and the faces' first corners (which corners make a face). Every
    F12 render is a new engine that extracts anew, and ``calc_tangents`` took 5.8 ms of a
    32k-corner mesh's render, hashing its inputs 0.7 ms."""
    faces = len(mesh.polygons)
    loop_start = _read(mesh.polygons, "loop_start", faces, np.int32) if faces else np.zeros(0, np.int32)
    key = content_key(positions, normals, uvs, loop_start)
    got = _TANGENTS.get(key)
    if got is None:
        said = []
        got = _TANGENTS.put(key, (_tangents(mesh, layer, nc, said), bool(said)), nc * 16)
        messages.extend(said)
    elif got[1]:
        messages.append(NGON_TANGENTS.format(name=mesh.name))
    return got[0].copy()


def _corner_colors(mesh, name, corner_vert, nc, messages):
    """Linear RGBA per face corner of colour attribute ``name`` ("" = the active render one);
    white (and a message) when it is missing."""
    attrs = mesh.color_attributes
    attr = attrs.get(name) if name else None
    if attr is None and not name:
        index = attrs.render_color_index
        attr = attrs[index] if 0 <= index < len(attrs) else None
    if attr is None or attr.domain not in {"POINT", "CORNER"}:
        want = f"colour attribute '{name}'" if name else "colour attribute"
        messages.append(f"mesh '{mesh.name}' has no {want} on points or corners: white is used")
        return np.ones((nc, 4), np.float32)
    count = len(mesh.vertices) if attr.domain == "POINT" else nc
    values = _read(attr.data, "color", count, np.float32, 4)
    return np.ascontiguousarray(values[corner_vert] if attr.domain == "POINT" else values)


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


def _topmost(ob):
    """An object's topmost parent (itself without one): its Cryptomatte asset."""
    seen = 0
    while ob.parent is not None and seen < 1000:
        ob, seen = ob.parent, seen + 1
    return ob


def _has_shape_keys(ob):
    data = ob.data
    return getattr(data, "shape_keys", None) is not None


@dataclass(frozen=True)
class _Object:
    """One drawn instance as ``SceneCache.snapshot`` reads it: the depsgraph instance, its
    evaluated object and original, its world matrix and whether the camera and shadows see it."""

    inst: object
    ob: object
    orig: object
    matrix: np.ndarray
    camera: bool
    shadow: bool


class _Reading:
    """What one ``SceneCache.snapshot`` gathers (instances, lights, portals, messages, the
    geometry keys still used) and the per-object values it reads once per snapshot."""

    def __init__(self, depsgraph):
        self.depsgraph = depsgraph
        self.render = depsgraph.mode == "RENDER"
        # Render > Curves > Shape: Strand (a pixel wide) or Strip (the strands' radius; Cylinder too).
        hair_type = getattr(depsgraph.scene.render, "hair_type", "STRIP")
        self.strip_mode = "STRAND" if hair_type == "STRAND" else "STRIP"
        self.instances, self.lights, self.portals, self.messages = [], [], [], []
        self.planes, self.spheres = [], []
        self.used = set()
        # The view layer's Override > Material and Filter > Surfaces and Curves.
        layer = depsgraph.view_layer
        self.material_override = getattr(layer, "material_override", None)
        self.surfaces = bool(getattr(layer, "use_solid", True))
        self.volumes = bool(getattr(layer, "use_volumes", True))
        self.media = []
        self.curves = bool(getattr(layer, "use_strand", True))
        self._own, self._held, self._sets, self._terminators = {}, {}, {}, {}

    def probe(self, inst):
        """A Light Probe: a Plane probe's ``PlaneProbe``, a Sphere probe's ``SphereProbe``;
        the others named once."""
        read = plane_probe(inst.object, matrix_np(inst.matrix_world))
        if isinstance(read, tuple):
            self.messages.append(read[0])
            read = read[1]
        if isinstance(read, str):
            self.messages.append(read)
        elif isinstance(read, SphereProbe):
            self.spheres.append(read)
        else:
            self.planes.append(read)

    def own_data(self, orig):
        """Pointer of ``orig``'s own evaluated geometry (cached for this snapshot)."""
        key = orig.name_full
        if key not in self._own:
            data = orig.evaluated_get(self.depsgraph).data
            self._own[key] = data.as_pointer() if data is not None else 0
        return self._own[key]

    def linked(self, collection):
        """A light linking collection's ``LinkSet``, read once per snapshot."""
        if collection is None:
            return None
        key = collection.original.name_full if collection.original is not None else collection.name_full
        if key not in self._sets:
            self._sets[key] = link_set(collection.original or collection)
        return self._sets[key]

    def holdout(self, orig, inst):
        """Object > Visibility > Holdout, or a collection set to Holdout in this view layer
        (an instance takes its instancer's, as Blender's engines do)."""
        base = inst.parent.original if inst.is_instance and inst.parent is not None else orig
        key = base.name_full
        if key not in self._held:
            self._held[key] = bool(base.holdout_get(view_layer=self.depsgraph.view_layer))
        return self._held[key] or bool(getattr(orig, "is_holdout", False))

    def terminator(self, ob):
        """Object > Shading > Shadow Terminator of ``ob`` (the instanced object's own, as
        Cycles reads it), read once per object and snapshot."""
        key = ob.name_full
        if key not in self._terminators:
            self._terminators[key] = Terminator.of(ob)
        return self._terminators[key]

    def light(self, inst):
        """A light instance: a portal, or a light (with its links)."""
        ob = inst.object
        if is_portal(ob.data):
            size_x = float(ob.data.size)
            size_y = float(ob.data.size_y) if ob.data.shape in {"RECTANGLE", "ELLIPSE"} else size_x
            self.portals.append((matrix_np(inst.matrix_world), size_x, size_y))
            return
        if ob.data.type == "AREA" and float(getattr(ob.data, "spread", math.pi)) < math.pi - 1e-6:
            self.messages.append(f"area light '{ob.name}': Spread is not rendered (it emits over the whole half-space)")
        light = light_from_blender(ob.data, matrix_np(inst.matrix_world))
        if light is not None:
            light.name = ob.name
            light.lightgroup = str(getattr(ob, "lightgroup", "") or "")
            light.motion_key = motion_key(inst)
            linking = getattr(ob, "light_linking", None)
            if linking is not None:
                light.receivers = self.linked(linking.receiver_collection)
                light.blockers = self.linked(linking.blocker_collection)
            self.lights.append(light)

    def add(self, obj, key, geo, materials, strip=None):
        """The instance of ``geo`` (kept under ``key``) drawn for ``obj`` with ``materials``;
        ``strip``: hair strips' shape (Render > Curves > Shape), None for a surface."""
        inst, ob, orig = obj.inst, obj.ob, obj.orig
        self.used.add(key)
        self.messages.extend(geo.messages)
        for mat in materials:
            if mat is not None:
                self.messages.extend(mat.messages)
        if strip is not None and obj.shadow and any(m is not None and m.uses_alpha for m in materials):
            self.messages.append(
                f"hair of '{ob.name}': its material's alpha is not drawn in shadows (strands cast solid)"
            )
        self.instances.append(
            MeshInstance(
                key=key,
                matrix=obj.matrix,
                materials=materials,
                shadow=obj.shadow,
                camera=obj.camera,
                holdout=self.holdout(orig, inst),
                terminator=self.terminator(ob) if strip is None else Terminator(),
                color=tuple(float(c) for c in orig.color),
                random=object_random(orig.name, inst),
                names=(orig.name_full, inst.parent.original.name_full)
                if inst.is_instance and inst.parent is not None
                else (orig.name_full,),
                hair=strip,
                motion_key=motion_key(inst),
                pass_index=int(getattr(orig, "pass_index", 0)),
                crypto_names=(orig.name, _topmost(orig).name),
                lightgroup=str(getattr(orig, "lightgroup", "") or ""),
            )
        )


class SceneCache:
    """Geometry cache of one engine instance, keyed by datablock, invalidated by updates."""

    def __init__(self):
        self.geometry = {}
        self.built = 0  # geometries extracted since creation (tests and stats read it)
        self.materials = {}  # material name -> Material, until an update changes it
        self.uv_pass = False  # every mesh reads its active render UV map (the UV pass)
        self.materials_read = 0
        self.images_changed = set()  # image names updated since the renderer last looked
        self.world = None  # (world name, materials.World) until a world or image update
        self.store = None  # ``store.Store`` of final renders: meshes found there by content
        self.extracted = 0  # meshes extracted (not found in the store) since creation

    def apply_updates(self, depsgraph):
        """Drop the geometry of every datablock whose geometry the depsgraph says changed, and
        the material read of every material (or, for a node group, every material) that
        changed; note changed images (their GPU textures are re-uploaded) and worlds."""
        changed = set()
        for update in depsgraph.updates:
            id_orig = update.id.original if update.id.original is not None else update.id
            kind = getattr(id_orig, "id_type", "")
            if kind == "MATERIAL":
                self.materials.pop(id_orig.name_full, None)
            elif kind == "NODETREE" and not getattr(id_orig, "is_embedded_data", False):
                self.materials.clear()  # a node group may feed any material (a material's own
                # tree is embedded data: its material is updated too)
            elif kind == "IMAGE":
                self.images_changed.add(id_orig.name_full)
                self.world = None  # an environment image may have changed
            elif kind in {"WORLD", "SCENE"}:
                self.world = None
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
        self.world = None

    def _world(self, scene, override=None):
        """The world's light: the scene's, or the view layer's World Override."""
        world = override if override is not None else scene.world
        name = world.name_full if world is not None else ""
        if self.world is None or self.world[0] != name:
            self.world = (name, world_from_blender(scene, world))
        return self.world[1]

    def _geometry_for(self, inst, ob, key, deps, needs):
        geo = self.geometry.get(key)
        if geo is not None:
            return geo
        if ob.type == "MESH":
            geo = self._extract(ob.data, needs)
        else:
            mesh = ob.to_mesh()
            try:
                geo = self._extract(mesh, needs) if mesh is not None else None
            finally:
                ob.to_mesh_clear()
            if geo is None:
                return None
        geo.deps = deps
        self.geometry[key] = geo
        self.built += 1
        geo.serial = self.built
        return geo

    def _extract(self, mesh, needs):
        """``geometry_from_mesh``, or with a ``store`` (final renders) the geometry it holds
        for the same content (a copy of its record sharing the arrays: ``deps`` and
        ``serial`` are this cache's)."""
        if self.store is None:
            self.extracted += 1
            return geometry_from_mesh(mesh, needs)
        content = mesh_content_key(mesh, needs)
        kept = self.store.get("geometry", content)
        if kept is None:
            kept = geometry_from_mesh(mesh, needs)
            kept.content = content
            self.store.put("geometry", content, kept, kept.nbytes)
            self.extracted += 1
        return dataclasses.replace(kept)

    def _strips_for(self, key, deps, build):
        """The hair strips kept under ``key``, built by ``build()`` on first use."""
        geo = self.geometry.get(key)
        if geo is None:
            geo = build()
            geo.deps = deps
            self.geometry[key] = geo
            self.built += 1
            geo.serial = self.built
        return geo

    def snapshot(self, depsgraph):
        """The scene as the renderer draws it: its instances, lights, portals and world, and
        what it cannot draw (``messages``). Geometry and materials come from the cache where
        unchanged; geometry no longer in the scene is forgotten."""
        scene = depsgraph.scene
        reading = _Reading(depsgraph)
        for inst in depsgraph.object_instances:
            if inst.object.type == "LIGHT":
                reading.light(inst)
            elif inst.object.type == "LIGHT_PROBE":
                reading.probe(inst)
            else:
                self._read_object(reading, inst)
        messages = reading.messages
        if any(i.hair for i in reading.instances) and int(getattr(scene.render, "hair_subdiv", 0)) > 0:
            messages.append("Render > Curves > Additional Subdivision is not drawn (strands keep their own points)")
        # Forget geometry no longer in the scene so its GPU buffers are freed.
        for key in [k for k in self.geometry if k not in reading.used]:
            del self.geometry[key]
        world = self._world(scene, getattr(depsgraph.view_layer, "world_override", None))
        messages += world.messages
        media = list(reading.media)
        if world.volume is not None and reading.volumes:
            media.insert(0, world.volume)
        return Snapshot(
            instances=reading.instances,
            lights=reading.lights,
            world_color=world.mean,
            geometry=self.geometry,
            world=world,
            messages=tuple(f"Penumbra: {m}" for m in dict.fromkeys(messages)),
            images_changed=frozenset(self._take_images_changed()),
            portals=tuple(reading.portals),
            planes=tuple(reading.planes),
            spheres=tuple(reading.spheres),
            media=tuple(media),
        )

    def _read_object(self, reading, inst):
        """A non-light instance: its hair (curves, particle systems) and its surface, where
        drawn and seen by the camera or shadows."""
        ob = inst.object
        if ob.type in _NOT_DRAWN:
            why = ": its OpenVDB grids are not read (a mesh's Volume material is drawn)" if ob.type == "VOLUME" else ""
            reading.messages.append(f"{_NOT_DRAWN[ob.type]} '{ob.name}' is not drawn{why}")
            return
        if ob.type not in GEOMETRY_TYPES and ob.type != "CURVES":
            return
        systems = hair.particle_hair(ob, reading.render) if ob.type in GEOMETRY_TYPES else []
        if ob.type != "CURVES" and not systems and not inst.is_instance and not inst.show_self:
            return  # a particle emitter with Show Emitter off for this render
        matrix = matrix_np(inst.matrix_world)
        if not np.all(np.isfinite(matrix)):
            print(f"Penumbra: object '{ob.name}' has a non-finite matrix; skipped", file=sys.stderr)
            return
        orig = ob.original if ob.original is not None else ob
        camera, shadow = bool(orig.visible_camera), bool(orig.visible_shadow)
        if not (camera or shadow):
            return
        if getattr(orig, "is_shadow_catcher", False):
            reading.messages.append(f"object '{ob.name}': Shadow Catcher is Cycles-only (drawn as an ordinary object)")
        obj = _Object(inst, ob, orig, matrix, camera, shadow)
        slots = [self._material(slot.material) for slot in ob.material_slots]
        if reading.material_override is not None:  # View Layer > Override > Material: every slot's
            slots = [self._material(reading.material_override)] * max(1, len(slots))
        if ob.type == "CURVES" or systems:
            if not reading.curves:  # View Layer > Filter > Curves off
                systems = []
                if ob.type == "CURVES":
                    return
        if ob.type == "CURVES":
            key, deps = _geometry_key(inst, ob, reading.own_data)
            geo = self._strips_for(key, deps, lambda ob=ob: hair.geometry_from_curves(ob.data))
            if geo.triangle_count:
                reading.add(obj, key, geo, slots, reading.strip_mode)
            return
        self._read_particle_hair(reading, obj, systems, slots)
        if not inst.is_instance and not inst.show_self:
            return  # a particle emitter with Show Emitter off for this render
        if any(m is not None and m.volume is not None for m in slots) and camera:
            self._read_medium(reading, obj, slots)
        if slots and all(m is not None and not m.surface for m in slots):
            return  # only a Volume output: the interior alone, no surface (as Cycles)
        if any(m is not None and not m.surface for m in slots):
            reading.messages.append(
                f"object '{ob.name}': a material with only a Volume output among its surfaces is drawn as black faces"
            )
        if reading.surfaces:  # View Layer > Filter > Surfaces
            self._read_surface(reading, obj, slots)

    def _read_medium(self, reading, obj, slots):
        """The medium of ``obj``'s first material with a Volume output, filling its bounding box
        (named where the mesh is not a box); View Layer > Filter > Volumes off: none."""
        ob = obj.ob
        if not reading.volumes:
            return
        mat = next(m for m in slots if m is not None and m.volume is not None)
        if sum(1 for m in slots if m is not None and m.volume is not None) > 1:
            reading.messages.append(f"object '{ob.name}': only its first material's Volume is drawn")
        matrix = volumes.box_matrix(obj.matrix, [tuple(c) for c in ob.bound_box])
        if matrix is None:
            reading.messages.append(f"object '{ob.name}': its volume is flat or empty and is not drawn")
            return
        if not (ob.type == "MESH" and volumes.is_box(ob.data)):
            reading.messages.append(f"object '{ob.name}': its volume fills its bounding box (the mesh is not a box)")
        reading.media.append(mat.volume.placed("BOX", matrix, ob.name))

    def _read_particle_hair(self, reading, obj, systems, slots):
        """The strips of the hair particle ``systems`` of ``obj``, each with its settings'
        material slot of ``slots``."""
        ob, orig = obj.ob, obj.orig
        for psys in systems:
            settings = psys.settings
            key = ("PS", orig.name_full, psys.name)
            deps = frozenset({orig.name_full, settings.original.name_full if settings.original else settings.name})
            geo = self._strips_for(
                key, deps, lambda ob=ob, psys=psys: hair.geometry_from_particles(ob, psys, reading.render)
            )
            index = int(settings.material) - 1  # the particle settings' material slot (1-based)
            mat = slots[index] if 0 <= index < len(slots) else None
            if geo.triangle_count:
                reading.add(obj, key, geo, [mat], reading.strip_mode)

    def _read_surface(self, reading, obj, materials):
        """The surface of ``obj`` (a mesh, or what another geometry type evaluates to) with
        the vertex data its ``materials`` read."""
        inst, ob = obj.inst, obj.ob
        needs, extra = Needs.of(materials, ob.data if ob.type == "MESH" else None)
        if self.uv_pass and needs.uv_map is None:  # the UV pass reads the active render map
            needs = dataclasses.replace(needs, uv_map="", uv_pass_only=True)
        if extra[0] or extra[1]:
            reading.messages.append(
                f"object '{ob.name}': its materials read several UV maps or colour attributes; only "
                f"{needs.uv_map or 'the active UV map'} / {needs.color_attribute or 'the active colour attribute'} "
                "is drawn"
            )
        key, deps = _geometry_key(inst, ob, reading.own_data)
        if needs.any:
            key = (*key, needs)
        geo = self._geometry_for(inst, ob, key, deps, needs)
        if geo is None or geo.triangle_count == 0:
            return
        reading.add(obj, key, geo, materials)

    def _take_images_changed(self):
        changed, self.images_changed = self.images_changed, set()
        return changed


def emitter_area(data, matrix):
    """The emitter's area as Blender's *Normalize* switch counts it (measured against Cycles):
    an area light's (with its object's X/Y scale; a disk or ellipse pi/4 of its box), a point
    or spot's sphere 4 pi r^2, a sun's pi sin^2(angle / 2); 1 for a point-like emitter."""
    kind = data.type
    if kind == "AREA":
        sx, sy = np.linalg.norm(np.asarray(matrix, np.float64)[:3, :2], axis=0)
        size_x = float(data.size)
        size_y = float(data.size_y) if data.shape in {"RECTANGLE", "ELLIPSE"} else size_x
        area = size_x * sx * size_y * sy * (math.pi / 4.0 if data.shape in {"DISK", "ELLIPSE"} else 1.0)
    elif kind == "SUN":
        area = math.pi * math.sin(0.5 * min(max(float(data.angle), 0.0), math.pi)) ** 2
    else:
        area = 4.0 * math.pi * float(getattr(data, "shadow_soft_size", 0.0)) ** 2
    return area if area > 0.0 and math.isfinite(area) else 1.0


def is_portal(data):
    """Whether light ``data`` is a Cycles light portal (an area light that only tells where the
    world's light enters: it emits nothing)."""
    return data.type == "AREA" and bool(getattr(getattr(data, "cycles", None), "is_portal", False))


def motion_key(inst):
    """An instance of ``depsgraph.object_instances`` as the same one at another time of the
    frame: its object, its instancer and its persistent id within it."""
    ob = inst.object
    orig = ob.original if ob.original is not None else ob
    if inst.is_instance and inst.parent is not None:
        parent = inst.parent.original if inst.parent.original is not None else inst.parent
        return (orig.name_full, parent.name_full, tuple(inst.persistent_id))
    return (orig.name_full,)


def motion_matrices(depsgraph):
    """{``motion_key``: world matrix} of every object instance at the depsgraph's time (what
    ``render_engine.read_motion`` reads at each step of the shutter)."""
    return {motion_key(inst): matrix_np(inst.matrix_world) for inst in depsgraph.object_instances}


def light_from_blender(data, matrix):
    color = np.array(data.color[:3], dtype=np.float64) * float(data.energy)
    if not getattr(data, "normalize", True):  # power per unit of emitter area: it grows with size
        color *= emitter_area(data, matrix)
    if getattr(data, "use_temperature", False):
        color *= np.array(data.temperature_color[:3], dtype=np.float64)  # Blender's blackbody colour
    color *= 2.0 ** float(getattr(data, "exposure", 0.0))
    if not np.all(np.isfinite(color)) or not np.all(np.isfinite(matrix)):
        return None
    radius = float(getattr(data, "shadow_soft_size", 0.0))
    if not getattr(data, "use_soft_falloff", True):
        radius = 0.0
    light = Light(type=data.type, color=color, matrix=matrix, radius=radius, use_shadow=bool(data.use_shadow))
    light.diffuse_factor = float(getattr(data, "diffuse_factor", 1.0))
    light.specular_factor = float(getattr(data, "specular_factor", 1.0))
    light.volume_factor = float(getattr(data, "volume_factor", 1.0))
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
