"""Scenes lit by the world (alone but for ``glossy_spheres``' sun), their Cycles references,
and the measurement the world-light bench and tests share::

    scene = world_scenes.build("window_room", 160, 90)
    ref = world_scenes.cycles_reference("window_room", samples=256, width=160, height=90)
    world_scenes.use_engine(scene, "PENUMBRA", render_samples=64, world_shadows=True)
    world_scenes.mae(world_scenes.render_display(scene), ref)

=================  =======================================================================
sky_outdoor        an 80 m grey ground with Suzanne, a cube, a torus lying flat and a
                   cylinder on it, diffuse-ish Principled materials (roughness 0.5-0.8),
                   a uniform sky (0.8, 0.85, 1.0) x 1; the camera 25 deg down, so contact
                   shadows, creases and the torus' hole show
sky_outdoor_hdri   the same under a procedural equirectangular sky (a horizon-to-zenith
                   gradient, a dim ground half and a sun blob 35 deg up), made in numpy and
                   read through an Environment Texture whose vector comes from a Mapping
                   node rotating it 70 deg about Z
glossy_spheres     five spheres of Principled roughness 0.15 to 0.5 (coloured, IOR 1.5) on a
                   grey ground under a dim uniform sky (0.6, 0.7, 0.9) x 0.3 and a sun 40 deg
                   up: the world's light is a small share, its glossy reflections of the
                   ground are blocked (where an estimator that subtracts went negative)
window_room_bare   ``window_room`` with no portal for Penumbra (Cycles keeps its own)
skylight_room      a closed 6 x 4 x 3 m room lit through a skylight and a doorway, a crate and
                   a pillar inside; no light portal for Penumbra (Cycles gets two)
window_room        a closed 4 x 5 x 2.8 m room of 0.2 m thick, overlapping boxes (no seam
                   lets light through) with one 1.6 x 1.4 m window in the +Y wall, a uniform
                   sky of strength 4 outside, a table and a sphere by the window; the camera
                   inside, looking at the lit floor patch, the window wall and the side wall
=================  =======================================================================

Every builder fills a scene made by ``devkit.scenes.empty_scene`` (view transform 'Standard',
look None, no dither) and returns it; ``build`` makes that scene. Nothing is random and
nothing is read from disk.

Errors are measured as the other image benches do (``bench assets``): the mean absolute
difference of display-referred RGB, 0..1 (scene-linear clipped to [0, 1], then the sRGB
transfer function of the 'Standard' view), over every pixel, the background included.

Cycles references (``cycles_reference``) render through the same pixel filter as Penumbra
(Blackman-Harris of Penumbra's Filter Size, ``reference_kit.matched_filter``), CPU, fixed
seed 1 (the compared Cycles renders use seed 0, so they share no samples with it), no
adaptive sampling, no denoiser, and in the room a light portal over the window (it only
guides Cycles' sampling of the sky: at 64 spp the room's noise fell from 0.083 to 0.007 MAE
between two seeds). ``bounces=0`` is Cycles with max_bounces 0: the world's
direct light with visibility, what Penumbra's world shadows converge to; ``bounces=1`` adds
one diffuse bounce (diffuse_bounces 1; glossy, transmission and transparent 0), what
``indirect_bounces = 1`` approximates. They are cached in ``out/reference_cache`` under a key
holding the scene, samples, size, bounces, Blender's major.minor and a digest of this file, so
a change here (or a missing file) renders them anew on the next call.
"""

import hashlib
import math
from pathlib import Path

import bpy
import numpy as np

from devkit import engines, scenes
from devkit import reference_kit as kit
from devkit.render import render

DEFAULT_WIDTH, DEFAULT_HEIGHT = 160, 90
CACHE = kit.DEFAULT_CACHE

SKY_COLOR = (0.8, 0.85, 1.0)
SKY_STRENGTH = 1.0
ROOM_SKY_STRENGTH = 4.0
HDRI_SIZE = (256, 128)
HDRI_ROTATION_Z = math.radians(70.0)
HDRI_SUN = (math.radians(35.0), math.radians(-60.0))  # elevation, atan2(y, x) in the image's frame
HDRI_SUN_RADIUS = math.radians(6.0)

# The room's inside: x in [-ROOM_X, ROOM_X], y in [-ROOM_Y, ROOM_Y], z in [0, ROOM_Z]; walls
# WALL thick; the window in the +Y wall spans x in [-WINDOW_X, WINDOW_X], z in WINDOW_Z.
ROOM_X, ROOM_Y, ROOM_Z = 2.0, 2.5, 2.8
WALL = 0.2
WINDOW_X, WINDOW_Z = 0.8, (0.7, 2.1)


# --- materials, world, meshes ---------------------------------------------------------------


def principled(name, color, roughness):
    """A Principled BSDF of ``color`` and ``roughness``, Blender's other defaults (specular 0.5,
    IOR 1.5 on 4.x/5.x)."""
    return scenes.material(name, color, roughness=roughness)


def uniform_sky(scene, color, strength):
    scenes.set_world(scene, color)
    bg = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    bg.inputs["Strength"].default_value = strength
    return scene.world


def hdri_pixels(width=HDRI_SIZE[0], height=HDRI_SIZE[1]):
    """Scene-linear RGBA (height, width, 4), row 0 at the bottom (Blender's pixel order), of an
    equirectangular sky: a gradient from a pale horizon to a deeper blue zenith, a dim brown
    lower half and a sun blob HDRI_SUN_RADIUS wide (peak 60) with a soft halo. Blender's
    equirectangular mapping: u = 0.5 - atan2(d.y, d.x) / (2 pi), v = 0.5 + atan2(d.z,
    hypot(d.x, d.y)) / pi."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    U, V = np.meshgrid(u, v)
    azimuth = (0.5 - U) * 2.0 * np.pi  # atan2(d.y, d.x)
    theta = (V - 0.5) * np.pi  # elevation
    d = np.stack([np.cos(theta) * np.cos(azimuth), np.cos(theta) * np.sin(azimuth), np.sin(theta)], -1)
    up = np.clip(np.sin(theta), 0.0, 1.0)[..., None]
    horizon, zenith = np.array([0.95, 0.95, 1.0]), np.array([0.25, 0.45, 1.0])
    sky = horizon * (1.0 - up) ** 2 + zenith * (1.0 - (1.0 - up) ** 2)
    ground = np.array([0.25, 0.2, 0.15])
    rgb = np.where(theta[..., None] >= 0.0, sky, ground)
    el, az = HDRI_SUN
    sun_dir = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    angle = np.arccos(np.clip(d @ sun_dir, -1.0, 1.0))
    rgb = rgb + np.array([1.0, 0.9, 0.75])[None, None] * (
        60.0 * np.exp(-0.5 * (angle / (0.5 * HDRI_SUN_RADIUS)) ** 2)[..., None]
        + 1.5 * np.exp(-angle / math.radians(15.0))[..., None]
    )
    rgba = np.ones((height, width, 4), np.float32)
    rgba[..., :3] = rgb
    return rgba


def hdri_sky(scene, strength=1.0):
    """The world of ``sky_outdoor_hdri``: Texture Coordinate (Generated) -> Mapping (Point,
    Z rotation HDRI_ROTATION_Z) -> Environment Texture (equirectangular, the numpy sky packed
    into the .blend as a float image) -> Background."""
    w, h = HDRI_SIZE
    image = bpy.data.images.new("penumbra_world_sky", w, h, alpha=True, float_buffer=True)
    # Colour space and format first: changing either regenerates a generated image's pixels.
    # Packed as OpenEXR, so the sun's values above 1 stay.
    image.colorspace_settings.name = _linear_colorspace(image)
    image.file_format = "OPEN_EXR"
    image.pixels.foreach_set(hdri_pixels(w, h).ravel())
    image.pack()
    world = environment_world(scene, image, strength, HDRI_ROTATION_Z)
    world.color = tuple(float(c) for c in hdri_pixels(w, h)[..., :3].reshape(-1, 3).mean(0))
    return world


def environment_world(scene, image, strength=1.0, rotation_z=None):
    """``scene``'s world lit by ``image``: Environment Texture (equirectangular) -> Background
    of ``strength``; with ``rotation_z``, Texture Coordinate (Generated) -> Mapping (Point, that
    Z rotation) -> the texture's Vector."""
    world = scene.world
    world.use_nodes = True
    tree = world.node_tree
    bg = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
    bg.inputs["Strength"].default_value = strength
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = image
    env.projection = "EQUIRECTANGULAR"
    if rotation_z is not None:
        mapping = tree.nodes.new("ShaderNodeMapping")
        mapping.vector_type = "POINT"
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, rotation_z)
        coords = tree.nodes.new("ShaderNodeTexCoord")
        tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
        tree.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    tree.links.new(env.outputs["Color"], bg.inputs["Color"])
    return world


def _linear_colorspace(image):
    """Scene-linear Rec.709 under whichever name this Blender line gives it."""
    names = {item.identifier for item in image.colorspace_settings.bl_rna.properties["name"].enum_items}
    for name in ("Linear Rec.709", "Linear"):
        if name in names:
            return name
    return image.colorspace_settings.name


def monkey(scene, name, location, height, rotation_z, mat):
    """Smooth Suzanne (bmesh's monkey, subdivided once: about 3,900 triangles) standing on
    the ground ``height`` tall, facing -Y turned by ``rotation_z``."""
    me = scenes.smooth_monkey_mesh(name)
    zs = np.array([v.co.z for v in me.vertices])
    scale = height / float(zs.max() - zs.min())
    ob = scenes.link(scene, bpy.data.objects.new(name, me))
    ob.scale = (scale,) * 3
    # Tilted back 10 deg as kit.suzanne stands; her chin then touches the ground.
    ob.rotation_euler = (math.radians(10.0), 0.0, rotation_z)
    ob.location = (location[0], location[1], 0.0)
    bpy.context.view_layer.update()
    lowest = min((ob.matrix_world @ v.co).z for v in me.vertices)
    ob.location.z = -lowest
    me.materials.append(mat)
    return ob


def torus(scene, name, center, major, minor, mat, segments=48, sides=16):
    """A smooth torus lying flat (axis +Z) centred at ``center``."""
    verts, faces = [], []
    for i in range(segments):
        a = 2.0 * math.pi * i / segments
        for j in range(sides):
            b = 2.0 * math.pi * j / sides
            r = major + minor * math.cos(b)
            verts.append((r * math.cos(a), r * math.sin(a), minor * math.sin(b)))
    for i in range(segments):
        for j in range(sides):
            i2, j2 = (i + 1) % segments, (j + 1) % sides
            faces.append((i * sides + j, i2 * sides + j, i2 * sides + j2, i * sides + j2))
    ob = scenes.mesh_object(scene, name, verts, faces, location=center, mat=mat)
    for poly in ob.data.polygons:
        poly.use_smooth = True
    return ob


def cylinder(scene, name, center, radius, height, mat, segments=32):
    """A capped cylinder standing on z = center.z - height / 2, smooth sides, flat caps."""
    verts = [(radius * math.cos(2 * math.pi * k / segments), radius * math.sin(2 * math.pi * k / segments), z)
             for z in (-height / 2, height / 2) for k in range(segments)]  # fmt: skip
    sides = [(k, (k + 1) % segments, segments + (k + 1) % segments, segments + k) for k in range(segments)]
    caps = [tuple(reversed(range(segments))), tuple(range(segments, 2 * segments))]
    ob = scenes.mesh_object(scene, name, verts, sides + caps, location=center, mat=mat)
    for poly in ob.data.polygons[: len(sides)]:
        poly.use_smooth = True
    return ob


# --- scenes ---------------------------------------------------------------------------------


def _outdoor_objects(scene):
    scenes.plane(scene, "Ground", size=80.0, mat=principled("Ground", (0.5, 0.5, 0.5), 0.8))
    monkey(scene, "Suzanne", (-0.2, 0.2), 1.0, math.radians(15.0), principled("Suzanne", (0.8, 0.45, 0.2), 0.6))
    cube = scenes.box(
        scene, "Cube", center=(-1.9, 0.9, 0.5), size=(1.0, 1.0, 1.0), mat=principled("Cube", (0.7, 0.7, 0.7), 0.7)
    )
    cube.rotation_euler = (0.0, 0.0, math.radians(25.0))
    torus(scene, "Torus", (1.6, -0.4, 0.15), 0.55, 0.15, principled("Torus", (0.2, 0.4, 0.75), 0.5))
    cylinder(scene, "Cylinder", (1.5, 1.6, 0.75), 0.35, 1.5, principled("Cylinder", (0.3, 0.65, 0.35), 0.7))
    cam = scenes.look_at(scene, (0.0, -5.6, 2.61), (0.0, 0.3, 0.0), lens=35.0)  # 25 deg down
    cam.data.clip_end = 200.0
    return scene


def sky_outdoor(scene):
    """Objects on an 80 m ground under a uniform bright sky (0.8, 0.85, 1.0) x 1."""
    uniform_sky(scene, SKY_COLOR, SKY_STRENGTH)
    return _outdoor_objects(scene)


def sky_outdoor_hdri(scene):
    """``sky_outdoor``'s objects under the rotated procedural HDRI (``hdri_sky``)."""
    hdri_sky(scene)
    return _outdoor_objects(scene)


GLOSSY_ROUGHNESS = (0.15, 0.2, 0.3, 0.4, 0.5)
GLOSSY_SKY = ((0.6, 0.7, 0.9), 0.3)


def glossy_spheres(scene):
    """Glossy spheres on a ground under a dim sky and a sun (see the module's table)."""
    uniform_sky(scene, *GLOSSY_SKY)
    scenes.plane(scene, "Ground", size=40.0, mat=principled("Ground", (0.5, 0.5, 0.5), 0.6))
    colours = ((0.2, 0.35, 0.8), (0.8, 0.25, 0.2), (0.85, 0.75, 0.3), (0.3, 0.7, 0.4), (0.7, 0.7, 0.7))
    for k, (rough, colour) in enumerate(zip(GLOSSY_ROUGHNESS, colours, strict=True)):
        x = (k - 2) * 1.15
        scenes.uv_sphere(
            scene, f"Sphere{k}", center=(x, 0.3 * (k % 2), 0.5), radius=0.5, mat=principled(f"Glossy{k}", colour, rough)
        )
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(50.0), 0.0, math.radians(30.0)), angle=0.02)
    cam = scenes.look_at(scene, (0.0, -6.0, 2.4), (0.0, 0.2, 0.4), lens=35.0)
    cam.data.clip_end = 100.0
    return scene


def _span_box(scene, name, lo, hi, mat):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return scenes.box(scene, name, center=tuple((lo + hi) / 2), size=tuple(hi - lo), mat=mat)


def window_room(scene):
    """A closed room lit only through one window by a uniform sky of strength 4 (see the
    module's table). Floor, ceiling and walls are boxes WALL thick that overlap at every edge
    and corner: floor and ceiling span the walls' outer faces, the side walls the full depth
    and height, the window wall's four pieces reach 5 cm into each other."""
    uniform_sky(scene, SKY_COLOR, ROOM_SKY_STRENGTH)
    X, Y, Z, t = ROOM_X, ROOM_Y, ROOM_Z, WALL
    walls = principled("Walls", (0.75, 0.75, 0.72), 0.8)
    floor = principled("Floor", (0.55, 0.45, 0.35), 0.6)
    _span_box(scene, "Floor", (-X - t, -Y - t, -t), (X + t, Y + t, 0.0), floor)
    _span_box(scene, "Ceiling", (-X - t, -Y - t, Z), (X + t, Y + t, Z + t), walls)
    _span_box(scene, "WallW", (-X - t, -Y - t, -t), (-X, Y + t, Z + t), walls)
    _span_box(scene, "WallE", (X, -Y - t, -t), (X + t, Y + t, Z + t), walls)
    _span_box(scene, "WallS", (-X - t, -Y - t, -t), (X + t, -Y, Z + t), walls)
    # The window wall (+Y): left and right of the opening full height, below and above it
    # reaching 5 cm into both.
    wx, (z0, z1), o = WINDOW_X, WINDOW_Z, 0.05
    _span_box(scene, "WallN_left", (-X - t, Y, -t), (-wx, Y + t, Z + t), walls)
    _span_box(scene, "WallN_right", (wx, Y, -t), (X + t, Y + t, Z + t), walls)
    _span_box(scene, "WallN_below", (-wx - o, Y, -t), (wx + o, Y + t, z0), walls)
    _span_box(scene, "WallN_above", (-wx - o, Y, z1), (wx + o, Y + t, Z + t), walls)
    wood = principled("Table", (0.6, 0.4, 0.25), 0.6)
    tx, ty = 1.2, 1.0
    _span_box(scene, "TableTop", (tx - 0.6, ty - 0.4, 0.70), (tx + 0.6, ty + 0.4, 0.75), wood)
    for k, (dx, dy) in enumerate(((-0.55, -0.35), (0.55, -0.35), (-0.55, 0.35), (0.55, 0.35))):
        x, y = tx + dx, ty + dy
        _span_box(scene, f"TableLeg{k}", (x - 0.03, y - 0.03, 0.0), (x + 0.03, y + 0.03, 0.70), wood)
    scenes.uv_sphere(
        scene, "Sphere", center=(-0.3, 1.1, 0.35), radius=0.35, mat=principled("Sphere", (0.8, 0.8, 0.8), 0.5)
    )
    # Where Cycles' portal goes (``use_engine``): the window's inner face.
    scene["world_window"] = (-wx, wx, z0, z1, Y)
    cam = scenes.look_at(scene, (1.3, -2.2, 1.8), (-0.3, 1.2, 0.2), lens=18.0)
    cam.data.clip_start = 0.05
    cam.data.clip_end = 50.0
    return scene


def skylight_room(scene):
    """A closed 6 x 4 x 3 m room (walls as ``window_room``'s: overlapping boxes WALL thick)
    lit by a uniform sky of strength 4 through a 1.2 x 1.2 m skylight in the ceiling and a
    0.9 x 2.0 m doorway in the west wall, with a crate under the skylight and a pillar; the
    camera in a corner looking across. No light portal for Penumbra (it finds the openings
    itself, ``engine/frame/world/probe.py``); Cycles gets portals over both openings, which
    only speed up its convergence (``use_engine``)."""
    uniform_sky(scene, (0.85, 0.9, 1.0), ROOM_SKY_STRENGTH)
    X, Y, Z, t, o = 3.0, 2.0, 3.0, WALL, 0.05
    walls = principled("Walls", (0.7, 0.72, 0.75), 0.8)
    floor = principled("Floor", (0.45, 0.5, 0.4), 0.6)
    _span_box(scene, "Floor", (-X - t, -Y - t, -t), (X + t, Y + t, 0.0), floor)
    # The ceiling around the skylight: x in [0.4, 1.6], y in [-0.6, 0.6].
    sx, sy = (0.4, 1.6), (-0.6, 0.6)
    _span_box(scene, "CeilingW", (-X - t, -Y - t, Z), (sx[0], Y + t, Z + t), walls)
    _span_box(scene, "CeilingE", (sx[1], -Y - t, Z), (X + t, Y + t, Z + t), walls)
    _span_box(scene, "CeilingS", (sx[0] - o, -Y - t, Z), (sx[1] + o, sy[0], Z + t), walls)
    _span_box(scene, "CeilingN", (sx[0] - o, sy[1], Z), (sx[1] + o, Y + t, Z + t), walls)
    _span_box(scene, "WallE", (X, -Y - t, -t), (X + t, Y + t, Z + t), walls)
    _span_box(scene, "WallS", (-X - t, -Y - t, -t), (X + t, -Y, Z + t), walls)
    _span_box(scene, "WallN", (-X - t, Y, -t), (X + t, Y + t, Z + t), walls)
    # The west wall around the doorway: y in [-1.2, -0.3], z in [0, 2].
    dy, dz = (-1.2, -0.3), 2.0
    _span_box(scene, "WallW_south", (-X - t, -Y - t, -t), (-X, dy[0], Z + t), walls)
    _span_box(scene, "WallW_north", (-X - t, dy[1], -t), (-X, Y + t, Z + t), walls)
    _span_box(scene, "WallW_above", (-X - t, dy[0] - o, dz), (-X, dy[1] + o, Z + t), walls)
    stone = principled("Stone", (0.6, 0.55, 0.5), 0.7)
    _span_box(scene, "Crate", (0.6, -0.9, 0.0), (1.4, -0.1, 0.8), stone)
    cylinder(scene, "Pillar", (-0.8, 0.6, 0.7), 0.3, 1.4, principled("Pillar", (0.8, 0.8, 0.8), 0.5))
    # Cycles' portals (location, rotation, size x, size y; each faces -Z into the room).
    scene["world_portals"] = [
        (sum(sx) / 2, sum(sy) / 2, Z, 0.0, 0.0, 0.0, sx[1] - sx[0], sy[1] - sy[0]),
        (-X, sum(dy) / 2, dz / 2, 0.0, -math.pi / 2, 0.0, dz, dy[1] - dy[0]),
    ]
    cam = scenes.look_at(scene, (2.6, 1.6, 1.7), (-1.0, -0.6, 0.6), lens=16.0)
    cam.data.clip_start = 0.05
    cam.data.clip_end = 50.0
    return scene


def window_room_bare(scene):
    """``window_room`` as most rooms come: no light portal for Penumbra (Cycles keeps one over
    the window, which only speeds up its convergence)."""
    window_room(scene)
    x0, x1, z0, z1, y = (float(v) for v in scene["world_window"])
    del scene["world_window"]
    scene["world_portals"] = [((x0 + x1) / 2, y, (z0 + z1) / 2, -math.pi / 2, 0.0, 0.0, x1 - x0, z1 - z0)]
    return scene


SCENES = {
    "sky_outdoor": sky_outdoor,
    "sky_outdoor_hdri": sky_outdoor_hdri,
    "glossy_spheres": glossy_spheres,
    "window_room": window_room,
    "window_room_bare": window_room_bare,
    "skylight_room": skylight_room,
}
INDOOR = ("window_room",)  # scenes where the bounce matters (a Cycles reference with one bounce)
PORTALLED = ("window_room", "window_room_bare", "skylight_room")  # Cycles renders them through portals


def build(name, width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    """A new empty scene (``scenes.empty_scene``) filled by builder ``name``; returns it."""
    try:
        builder = SCENES[name]
    except KeyError:
        raise ValueError(f"unknown world scene {name!r}; known: {', '.join(SCENES)}") from None
    return builder(scenes.empty_scene(width, height))


# --- engines and measurement ----------------------------------------------------------------

WORLD_SETTINGS = (
    "world_shadows",
    "world_samples",
    "world_map_size",
    "world_ao",
    "world_ao_distance",
    "indirect_bounces",
    "indirect_samples",
)


PORTAL = "WindowPortal"


def _portal(scene, present):
    """Add (``present``) or remove Cycles' light portal over a room's window
    (``scene['world_window']``): an area light flagged as a portal, which only guides Cycles'
    sampling of the sky through the window (the image converges to the same light, much
    faster). Penumbra reads it the same way (its directions of the world gather in the cone
    through the window); EEVEE is not shown it."""
    existing = scene.objects.get(PORTAL)
    if existing is not None and not present:
        data = existing.data
        bpy.data.objects.remove(existing)
        bpy.data.lights.remove(data)
    if present and existing is None and "world_window" in scene:
        x0, x1, z0, z1, y = scene["world_window"]
        ob = scenes.light(
            scene,
            PORTAL,
            "AREA",
            0.0,
            location=((x0 + x1) / 2, y, (z0 + z1) / 2),
            rotation=(-math.pi / 2, 0.0, 0.0),  # -Z, where it faces, along -Y: into the room
            shape="RECTANGLE",
            size=x1 - x0,
            size_y=z1 - z0,
        )
        ob.data.cycles.is_portal = True


def _portals(scene, present):
    """Add (``present``) or remove Cycles' light portals over a room's openings
    (``scene['world_portals']``: location, rotation, size x, size y each)."""
    for ob in [ob for ob in scene.objects if ob.name.startswith(PORTAL + "_")]:
        data = ob.data
        bpy.data.objects.remove(ob)
        bpy.data.lights.remove(data)
    if not present or "world_portals" not in scene:
        return
    for k, row in enumerate(scene["world_portals"]):
        x, y, z, rx, ry, rz, size_x, size_y = (float(v) for v in row)
        ob = scenes.light(
            scene,
            f"{PORTAL}_{k}",
            "AREA",
            0.0,
            location=(x, y, z),
            rotation=(rx, ry, rz),
            shape="RECTANGLE",
            size=size_x,
            size_y=size_y,
        )
        ob.data.cycles.is_portal = True


def use_engine(scene, engine, **settings):
    """Set ``scene`` up for ``engine`` ('PENUMBRA', 'CYCLES' or 'EEVEE') with ``settings``:

    PENUMBRA  ``scene.penumbra`` settings; a world or light-path setting this build does not
              have (WORLD_SETTINGS) is skipped, any other unknown name is an error
    CYCLES    ``bounces`` (0: direct light; 1: one diffuse bounce), ``samples``, ``seed``,
              through Penumbra's pixel filter, a portal over a room's window (Penumbra too)
              and over ``world_portals`` (Cycles only); ``portals=False``: none (any engine)
    EEVEE     ``devkit.engines``' EEVEE (16 TAA samples), no light probe baked

    Returns the names of the settings skipped."""
    key = engine.upper()
    portals = settings.pop("portals", True)
    _portal(scene, portals and key in ("CYCLES", "PENUMBRA"))
    _portals(scene, portals and key == "CYCLES")
    if key == "CYCLES":
        engines.configure(scene, "CYCLES", **cycles_settings(**settings), **kit.matched_filter(scene))
        return []
    if key != "PENUMBRA":
        engines.configure(scene, key, **settings)
        return []
    engines.configure(scene, "PENUMBRA")
    skipped = []
    for name, value in settings.items():
        if not hasattr(scene.penumbra, name):
            if name not in WORLD_SETTINGS:
                raise AttributeError(f"PENUMBRA: no setting {name!r}")
            skipped.append(name)
            continue
        setattr(scene.penumbra, name, value)
    return skipped


def cycles_settings(bounces=0, samples=16, seed=0):
    """``scene.cycles`` settings for ``bounces`` 0 (direct light only, as ``devkit.engines``
    sets Cycles up) or 1 (one diffuse bounce; glossy and transmission bounces 0)."""
    settings = {"samples": samples, "seed": seed}
    if bounces:
        settings.update(max_bounces=1, diffuse_bounces=1, glossy_bounces=0, transmission_bounces=0)
    return settings


def display(linear):
    """Scene-linear RGB(A) -> display RGB in 0..1 through the 'Standard' view (sRGB)."""
    x = np.clip(np.nan_to_num(np.asarray(linear)[..., :3], nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)
    return np.where(x <= 0.0031308, x * 12.92, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def render_display(scene):
    """Display RGB (h, w, 3), row 0 at the bottom, of ``scene`` with its current engine."""
    return display(render(scene)["Combined"])


def mae(a, b):
    """Mean absolute difference of two display images (every pixel and channel)."""
    return float(np.mean(np.abs(np.asarray(a, np.float64) - np.asarray(b, np.float64))))


def source_digest():
    """The first 10 hex digits of SHA-256 of this file: part of the cache key."""
    return hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:10]


def cache_path(name, samples, width, height, bounces=0, cache_dir=CACHE):
    major, minor = bpy.app.version[:2]
    key = f"world-{name}-b{bounces}-{samples}spp-{width}x{height}-blender{major}.{minor}-{source_digest()}.npy"
    return Path(cache_dir) / key


REFERENCE_SEED = 1


def cycles_reference(name, samples=256, width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT, bounces=0, cache_dir=CACHE):
    """Display RGB (h, w, 3), row 0 at the bottom, of Cycles on world scene ``name`` with
    ``bounces`` (0: direct light; 1: one diffuse bounce) at ``samples`` spp, seed
    REFERENCE_SEED, through Penumbra's pixel filter: from the cache when there, else rendered
    (this replaces the current scene) and cached."""
    path = cache_path(name, samples, width, height, bounces, cache_dir)
    if path.exists():
        return np.load(path)
    scene = build(name, width, height)
    use_engine(scene, "CYCLES", bounces=bounces, samples=samples, seed=REFERENCE_SEED)
    image = render_display(scene)
    kit.save_npy(path, image)
    return image
