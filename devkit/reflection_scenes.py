"""Scenes of what surfaces see (issue 50), their Cycles references, and the measurement the
reflections bench and tests share::

    scene = reflection_scenes.build("hdri_spheres", 160, 90)
    ref = reflection_scenes.cycles_reference("hdri_spheres", samples=256, width=160, height=90)
    reflection_scenes.use_engine(scene, "PENUMBRA", render_samples=64)
    reflection_scenes.object_mae(reflection_scenes.render_display(scene), ref, mask)

==============  ==========================================================================
hdri_spheres    three spheres on a grey ground under a real outdoor HDRI (Blender's own
                ``studiolights/world/forest.exr``, CC0, Poly Haven; shipped with bpy): a
                mirror metal (roughness 0), a brushed metal (0.25) and a polished red
                dielectric (0.05); the camera 12 deg down, so the mirror shows the sky and
                the trees
polished_floor  a dark polished dielectric floor (roughness 0.05) under a sun 35 deg up and a
                dim uniform sky, with a cube, Suzanne and a sphere on it: where the floor's
                sharp lobe met the world's ratio it carried a salt-and-pepper pattern
probe_floor     polished_floor with a Plane Light Probe over the floor (a planar reflection:
                what the screen does not hold of the objects, their undersides and backs, is
                reflected too)
glass_checker   a Glass BSDF sphere (IOR 1.45) and a Principled cube of Transmission 1
                (roughness 0.05, Thickness Mode Slab) on a checker ground under a sun and a
                pale sky
==============  ==========================================================================

References are Cycles with one glossy bounce (max_bounces 1, diffuse 0: a mirror shows the
world and what is around it, a diffuse surface its direct light), and for a scene with glass
(``scene["transmission_bounces"]``) as many transmission bounces with caustics off, through
Penumbra's pixel filter, cached like ``world_scenes``' (out/reference_cache, keyed by this
file's digest)."""

import hashlib
import math
from pathlib import Path

import bpy
import numpy as np

from . import engines, scenes
from . import reference_kit as kit
from . import world_scenes as ws

HDRI = "forest.exr"
CACHE = ws.CACHE
DEFAULT_WIDTH, DEFAULT_HEIGHT = 160, 90
SPHERES = (  # (name, centre x, colour, metallic, roughness)
    ("Mirror", -2.3, (0.9, 0.9, 0.9), 1.0, 0.0),
    ("Brushed", 0.0, (0.95, 0.7, 0.45), 1.0, 0.25),
    ("Polished", 2.3, (0.6, 0.05, 0.04), 0.0, 0.05),
)


def hdri_path(name=HDRI):
    """The path of Blender's own studio-light HDRI ``name`` (datafiles/studiolights/world)."""
    folder = bpy.utils.system_resource("DATAFILES", path="studiolights/world")
    path = Path(folder) / name
    if not path.exists():
        raise FileNotFoundError(f"no studio-light HDRI {name!r} in {folder}")
    return path


def hdri_world(scene, name=HDRI, strength=1.0, rotation_z=0.0):
    """The world: Environment Texture of ``name`` (a Mapping node turning it ``rotation_z``
    about Z where not 0) -> Background of ``strength`` (``world_scenes.environment_world``)."""
    image = bpy.data.images.load(str(hdri_path(name)), check_existing=True)
    return ws.environment_world(scene, image, strength, rotation_z or None)


def hdri_spheres(scene):
    hdri_world(scene, rotation_z=math.radians(40.0))
    scenes.plane(scene, "Ground", size=60.0, mat=ws.principled("Ground", (0.35, 0.35, 0.35), 0.6))
    for name, x, color, metallic, rough in SPHERES:
        scenes.uv_sphere(
            scene,
            name,
            center=(x, 0.0, 1.0),
            radius=1.0,
            segments=64,
            rings=32,
            mat=scenes.material(name, color, roughness=rough, metallic=metallic),
        )
    for ob in scene.objects:
        if ob.type == "MESH" and ob.name != "Ground":
            for poly in ob.data.polygons:
                poly.use_smooth = True
    scenes.look_at(scene, (0.0, -8.5, 2.6), (0.0, 0.0, 0.9), lens=40.0)


def polished_floor(scene):
    ws.uniform_sky(scene, (0.55, 0.65, 0.85), 0.4)
    scenes.plane(scene, "Floor", size=60.0, mat=ws.principled("Floor", (0.03, 0.03, 0.035), 0.05))
    scenes.box(
        scene, "Cube", center=(-1.8, 0.4, 0.6), size=(1.2, 1.2, 1.2), mat=ws.principled("Cube", (0.7, 0.3, 0.1), 0.5)
    )
    ws.monkey(scene, "Suzanne", (0.2, 0.0, 0.0), 1.3, math.radians(20.0), ws.principled("Monkey", (0.2, 0.5, 0.7), 0.4))
    scenes.uv_sphere(
        scene,
        "Ball",
        center=(2.0, -0.2, 0.7),
        radius=0.7,
        segments=48,
        rings=24,
        mat=ws.principled("Ball", (0.8, 0.8, 0.75), 0.3),
    )
    for poly in scene.objects["Ball"].data.polygons:
        poly.use_smooth = True
    sun = scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(55.0), 0.0, math.radians(30.0)))
    sun.data.angle = math.radians(1.0)
    scenes.look_at(scene, (0.0, -7.0, 2.4), (0.0, 0.0, 0.4), lens=35.0)


def probe_floor(scene):
    polished_floor(scene)
    scenes.plane_probe(scene, "Floor Probe", size=(60.0, 60.0))


def glass_checker(scene):
    ws.uniform_sky(scene, (0.6, 0.7, 0.9), 0.5)
    ground, bsdf, _out = _node_material("Checker")
    checker = ground.node_tree.nodes.new("ShaderNodeTexChecker")
    checker.inputs["Scale"].default_value = 12.0
    checker.inputs["Color1"].default_value = (0.8, 0.8, 0.8, 1.0)
    checker.inputs["Color2"].default_value = (0.05, 0.05, 0.05, 1.0)
    ground.node_tree.links.new(checker.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.6
    scenes.plane(scene, "Ground", size=20.0, mat=ground)
    glass, _bsdf, out = _node_material("Glass")
    node = glass.node_tree.nodes.new("ShaderNodeBsdfGlass")
    node.inputs["IOR"].default_value = 1.45
    node.inputs["Roughness"].default_value = 0.0
    node.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    glass.node_tree.nodes.remove(_bsdf)
    glass.node_tree.links.new(node.outputs[0], out.inputs["Surface"])
    scenes.uv_sphere(scene, "GlassBall", center=(-1.2, 0.0, 1.0), radius=1.0, segments=64, rings=32, mat=glass)
    for poly in scene.objects["GlassBall"].data.polygons:
        poly.use_smooth = True
    clear = scenes.material("Clear", (0.9, 0.95, 1.0), roughness=0.05)
    next(n for n in clear.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled").inputs[
        "Transmission Weight"
    ].default_value = 1.0
    clear.thickness_mode = "SLAB"  # Settings > Thickness Mode, as an EEVEE user sets it for a box
    scenes.box(scene, "ClearCube", center=(1.4, 0.3, 0.7), size=(1.4, 1.4, 1.4), mat=clear)
    sun = scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(40.0), 0.0, math.radians(-30.0)))
    sun.data.angle = math.radians(1.0)
    scenes.look_at(scene, (0.0, -7.5, 3.2), (0.0, 0.0, 0.6), lens=40.0)
    scene["transmission_bounces"] = 8


def _node_material(name):
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:  # Blender 4.5
        mat.use_nodes = True
    nodes = mat.node_tree.nodes
    bsdf = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    out = next(n for n in nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    return mat, bsdf, out


SCENES = {
    "hdri_spheres": hdri_spheres,
    "polished_floor": polished_floor,
    "probe_floor": probe_floor,
    "glass_checker": glass_checker,
}


def build(name, width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT):
    """A new scene ``name`` of SCENES at ``width`` x ``height``."""
    scene = scenes.empty_scene(width, height)
    SCENES[name](scene)
    return scene


def use_engine(scene, engine, **settings):
    """``scene`` set up for ``engine`` ('PENUMBRA', 'EEVEE', 'CYCLES') with ``settings`` of its
    engine's settings; Cycles with one glossy bounce through Penumbra's pixel filter."""
    key = engine.upper()
    if key == "CYCLES":
        bounces = {"max_bounces": 1, "glossy_bounces": 1}
        through = int(scene.get("transmission_bounces", 0))
        if through:  # glass: through it (each interface a bounce), caustics off
            bounces = {
                "max_bounces": through + 1,
                "glossy_bounces": 1,
                "transmission_bounces": through,
                "diffuse_bounces": 0,
                "caustics_refractive": False,
                "caustics_reflective": False,
            }
        engines.configure(scene, "CYCLES", **bounces, **settings, **kit.matched_filter(scene))
    else:
        engines.configure(scene, key, **settings)
    return scene


def render_display(scene):
    return ws.render_display(scene)


def object_mask(name, width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT, objects=None):
    """A boolean mask (h, w), row 0 at the bottom, of the pixels that ``objects`` (names;
    default every object but the ground and floor) cover in scene ``name``: Workbench's flat
    render with those objects white and the rest black."""
    scene = build(name, width, height)
    keep = (
        set(objects)
        if objects is not None
        else {o.name for o in scene.objects if o.type == "MESH"} - {"Ground", "Floor"}
    )
    engines.configure(scene, "WORKBENCH")
    shading = scene.display.shading
    shading.light = "FLAT"
    shading.color_type = "OBJECT"
    shading.show_shadows = False
    shading.show_cavity = False
    shading.show_object_outline = False
    scene.world.color = (0.0, 0.0, 0.0)
    shading.background_type = "WORLD"
    for ob in scene.objects:
        if ob.type == "MESH":
            ob.color = (1.0, 1.0, 1.0, 1.0) if ob.name in keep else (0.0, 0.0, 0.0, 1.0)
    image = ws.render_display(scene)
    return image.mean(axis=2) > 0.5


def object_mae(image, reference, mask):
    """Mean absolute difference of display RGB over the pixels of ``mask``."""
    diff = np.abs(np.asarray(image, np.float64) - np.asarray(reference, np.float64)).mean(axis=2)
    return float(diff[mask].mean())


def source_digest():
    return hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:10]


def cycles_reference(name, samples=256, width=DEFAULT_WIDTH, height=DEFAULT_HEIGHT, cache_dir=CACHE):
    """Display RGB (h, w, 3), row 0 at the bottom, of Cycles with one glossy bounce on scene
    ``name`` at ``samples`` spp (seed 1): from the cache when there, else rendered and cached."""
    major, minor = bpy.app.version[:2]
    key = f"reflect-{name}-{samples}spp-{width}x{height}-blender{major}.{minor}-{source_digest()}.npy"
    path = Path(cache_dir) / key
    if path.exists():
        return np.load(path)
    scene = build(name, width, height)
    use_engine(scene, "CYCLES", samples=samples, seed=1)
    image = render_display(scene)
    kit.save_npy(path, image)
    return image
