"""Shadow accuracy kit: reference scenes built in code, per-pixel shadow visibility measured
the same way in every engine, and converged Cycles references cached on disk::

    scene = reference_kit.build("sun_soft", 160, 90)
    ref = reference_kit.cycles_reference("sun_soft", samples=512, width=160, height=90)
    vis = reference_kit.measure_visibility(scene, "PENUMBRA", shadow_filter="PCSS")
    reference_kit.compare(vis, ref)   # {'iou': ..., 'mae': ..., ...}

Every scene has one light, a black world, a white Lambertian plane (specular 0, roughness 1),
grey Lambertian casters and a perspective camera looking down at an angle:

=========  ============================================================================
sun_hard   sun, angle 0.5 deg, over a box, a floating sphere and a floating slab
sun_soft   the same sun with angle 10 deg
spot       spot light, radius (shadow_soft_size) 0.25, 70 deg cone, same casters
spot_hard  the same spot with radius 0.02: near-hard shadows (not in LIGHT_SCENES)
point      point light, radius 0.2, same casters
area       square area light, size 1.0, facing down, same casters
contact    a tall thin box (0.5 x 0.5 x 3) standing on the plane, sun with angle 8 deg:
           the shadow is sharp where the box meets the plane and soft far from it
=========  ============================================================================

Detailed casters on large grounds (``DETAILED_SCENES``; shared meshes from ``devkit.assets``,
rendered at DETAILED_WIDTH x DETAILED_HEIGHT), where the maps' fit and bias decide the result:

=========  ============================================================================
bunny      the scanned bunny (69k triangles, 0.6 m) on a 2 km ground, sharp sun (0.5 deg)
           at 40 deg, camera 2.4 m away with a 1 km far clip: fine self-shadowing
suzanne    smooth-shaded Suzanne (subdivided once) on the same ground and sun: smooth
           low-poly self-shadowing (the shadow terminator)
grazing    three cows (6k triangles each) on the ground under a sun 4 deg above the
           horizon: long thin shadows, legs, contact at the feet
tiny       a 15 cm bunny on a 1 km ground, camera 0.6 m away, far clip 500 m
lamp       the bunny on the 2 km ground under a street lamp: a spot light 5 m up with a
           150 deg cone (radius 0.02)
room       a point light (radius 0.05) in a closed 6 x 5 x 3 m room with a table and the
           bunny: cube-face seams cross floor and wall shadows
=========  ============================================================================

Thin casters (``THIN_SCENES``, on the same large ground, at DETAILED_WIDTH x DETAILED_HEIGHT),
whose shadows are a few pixels wide, so the pixel filter decides as much as the maps: they are
compared with Cycles through the same Blackman-Harris filter (``matched_filter``):

=========  ============================================================================
knot       a (2, 3) torus knot of 2 cm tube radius floating 0.8 m up, sharp sun at 35 deg
fence      24 slats 2 cm square and 1 m tall with a 1.5 cm rail, sun 12 deg above the
           horizon: long parallel shadows two pixels wide
wires      five sagging wires of 6-22 mm diameter 1.5 m up, sharp sun at 55 deg: shadows
           partly lit (the sun's disc is wider than the thinnest wires seen from the ground)
leaves     160 leaves (10 x 5 cm quads) scattered around 1.6 m under a near-hard spot
stack      six boxes of shrinking size stacked under a near-hard spot (radius 0.02)
=========  ============================================================================

The shadow terminator (``TERMINATOR_SCENES``; Object › Shading › Shadow Terminator):

===============  ======================================================================
terminator       a low-poly smooth UV sphere (16 x 8, radius 1) on the ground under a
                 sharp sun 25 deg above the horizon, seen across its terminator;
                 Geometry Offset 0.1 (Blender's default)
terminator_off   the same with Geometry Offset 0: the facets' stair-stepped terminator
===============  ======================================================================

Visibility is (render with shadows) / (render with the light's ``use_shadow`` off), in
luminance, so light units, falloff and cone shapes cancel and only the shadow term remains.
Engines are set up by ``devkit.engines``; its Cycles renders direct light only, so indirect
light does not make its shadows brighter than a shadow-mapping engine's.
"""

import math
import os
import tempfile
from pathlib import Path

import bpy
import numpy as np

from devkit import scenes
from devkit.analytic import camera_matrices
from devkit.engines import configure
from devkit.render import render
from devkit.session import ROOT

# Part of every cache key: bump it whenever a scene or the measurement changes.
KIT_VERSION = 1
DEFAULT_CACHE = ROOT / "out" / "reference_cache"
DEFAULT_WIDTH, DEFAULT_HEIGHT = 160, 90

PLANE_ALBEDO = 0.8
CASTER_ALBEDO = 0.6
LUMA = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 luminance of scene-linear RGB

# The floating sphere of the five light scenes (the benchmark varies its detail).
SPHERE_CENTER = (0.9, -0.5, 1.3)
SPHERE_RADIUS = 0.6

# Contact scene geometry: a pillar PILLAR_WIDTH wide and PILLAR_HEIGHT tall centred on the
# origin; the sun comes from +Y, CONTACT_ELEVATION above the horizon, so the shadow runs along -Y.
PILLAR_WIDTH = 0.5
PILLAR_HEIGHT = 3.0
CONTACT_ELEVATION = math.radians(50.0)
CONTACT_SUN_ANGLE = math.radians(8.0)


# --- scenes -------------------------------------------------------------------------------


def _stage(width, height):
    """Empty scene, black world, the white plane; returns (scene, caster material)."""
    scene = scenes.empty_scene(width, height)
    scenes.plane(scene, "Ground", size=24.0, mat=scenes.white("Plane", PLANE_ALBEDO))
    return scene, scenes.white("Caster", CASTER_ALBEDO)


def _casters_scene(width, height):
    """The shared set-up of the five light scenes: a box on the ground (contact shadow), a
    floating sphere (soft shadow far from its caster), a floating slab (thin, long edges)."""
    scene, grey = _stage(width, height)
    scenes.box(scene, "Box", center=(-1.3, 0.2, 0.5), size=(1.0, 1.0, 1.0), mat=grey)
    scenes.uv_sphere(scene, "Sphere", center=SPHERE_CENTER, radius=SPHERE_RADIUS, mat=grey)
    slab = scenes.box(scene, "Slab", center=(0.5, 1.1, 1.7), size=(1.8, 0.35, 0.08), mat=grey)
    slab.rotation_euler = (0.0, 0.0, math.radians(-20.0))
    scenes.look_at(scene, (1.0, -7.0, 5.5), (0.2, -0.2, 0.4), lens=42.0)
    return scene


def _hide_from_camera(light_ob):
    """Cycles may show an emitter to camera rays; no reference image should contain one."""
    if hasattr(light_ob, "visible_camera"):
        light_ob.visible_camera = False
    return light_ob


def _sun(scene, angle_deg):
    sun = scenes.light(scene, "Sun", "SUN", 3.0, angle=math.radians(angle_deg))
    # Light travelling towards +X and -Y: the shadows fall towards the camera, to the right.
    sun.rotation_euler = (math.radians(-45.0), 0.0, math.radians(30.0))
    return _hide_from_camera(sun)


def sun_hard(width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    scene = _casters_scene(width, height)
    _sun(scene, 0.5)
    return scene


def sun_soft(width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    scene = _casters_scene(width, height)
    _sun(scene, 10.0)
    return scene


def spot(width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    scene = _casters_scene(width, height)
    ob = scenes.light(
        scene,
        "Spot",
        "SPOT",
        1500.0,
        location=(2.2, -1.8, 5.0),
        shadow_soft_size=0.25,
        spot_size=math.radians(70.0),
        spot_blend=0.15,
    )
    scenes.aim(ob, (-0.2, 0.4, 0.0))
    _hide_from_camera(ob)
    return scene


def spot_hard(width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    """The spot scene with a near-point emitter (radius 2 cm): sharp shadows."""
    scene = spot(width, height)
    scene.objects["Spot"].data.shadow_soft_size = 0.02
    return scene


def point(width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    scene = _casters_scene(width, height)
    ob = scenes.light(scene, "Point", "POINT", 1000.0, location=(1.6, -1.4, 3.6), shadow_soft_size=0.2)
    _hide_from_camera(ob)
    return scene


def area(width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    scene = _casters_scene(width, height)
    ob = scenes.light(scene, "Area", "AREA", 1500.0, location=(1.4, -1.2, 4.0), shape="SQUARE", size=1.0)
    _hide_from_camera(ob)
    return scene


def contact(width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    scene, grey = _stage(width, height)
    scenes.box(
        scene,
        "Pillar",
        center=(0.0, 0.0, PILLAR_HEIGHT / 2),
        size=(PILLAR_WIDTH, PILLAR_WIDTH, PILLAR_HEIGHT),
        mat=grey,
    )
    sun = scenes.light(scene, "Sun", "SUN", 3.0, angle=CONTACT_SUN_ANGLE)
    # Rotating -Z by -(90 deg - elevation) about X: the light travels towards -Y and down.
    sun.rotation_euler = (-(math.pi / 2 - CONTACT_ELEVATION), 0.0, 0.0)
    _hide_from_camera(sun)
    # From the -Y side, in front of the shadow, which then runs up the image.
    scenes.look_at(scene, (0.0, -8.0, 5.0), (0.0, -1.2, 0.5), lens=40.0)
    return scene


# --- detailed casters on large grounds ------------------------------------------------------

DETAILED_WIDTH, DETAILED_HEIGHT = 320, 180
BIG_GROUND = 2000.0


def _big_stage(width, height, ground=BIG_GROUND, far=1000.0):
    scene, grey = _stage(width, height)
    ground_ob = scene.objects["Ground"]
    ground_ob.scale = (ground / 24.0,) * 3
    return scene, grey, far


def _sharp_sun(scene, elevation_deg, azimuth_deg=30.0, angle_deg=0.5):
    sun = scenes.light(scene, "Sun", "SUN", 3.0, angle=math.radians(angle_deg))
    sun.rotation_euler = (-(math.pi / 2 - math.radians(elevation_deg)), 0.0, math.radians(azimuth_deg))
    return _hide_from_camera(sun)


def _camera(scene, location, target, lens, far):
    cam = scenes.look_at(scene, location, target, lens=lens)
    cam.data.clip_end = far
    cam.data.clip_start = min(0.1, far * 1e-4)
    return cam


def _mesh(scene, path, height, material, location=(0.0, 0.0, 0.0), rotation_z=0.0, name=None):
    from devkit import assets

    ob = assets.import_mesh(scene, path, height=height, name=name)
    ob.location = location
    ob.rotation_euler = (0.0, 0.0, math.radians(rotation_z))
    ob.data.materials.clear()
    ob.data.materials.append(material)
    return ob


def bunny(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    from devkit import assets

    scene, grey, far = _big_stage(width, height)
    _mesh(scene, assets.BUNNY, 0.6, grey, rotation_z=-30.0, name="Bunny")
    _sharp_sun(scene, 40.0, azimuth_deg=40.0)
    _camera(scene, (0.9, -2.1, 0.9), (0.0, 0.0, 0.22), 45.0, far)
    return scene


def suzanne(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    scene, grey, far = _big_stage(width, height)
    me = scenes.smooth_monkey_mesh("Suzanne")
    ob = scenes.link(scene, bpy.data.objects.new("Suzanne", me))
    # Suzanne faces -Y; standing 1 m tall on the ground, her face towards the camera.
    ob.scale = (0.5, 0.5, 0.5)
    ob.location = (0.0, 0.0, 0.6)
    ob.rotation_euler = (math.radians(10.0), 0.0, math.radians(20.0))
    me.materials.append(grey)
    _sharp_sun(scene, 45.0, azimuth_deg=-35.0)
    _camera(scene, (0.6, -3.2, 1.5), (0.0, 0.0, 0.55), 50.0, far)
    return scene


def grazing(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    from devkit import assets

    scene, grey, far = _big_stage(width, height)
    cows = [((-1.4, 0.6, 0.0), 20.0), ((0.4, -0.2, 0.0), -50.0), ((1.8, 1.4, 0.0), 100.0)]
    for k, (loc, rot) in enumerate(cows):
        _mesh(scene, assets.SPOT, 0.9, grey, location=loc, rotation_z=rot, name=f"Cow{k}")
    # The sun 4 deg above the horizon, from behind and to the side: shadows 13 m long.
    _sharp_sun(scene, 4.0, azimuth_deg=150.0)
    _camera(scene, (1.0, -7.5, 3.2), (0.2, 1.0, 0.2), 35.0, far)
    return scene


def tiny(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    from devkit import assets

    scene, grey, _far = _big_stage(width, height, ground=1000.0)
    _mesh(scene, assets.BUNNY, 0.15, grey, rotation_z=-30.0, name="Bunny")
    _sharp_sun(scene, 50.0, azimuth_deg=40.0)
    _camera(scene, (0.22, -0.5, 0.3), (0.0, 0.0, 0.05), 45.0, 500.0)
    return scene


def lamp(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    from devkit import assets

    scene, grey, far = _big_stage(width, height)
    _mesh(scene, assets.BUNNY, 0.6, grey, rotation_z=-30.0, name="Bunny")
    ob = scenes.light(
        scene,
        "Lamp",
        "SPOT",
        2000.0,
        location=(1.2, 1.0, 5.0),
        shadow_soft_size=0.02,
        spot_size=math.radians(150.0),
        spot_blend=0.3,
    )
    scenes.aim(ob, (0.0, 0.0, 0.0))
    _hide_from_camera(ob)
    _camera(scene, (0.9, -2.1, 0.9), (0.0, 0.0, 0.22), 45.0, far)
    return scene


def room(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    from devkit import assets

    scene, grey = _stage(width, height)
    scene.objects["Ground"].scale = (6.0 / 24.0, 5.0 / 24.0, 1.0)
    white = scenes.white("Walls", PLANE_ALBEDO)
    # Walls and ceiling as thin boxes, so every surface casts and receives from both sides.
    t = 0.1
    for name, center, size in (
        ("Ceiling", (0.0, 0.0, 3.0 + t / 2), (6.0, 5.0, t)),
        ("WallN", (0.0, 2.5 + t / 2, 1.5), (6.0, t, 3.0)),
        ("WallS", (0.0, -2.5 - t / 2, 1.5), (6.0, t, 3.0)),
        ("WallE", (3.0 + t / 2, 0.0, 1.5), (t, 5.0, 3.0)),
        ("WallW", (-3.0 - t / 2, 0.0, 1.5), (t, 5.0, 3.0)),
    ):
        scenes.box(scene, name, center=center, size=size, mat=white)
    scenes.box(scene, "Table", center=(0.6, 0.5, 0.75), size=(1.4, 0.8, 0.06), mat=grey)
    for k, (x, y) in enumerate(((0.0, 0.2), (1.2, 0.2), (0.0, 0.8), (1.2, 0.8))):
        scenes.box(scene, f"Leg{k}", center=(x, y, 0.36), size=(0.06, 0.06, 0.72), mat=grey)
    _mesh(scene, assets.BUNNY, 0.5, grey, location=(-1.2, -0.4, 0.0), rotation_z=20.0, name="Bunny")
    ob = scenes.light(scene, "Point", "POINT", 600.0, location=(0.2, -0.6, 2.1), shadow_soft_size=0.05)
    _hide_from_camera(ob)
    cam = _camera(scene, (2.6, -2.3, 2.2), (-0.6, 0.6, 0.6), 24.0, 100.0)
    cam.data.clip_start = 0.05
    return scene


def _tube(points, radius, sides, closed):
    """A tube of ``sides`` faces around the polyline ``points`` (n, 3): (verts, quads)."""
    p = np.asarray(points, np.float64)
    n = len(p)
    t = (np.roll(p, -1, 0) - np.roll(p, 1, 0)) if closed else np.gradient(p, axis=0)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    a = np.cross(t, (0.0, 0.0, 1.0))
    flat = np.linalg.norm(a, axis=1) < 1e-3
    a[flat] = np.cross(t[flat], (1.0, 0.0, 0.0))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(t, a)
    ang = np.arange(sides) * (2.0 * math.pi / sides)
    ring = np.cos(ang)[None, :, None] * a[:, None, :] + np.sin(ang)[None, :, None] * b[:, None, :]
    verts = (p[:, None, :] + radius * ring).reshape(-1, 3)
    faces = []
    for i in range(n if closed else n - 1):
        j = (i + 1) % n
        for k in range(sides):
            k2 = (k + 1) % sides
            faces.append((i * sides + k, i * sides + k2, j * sides + k2, j * sides + k))
    return verts, faces


def knot(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    scene, grey, far = _big_stage(width, height)
    s = np.linspace(0.0, 2.0 * math.pi, 360, endpoint=False)
    r = 0.35 + 0.15 * np.cos(3 * s)
    points = np.stack([r * np.cos(2 * s), r * np.sin(2 * s), 0.15 * np.sin(3 * s) + 0.8], 1)
    verts, faces = _tube(points, 0.02, 8, closed=True)
    scenes.mesh_object(scene, "Knot", verts, faces, mat=grey)
    _sharp_sun(scene, 35.0, azimuth_deg=200.0)
    _camera(scene, (0.6, -2.4, 1.9), (0.0, 0.8, 0.2), 40.0, far)
    return scene


def fence(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    scene, grey, far = _big_stage(width, height)
    for k in range(24):
        scenes.box(scene, f"Slat{k}", center=(-1.2 + 0.1 * k, 0.0, 0.5), size=(0.02, 0.02, 1.0), mat=grey)
    scenes.box(scene, "Rail", center=(0.0, 0.0, 0.9), size=(2.5, 0.015, 0.015), mat=grey)
    _sharp_sun(scene, 12.0, azimuth_deg=160.0)
    _camera(scene, (1.5, -4.5, 2.5), (0.0, 1.5, 0.0), 35.0, far)
    return scene


def wires(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    scene, grey, far = _big_stage(width, height)
    x = np.linspace(-3.0, 3.0, 60)
    sag = 1.5 - 0.15 * np.cos(np.linspace(-1.0, 1.0, 60) * math.pi / 2)
    for k in range(5):
        points = np.stack([x, np.full(60, -0.6 + 0.3 * k), sag], 1)
        verts, faces = _tube(points, 0.003 + 0.002 * k, 6, closed=False)
        scenes.mesh_object(scene, f"Wire{k}", verts, faces, mat=grey)
    _sharp_sun(scene, 55.0, azimuth_deg=190.0)
    _camera(scene, (0.5, -2.5, 2.2), (0.0, 1.0, 0.0), 40.0, far)
    return scene


def _spot_over(scene, location, target, radius=0.02, cone_deg=90.0):
    ob = scenes.light(
        scene,
        "Spot",
        "SPOT",
        300.0,
        location=location,
        shadow_soft_size=radius,
        spot_size=math.radians(cone_deg),
        spot_blend=0.2,
    )
    scenes.aim(ob, target)
    return _hide_from_camera(ob)


def leaves(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    scene, grey, far = _big_stage(width, height)
    rng = np.random.default_rng(3)
    verts, faces = [], []
    for _ in range(160):
        c = rng.normal(0.0, 0.35, 3) * (1.0, 1.0, 0.5) + (0.0, 0.0, 1.6)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        w = rng.normal(size=3)
        w -= u * (w @ u)
        w /= np.linalg.norm(w)
        base = len(verts)
        verts += [c + 0.05 * u, c + 0.025 * w, c - 0.05 * u, c - 0.025 * w]
        faces.append((base, base + 1, base + 2, base + 3))
    scenes.mesh_object(scene, "Leaves", np.array(verts), faces, mat=grey)
    _spot_over(scene, (0.8, 0.6, 4.0), (0.0, 0.0, 0.0))
    _camera(scene, (1.2, -3.0, 2.6), (0.0, 0.0, 0.4), 40.0, far)
    return scene


def stack(width=DETAILED_WIDTH, height=DETAILED_HEIGHT):
    scene, grey, far = _big_stage(width, height)
    z = 0.0
    for k, side in enumerate((0.6, 0.45, 0.33, 0.24, 0.17, 0.12)):
        scenes.box(scene, f"Box{k}", center=(0.05 * k, 0.03 * k, z + side / 2), size=(side,) * 3, mat=grey)
        z += side
    _spot_over(scene, (-1.5, 1.0, 4.0), (0.0, 0.0, 0.5), cone_deg=80.0)
    _camera(scene, (2.0, -3.0, 2.4), (0.0, 0.2, 0.6), 40.0, far)
    return scene


def matched_filter(scene):
    """Cycles settings that filter pixels as Penumbra does on ``scene``: its Blackman-Harris
    filter of the same reach (Cycles' Pixel Filter Width). The kit's other comparisons keep
    Cycles' narrow box (pixel centres), which barely differs where edges are long and smooth;
    a shadow a few pixels wide is mostly edge, and its pixels' values are the filter's."""
    return {"pixel_filter_type": "BLACKMAN_HARRIS", "filter_width": float(scene.penumbra.filter_size)}


TERMINATOR_SEGMENTS, TERMINATOR_RINGS = 16, 8
TERMINATOR_CENTER = (0.0, 0.0, 1.0)


def terminator(width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT, geometry_offset=0.1, shading_offset=0.0):
    """A smooth 16 x 8 UV sphere of radius 1 resting on the ground, a sun (angle 0.5 deg) 25
    deg above the horizon from +X, the camera looking at the sphere across the terminator."""
    scene, grey = _stage(width, height)
    ob = scenes.uv_sphere(
        scene,
        "Sphere",
        center=TERMINATOR_CENTER,
        radius=1.0,
        segments=TERMINATOR_SEGMENTS,
        rings=TERMINATOR_RINGS,
        mat=grey,
    )
    ob.rotation_euler = (0.0, 0.0, math.radians(7.0))  # facets not aligned with the sun
    ob.shadow_terminator_geometry_offset = geometry_offset
    ob.shadow_terminator_shading_offset = shading_offset
    _sharp_sun(scene, 25.0, azimuth_deg=90.0)
    scenes.look_at(scene, (1.2, -5.5, 2.2), (0.0, 0.0, 0.9), lens=60.0)
    return scene


def terminator_off(width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    return terminator(width, height, geometry_offset=0.0)


def sphere_mask(scene, center, radius):
    """Pixels (h, w), row 0 at the bottom, whose centre's camera ray meets the sphere
    (``center``, ``radius``)."""
    view, proj, w, h = camera_matrices(scene)
    inv = np.linalg.inv(proj @ view)
    xs = (np.arange(w) + 0.5) / w * 2.0 - 1.0
    ys = (np.arange(h) + 0.5) / h * 2.0 - 1.0
    X, Y = np.meshgrid(xs, ys)
    near = np.stack([X, Y, -np.ones_like(X), np.ones_like(X)], axis=-1) @ inv.T
    far = np.stack([X, Y, np.ones_like(X), np.ones_like(X)], axis=-1) @ inv.T
    a = near[..., :3] / near[..., 3:4]
    d = far[..., :3] / far[..., 3:4] - a
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    oc = a - np.asarray(center, np.float64)
    b = np.einsum("...i,...i", oc, d)
    c = np.einsum("...i,...i", oc, oc) - radius * radius
    return b * b - c > 0.0


SCENES = {
    "sun_hard": sun_hard,
    "sun_soft": sun_soft,
    "spot": spot,
    "spot_hard": spot_hard,
    "point": point,
    "area": area,
    "contact": contact,
    "bunny": bunny,
    "suzanne": suzanne,
    "grazing": grazing,
    "tiny": tiny,
    "lamp": lamp,
    "room": room,
    "knot": knot,
    "fence": fence,
    "wires": wires,
    "leaves": leaves,
    "stack": stack,
    "terminator": terminator,
    "terminator_off": terminator_off,
}
LIGHT_SCENES = ("sun_hard", "sun_soft", "spot", "point", "area", "contact")
SOFT_SCENES = ("sun_soft", "spot", "point", "area", "contact")  # visibly soft shadows in Cycles
DETAILED_SCENES = ("bunny", "suzanne", "grazing", "tiny", "lamp", "room")  # detailed casters, large grounds
THIN_SCENES = ("knot", "fence", "wires", "leaves", "stack")  # shadows a few pixels wide (matched_filter)
TERMINATOR_SCENES = ("terminator", "terminator_off")


def build(name, width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    """Build reference scene ``name`` (a key of SCENES) as the current scene and return it."""
    try:
        builder = SCENES[name]
    except KeyError:
        raise ValueError(f"unknown reference scene {name!r}; known: {', '.join(SCENES)}") from None
    return builder(width, height)


def set_sphere_detail(scene, segments):
    """Rebuild the caster sphere of a light scene with ``segments`` segments and
    ``segments // 2`` rings: 2 x segments x (rings - 1) triangles (32 -> 960, 100 -> 9,800,
    318 -> 100,488)."""
    old = scene.objects["Sphere"]
    mat = old.data.materials[0] if old.data.materials else None
    mesh = old.data
    bpy.data.objects.remove(old)
    bpy.data.meshes.remove(mesh)
    return scenes.uv_sphere(
        scene,
        "Sphere",
        center=SPHERE_CENTER,
        radius=SPHERE_RADIUS,
        segments=segments,
        rings=max(segments // 2, 3),
        mat=mat,
    )


def scene_light(scene):
    """The one light object of a reference scene."""
    lights = [ob for ob in scene.objects if ob.type == "LIGHT"]
    if len(lights) != 1:
        raise ValueError(f"expected one light in scene '{scene.name}', found {len(lights)}")
    return lights[0]


# --- measurement --------------------------------------------------------------------------


def luminance(rgba):
    return np.asarray(rgba, np.float64)[..., :3] @ LUMA


def visibility_from(shadowed, unshadowed, threshold=0.02):
    """Visibility per pixel from two luminance images: shadowed / unshadowed, clipped to
    [0, 1]; NaN where the unshadowed image is below ``threshold`` times its 99th percentile
    (back faces, outside a spot cone, the black background)."""
    shadowed = np.asarray(shadowed, np.float64)
    unshadowed = np.asarray(unshadowed, np.float64)
    lit = unshadowed[np.isfinite(unshadowed)]
    level = float(np.percentile(lit, 99)) if lit.size else 0.0
    valid = np.isfinite(unshadowed) & np.isfinite(shadowed) & (unshadowed > threshold * level) & (level > 0)
    vis = np.full(unshadowed.shape, np.nan)
    vis[valid] = np.clip(shadowed[valid] / unshadowed[valid], 0.0, 1.0)
    return vis


def render_luminance(scene):
    """Render ``scene`` with its engine through Blender's output path; luminance (h, w), row 0
    at the bottom of the image."""
    return luminance(render(scene)["Combined"])


def measure_visibility(scene, engine, threshold=0.02, **engine_settings):
    """Shadow visibility per pixel (h, w) of ``scene``'s one light in ``engine``: the render
    with shadows over the render with ``light.data.use_shadow = False``, in luminance.
    NaN where the light does not reach (see ``visibility_from``); row 0 is the bottom row."""
    configure(scene, engine, **engine_settings)
    light = scene_light(scene).data
    old = light.use_shadow
    try:
        light.use_shadow = True
        shadowed = render_luminance(scene)
        light.use_shadow = False
        unshadowed = render_luminance(scene)
    finally:
        light.use_shadow = old
    return visibility_from(shadowed, unshadowed, threshold)


def compare(vis, ref, edge=0.5):
    """Accuracy of visibility ``vis`` against the reference ``ref`` over the pixels valid in
    both:

    iou           intersection over union of the shadowed regions (visibility < ``edge``)
    mae           mean absolute visibility error
    mae_penumbra  the same error over the reference's penumbrae only (0.02 < ref < 0.98),
                  where filters differ most
    pixels        valid pixels compared
    """
    vis = np.asarray(vis, np.float64)
    ref = np.asarray(ref, np.float64)
    if vis.shape != ref.shape:
        raise ValueError(f"shape mismatch: {vis.shape} vs {ref.shape}")
    valid = np.isfinite(vis) & np.isfinite(ref)
    a, b = vis[valid] < edge, ref[valid] < edge
    union = int((a | b).sum())
    err = np.abs(vis[valid] - ref[valid])
    soft = (ref[valid] > 0.02) & (ref[valid] < 0.98)
    return {
        "iou": float((a & b).sum() / union) if union else 1.0,
        "mae": float(err.mean()) if err.size else float("nan"),
        "mae_penumbra": float(err[soft].mean()) if soft.any() else float("nan"),
        "pixels": int(valid.sum()),
    }


# --- Cycles references ----------------------------------------------------------------------


def cache_path(name, samples, width, height, cache_dir=DEFAULT_CACHE):
    """Where the Cycles reference of ``name`` is cached: scene, samples, resolution, Blender
    major.minor (references may differ between Blender lines) and the kit version."""
    major, minor = bpy.app.version[:2]
    key = f"{name}-{samples}spp-{width}x{height}-blender{major}.{minor}-v{KIT_VERSION}.npy"
    return Path(cache_dir) / key


def save_npy(path, array):
    """Save ``array`` to ``path`` (.npy), its folder made: written then renamed, so a
    concurrent reader never sees half a file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".npy", dir=path.parent)
    with os.fdopen(fd, "wb") as f:
        np.save(f, array)
    os.chmod(tmp, 0o644)  # mkstemp creates files readable by their owner only
    os.replace(tmp, path)


def cycles_reference(name, samples=512, width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT, cache_dir=DEFAULT_CACHE):
    """Cycles visibility of reference scene ``name`` at ``samples`` spp, from the cache when
    present; otherwise rendered (this rebuilds the current scene) and cached. THIN_SCENES are
    rendered through ``matched_filter``."""
    path = cache_path(name, samples, width, height, cache_dir)
    if name in THIN_SCENES:
        path = path.with_name(path.name.replace(".npy", "-matched.npy"))
    if path.exists():
        return np.load(path)
    scene = build(name, width, height)
    extra = matched_filter(scene) if name in THIN_SCENES else {}
    vis = measure_visibility(scene, "CYCLES", samples=samples, **extra)
    save_npy(path, vis)
    return vis


def cycles_luminance(name, samples=512, width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT, cache_dir=DEFAULT_CACHE):
    """Cycles luminance (the whole shadowed image) of reference scene ``name`` at ``samples``
    spp, cached beside the visibility references."""
    path = cache_path(name, samples, width, height, cache_dir).with_suffix(".lum.npy")
    if path.exists():
        return np.load(path)
    scene = build(name, width, height)
    configure(scene, "CYCLES", samples=samples)
    lum = render_luminance(scene)
    save_npy(path, lum)
    return lum


# --- contact hardening ----------------------------------------------------------------------


def _sample_bilinear(image, px, py):
    """Bilinear samples of ``image`` (h, w) at pixel coordinates (0 = first pixel centre);
    NaN outside the image or next to an invalid pixel."""
    h, w = image.shape
    x0, y0 = np.floor(px).astype(int), np.floor(py).astype(int)
    fx, fy = px - x0, py - y0
    inside = (x0 >= 0) & (y0 >= 0) & (x0 + 1 < w) & (y0 + 1 < h)
    x0c, y0c = np.clip(x0, 0, w - 2), np.clip(y0, 0, h - 2)
    a, b = image[y0c, x0c], image[y0c, x0c + 1]
    c, d = image[y0c + 1, x0c], image[y0c + 1, x0c + 1]
    value = (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy
    return np.where(inside, value, np.nan)


def _crossing(x, v, level):
    """First x where the profile v(x) reaches ``level`` (linear interpolation), or NaN."""
    above = np.nonzero(v >= level)[0]
    if len(above) == 0 or above[0] == 0:
        return float("nan")
    i = above[0]
    return float(x[i - 1] + (level - v[i - 1]) / (v[i] - v[i - 1]) * (x[i] - x[i - 1]))


def penumbra_width(scene, vis, distance, low=0.1, high=0.9, band=0.06):
    """Width on the plane (scene units) of the ``low``-``high`` visibility transition across
    the contact scene's pillar shadow, ``distance`` units from the pillar along the shadow.

    The visibility image is sampled along lines across the shadow (averaged over a ``band``
    along it, against noise), from the shadow's centre line outwards on both sides; the
    width is the mean of the two sides. NaN when the profile never drops below ``low``."""
    view, proj, w, h = camera_matrices(scene)
    y = -(PILLAR_WIDTH / 2 + distance) + np.linspace(-band / 2, band / 2, 7)
    x = np.linspace(0.0, 1.5, 601)
    X, Y = np.meshgrid(x, y)
    widths = []
    for side in (1.0, -1.0):
        world = np.stack([side * X, Y, np.zeros_like(X), np.ones_like(X)], axis=-1) @ (proj @ view).T
        ndc = world[..., :2] / world[..., 3:4]
        px = (ndc[..., 0] + 1) / 2 * w - 0.5
        py = (ndc[..., 1] + 1) / 2 * h - 0.5
        profile = np.nanmean(_sample_bilinear(np.asarray(vis, np.float64), px, py), axis=0)
        if not np.nanmin(profile) < low:
            return float("nan")
        widths.append(_crossing(x, profile, high) - _crossing(x, profile, low))
    return float(np.mean(widths))


def contact_widths(scene, vis, near=0.3, far=1.8):
    """(near width, far width) of the contact scene's penumbra, ``near`` and ``far`` units
    from the pillar along its shadow."""
    return penumbra_width(scene, vis, near), penumbra_width(scene, vis, far)
