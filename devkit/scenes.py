"""Scenes built in code (no binary .blend files): the demo and the test scenes.

Every ``*_scene`` builder starts from an empty factory scene and returns it; the other
functions add objects, materials, lights and cameras to a given scene.
"""

import math

import bpy
import numpy as np
from mathutils import Vector

WHITE_ALBEDO = 0.8  # albedo of white(): the Lambertian white of the shadow and light-unit scenes


def empty_scene(width=320, height=180, engine="PENUMBRA"):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = engine
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.dither_intensity = 0.0
    if hasattr(scene, "penumbra"):
        # Scenes start from one sample (the single-sample frame most tests measure); the
        # sampling tests and tools that compare samples set their own counts.
        scene.penumbra.render_samples = 1
        scene.penumbra.viewport_samples = 1
    scene.world = bpy.data.worlds.new("World")
    set_world(scene, (0.0, 0.0, 0.0))
    return scene


def set_world(scene, color):
    world = scene.world
    world.use_nodes = True
    bg = next(n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    bg.inputs["Color"].default_value = (*color, 1.0)
    bg.inputs["Strength"].default_value = 1.0
    world.color = color


def material(name, color, roughness=0.5, specular=0.5, metallic=0.0):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    spec = "Specular IOR Level" if "Specular IOR Level" in bsdf.inputs else "Specular"
    bsdf.inputs[spec].default_value = specular
    bsdf.inputs["Metallic"].default_value = metallic
    mat.diffuse_color = (*color, 1.0)
    return mat


def emissive(name="Glow", strength=1.0):
    """A black Principled BSDF emitting white at ``strength``: it shows its own light alone."""
    mat = material(name, (0.0, 0.0, 0.0), specular=0.0)
    bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Emission Color" if "Emission Color" in bsdf.inputs else "Emission"].default_value = (1, 1, 1, 1)
    if "Emission Strength" in bsdf.inputs:
        bsdf.inputs["Emission Strength"].default_value = strength
    return mat


def white(name="White", albedo=WHITE_ALBEDO):
    """A purely diffuse grey material: albedo / pi, no specular reflection."""
    return material(name, (albedo,) * 3, roughness=1.0, specular=0.0)


def smooth_monkey_mesh(name):
    """bmesh's monkey subdivided once and smooth-shaded (about 3,900 triangles), facing -Y."""
    import bmesh

    me = bpy.data.meshes.new(name)
    bm = bmesh.new()
    bmesh.ops.create_monkey(bm)
    bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=1, use_grid_fill=True, smooth=1.0)
    bmesh.ops.triangulate(bm, faces=[f for f in bm.faces if len(f.verts) > 4])
    bm.to_mesh(me)
    bm.free()
    for poly in me.polygons:
        poly.use_smooth = True
    return me


def link(scene, ob):
    scene.collection.objects.link(ob)
    return ob


def mesh_object(scene, name, verts, faces, location=(0, 0, 0), mat=None):
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.update()
    ob = link(scene, bpy.data.objects.new(name, me))
    ob.location = location
    if mat is not None:
        me.materials.append(mat)
    return ob


def mix_with(mat, kind, fac=0.5, inputs=None):
    """``mat``'s Principled BSDF mixed with a new shader node of ``kind`` (its ``inputs``
    {name: value} set) by a Mix Shader of factor ``fac`` (the new node's share) into the output;
    returns the new node."""
    tree = mat.node_tree
    other = tree.nodes.new(kind)
    for name, value in (inputs or {}).items():
        other.inputs[name].default_value = value
    mix = tree.nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = fac
    out = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    tree.links.new(tree.nodes["Principled BSDF"].outputs[0], mix.inputs[1])
    tree.links.new(other.outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], out.inputs["Surface"])
    return other


def plane(scene, name="Plane", size=10.0, z=0.0, mat=None):
    h = size / 2.0
    return mesh_object(scene, name, [(-h, -h, z), (h, -h, z), (h, h, z), (-h, h, z)], [(0, 1, 2, 3)], mat=mat)


def box(scene, name="Box", center=(0, 0, 0), size=(1, 1, 1), mat=None):
    sx, sy, sz = (s / 2.0 for s in size)
    verts = [(x, y, z) for z in (-sz, sz) for y in (-sy, sy) for x in (-sx, sx)]
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return mesh_object(scene, name, verts, faces, location=center, mat=mat)


def plane_probe(scene, name="Mirror Probe", location=(0, 0, 0), size=(1.0, 1.0), distance=0.1, clip=0.001):
    """A Plane Light Probe (a planar reflection) at ``location``, its square ``size`` (X, Y)
    across, Influence Distance ``distance`` and Clipping Offset ``clip``."""
    data = bpy.data.lightprobes.new(name, "PLANE")
    data.influence_distance = distance
    data.clip_start = clip
    ob = bpy.data.objects.new(name, data)
    ob.location = location
    ob.scale = (size[0] / 2.0, size[1] / 2.0, 1.0)
    return link(scene, ob)


def box_over_plane(scene, plane_size=10.0, box_center=(0, 0, 1.5), box_size=1.0, mat=None):
    """A square plane of side ``plane_size`` at z = 0 (object "Plane") and a cube of side
    ``box_size`` centred at ``box_center`` (object "Box"), both with ``mat`` (default: a new
    ``white()``). The analytic shadow of the box is a ray-box test (``devkit.analytic``).
    Returns (plane, box)."""
    mat = white() if mat is None else mat
    ground = plane(scene, "Plane", size=plane_size, mat=mat)
    caster = box(scene, "Box", center=box_center, size=(box_size,) * 3, mat=mat)
    return ground, caster


def uv_sphere(scene, name="Sphere", center=(0, 0, 0), radius=1.0, segments=32, rings=16, mat=None, uvs=False):
    """A smooth UV sphere built in one fixed order (``bpy.ops.mesh.primitive_uv_sphere_add``
    orders its faces differently in every Blender process, so a scene built with it does not
    rasterise the same to the last bit twice). ``uvs``: with a UV map "UVMap" laid out as
    Blender's (u around from 0 to 1, a seam at u = 1; v from 0 at the bottom pole to 1)."""
    verts = [(0, 0, radius)]
    for r in range(1, rings):
        theta = math.pi * r / rings
        for s in range(segments):
            phi = 2 * math.pi * s / segments
            verts.append(
                (
                    radius * math.sin(theta) * math.cos(phi),
                    radius * math.sin(theta) * math.sin(phi),
                    radius * math.cos(theta),
                )
            )
    verts.append((0, 0, -radius))
    faces = []
    for s in range(segments):
        faces.append((0, 1 + s, 1 + (s + 1) % segments))
    for r in range(rings - 2):
        a = 1 + r * segments
        b = a + segments
        for s in range(segments):
            faces.append((a + s, b + s, b + (s + 1) % segments, a + (s + 1) % segments))
    last = len(verts) - 1
    a = 1 + (rings - 2) * segments
    for s in range(segments):
        faces.append((a + (s + 1) % segments, a + s, last))
    ob = mesh_object(scene, name, verts, faces, location=center, mat=mat)
    for poly in ob.data.polygons:
        poly.use_smooth = True
    if uvs:
        last = len(verts) - 1

        def corner_uv(face, k):
            v = face[k]
            if v in (0, last):  # a pole: the middle of its triangle's segment
                others = [face[j] for j in range(len(face)) if face[j] not in (0, last)]
                seg = min((o - 1) % segments for o in others)
                if {(o - 1) % segments for o in others} == {0, segments - 1}:
                    seg = segments - 1
                return ((seg + 0.5) / segments, 1.0 if v == 0 else 0.0)
            ring, seg = divmod(v - 1, segments)
            # The face's last segment wraps to 0: it reads u = 1 there (the seam).
            wraps = any((face[j] - 1) % segments == segments - 1 for j in range(len(face)) if face[j] not in (0, last))
            u = 1.0 if seg == 0 and wraps else seg / segments
            return (u, 1.0 - (ring + 1) / rings)

        coords = [corner_uv(face, k) for face in faces for k in range(len(face))]
        ob.data.uv_layers.new(name="UVMap").data.foreach_set("uv", [c for uv in coords for c in uv])
    return ob


def light(scene, name, kind, energy, location=(0, 0, 0), rotation=(0, 0, 0), color=(1, 1, 1), **props):
    data = bpy.data.lights.new(name, kind)
    data.energy = energy
    data.color = color
    for k, v in props.items():
        setattr(data, k, v)
    ob = link(scene, bpy.data.objects.new(name, data))
    ob.location = location
    ob.rotation_euler = rotation
    return ob


def aim(ob, target):
    """Point a camera or a spot/area/sun light (they look along their local -Z) at ``target``."""
    direction = Vector(target) - ob.location
    ob.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()


def camera(scene, location, rotation, lens=50.0, ortho_scale=None, clip=(0.1, 100.0)):
    data = bpy.data.cameras.new("Camera")
    data.lens = lens
    data.clip_start, data.clip_end = clip
    if ortho_scale is not None:
        data.type = "ORTHO"
        data.ortho_scale = ortho_scale
    ob = link(scene, bpy.data.objects.new("Camera", data))
    ob.location = location
    ob.rotation_euler = rotation
    scene.camera = ob
    return ob


def top_camera(scene, height=20.0, ortho_scale=10.0):
    """Orthographic camera looking straight down, framing [-s/2, s/2]^2 of the z=0 plane."""
    return camera(scene, (0, 0, height), (0, 0, 0), ortho_scale=ortho_scale, clip=(0.1, 2 * height))


def look_at(scene, location, target, lens=35.0):
    """A perspective camera at ``location`` looking at ``target`` (world up stays up)."""
    rotation = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    return camera(scene, tuple(location), tuple(rotation), lens=lens, clip=(0.1, 100.0))


def triangle_count(scene):
    """Triangles of every evaluated mesh instance in the scene (modifiers and instancing applied)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    total = 0
    for instance in depsgraph.object_instances:
        ob = instance.object
        if ob.type != "MESH":
            continue
        mesh = ob.to_mesh()
        try:
            mesh.calc_loop_triangles()
            total += len(mesh.loop_triangles)
        finally:
            ob.to_mesh_clear()
    return total


def demo_scene(width=640, height=360):
    """Several objects, a sun and a spot light, two post layers."""
    scene = empty_scene(width, height)
    set_world(scene, (0.05, 0.06, 0.08))
    plane(scene, "Ground", size=14.0, mat=material("Ground", (0.75, 0.72, 0.68), roughness=0.8))
    box(
        scene,
        "Crate",
        center=(-1.6, 0.4, 0.75),
        size=(1.5, 1.5, 1.5),
        mat=material("Crate", (0.8, 0.35, 0.12), roughness=0.6),
    )
    uv_sphere(
        scene,
        "Ball",
        center=(0.9, -0.6, 1.0),
        radius=1.0,
        mat=material("Ball", (0.2, 0.45, 0.85), roughness=0.25, specular=0.6),
    )
    pillar = box(
        scene,
        "Pillar",
        center=(2.8, 1.8, 1.5),
        size=(0.5, 0.5, 3.0),
        mat=material("Pillar", (0.85, 0.85, 0.85), roughness=0.4),
    )
    pillar.rotation_euler = (0, 0, math.radians(30))
    box(
        scene,
        "Slab",
        center=(-0.5, 2.8, 0.15),
        size=(2.5, 1.0, 0.3),
        mat=material("Slab", (0.3, 0.7, 0.35), roughness=0.7),
    )
    light(
        scene,
        "Sun",
        "SUN",
        3.0,
        rotation=(math.radians(40), math.radians(15), math.radians(-35)),
        angle=math.radians(2),
    )
    light(
        scene,
        "Spot",
        "SPOT",
        600.0,
        location=(-3.5, -3.0, 5.0),
        rotation=(math.radians(40), 0, math.radians(-50)),
        color=(1.0, 0.85, 0.65),
        spot_size=math.radians(55),
        spot_blend=0.3,
        shadow_soft_size=0.2,
    )
    camera(scene, (7.5, -8.5, 6.0), (math.radians(62), 0, math.radians(41)), lens=35.0)
    s = scene.penumbra
    s.layers.clear()
    blur = s.layers.add()
    blur.effect, blur.name, blur.mix = "BLUR", "Soft focus", 0.25
    blur.blur.radius = 3
    vig = s.layers.add()
    vig.effect, vig.name = "VIGNETTE", "Vignette"
    vig.vignette.radius, vig.vignette.softness = 0.9, 0.8
    return scene


def bare_demo(width, height):
    """The demo scene without its post layers and with every sample in every pixel (Noise
    Threshold 0): what a frame's samples cost and draw, counted sample by sample."""
    scene = demo_scene(width, height)
    scene.penumbra.layers.clear()
    scene.penumbra.adaptive_threshold = 0.0
    return scene


def textured_asset(width=160, height=90, texels=2048, seed=7):
    """A scanned-asset-like object as glTF's importer builds one (a DamagedHelmet stand-in):
    a smooth mesh of about 16k triangles whose Principled BSDF reads four ``texels``² images
    (Base Color and Emission in sRGB; metallic-roughness through Separate Color and a normal
    map, Non-Color) with a fifth, occlusion, in an Image Texture node nothing reads; a sun and
    a point light on a ground. The images are smooth noise made here, so nothing is downloaded."""
    scene = empty_scene(width, height)
    set_world(scene, (0.05, 0.05, 0.06))
    plane(scene, "Ground", size=10.0, mat=material("Ground", (0.5, 0.5, 0.5), roughness=0.7))
    rng = np.random.default_rng(seed)

    def image(name, colorspace, channels):
        coarse = rng.random((33, 33, channels), dtype=np.float32)
        # Bilinear upsampling of a coarse grid: smooth detail at every scale above a texel.
        t = np.linspace(0.0, 32.0, texels, dtype=np.float32)
        i = np.minimum(t.astype(np.int32), 31)
        f = (t - i)[:, None]
        rows = coarse[i] * (1.0 - f[..., None]) + coarse[i + 1] * f[..., None]
        grid = rows[:, i] * (1.0 - f[None, :, :]) + rows[:, i + 1] * f[None, :, :]
        grain = rng.random((texels, texels, 1), dtype=np.float32) * 0.1
        rgba = np.ones((texels, texels, 4), np.float32)
        rgba[..., :3] = np.clip(grid[..., :3] * 0.9 + grain, 0.0, 1.0) if channels >= 3 else grid[..., :1]
        img = bpy.data.images.new(name, texels, texels, alpha=True)
        img.pixels.foreach_set(rgba.ravel())
        img.colorspace_settings.name = colorspace
        img.pack()
        return img

    mat = bpy.data.materials.new("Asset")
    if bpy.app.version < (5, 0, 0):
        mat.use_nodes = True
    tree = mat.node_tree
    bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")

    def texture(name, colorspace, channels=3):
        node = tree.nodes.new("ShaderNodeTexImage")
        node.image = image(name, colorspace, channels)
        return node

    tree.links.new(texture("base_color", "sRGB").outputs["Color"], bsdf.inputs["Base Color"])
    separate = tree.nodes.new("ShaderNodeSeparateColor")
    tree.links.new(texture("metallic_roughness", "Non-Color").outputs["Color"], separate.inputs["Color"])
    tree.links.new(separate.outputs["Green"], bsdf.inputs["Roughness"])
    tree.links.new(separate.outputs["Blue"], bsdf.inputs["Metallic"])
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    tree.links.new(texture("normal", "Non-Color").outputs["Color"], normal_map.inputs["Color"])
    tree.links.new(normal_map.outputs["Normal"], bsdf.inputs["Normal"])
    emission = "Emission Color" if "Emission Color" in bsdf.inputs else "Emission"
    tree.links.new(texture("emissive", "sRGB").outputs["Color"], bsdf.inputs[emission])
    if "Emission Strength" in bsdf.inputs:
        bsdf.inputs["Emission Strength"].default_value = 0.2
    texture("occlusion", "Non-Color")  # glTF keeps occlusion beside the shader, unread
    uv_sphere(scene, "Sphere", (0.0, 0.0, 1.1), 1.0, segments=128, rings=64, mat=mat, uvs=True)
    light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(40), 0.0, math.radians(30)), angle=math.radians(1.0))
    light(scene, "Point", "POINT", 300.0, location=(-2.5, -2.0, 3.0), shadow_soft_size=0.1)
    look_at(scene, (0.0, -4.5, 2.2), (0.0, 0.0, 1.0), lens=40.0)
    return scene
