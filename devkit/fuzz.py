"""Random scenes for the render-ends fuzz test (tests/blender/test_render_ends.py) and
``python -m tools.fuzz``: meshes at scales 1e-3 to 1e2 (non-uniform and degenerate ones among
them), lights of every type and size (0 included), node trees with extreme linked and unlinked
inputs, alpha from constants, nodes and image textures, hashed and blended. Every scene is a
pure function of its seed; ``describe`` says what a seed built, so a failing seed can be
rebuilt and saved (``tools.fuzz --seed N --save scene.blend``).

The scenes' inputs are non-negative where Blender's engines read them as light (colours,
strengths), so every frame they make must be finite and >= 0 (the suite's light check)."""

import math

import bpy
import numpy as np

from devkit import scenes

SHAPES = ("box", "sphere", "monkey", "cone", "plane", "sliver")
LIGHTS = ("POINT", "SPOT", "AREA", "SUN")
# Where a material's alpha comes from. Node shapes are few (each is one compiled program); their
# constants are drawn per scene (constants are uniforms: equal trees share a program).
ALPHA_SOURCES = ("opaque", "constant", "fresnel", "noise", "voronoi", "math", "image", "ramp")
EXTREMES = (0.0, 1e-30, 1e-6, 1.0, 1e6, 1e30, -1e30)


def _principled(mat):
    return next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")


def _set(node, names, value):
    """Set the first of ``names`` the node has (input names differ between Blender lines)."""
    for name in names:
        if name in node.inputs:
            node.inputs[name].default_value = value
            return


def _set_render_method(mat, blended):
    if hasattr(mat, "surface_render_method"):
        mat.surface_render_method = "BLENDED" if blended else "DITHERED"
    if hasattr(mat, "blend_method"):
        try:
            mat.blend_method = "BLEND" if blended else "HASHED"
        except (TypeError, AttributeError):
            pass


def _image(rng, name):
    """A small RGBA image whose alpha varies (0 to 1 across it, with a hole of exactly 0)."""
    size = int(rng.choice((1, 4, 16)))
    img = bpy.data.images.new(name, size, size, alpha=True, float_buffer=bool(rng.integers(2)))
    px = rng.random((size, size, 4)).astype(np.float32)
    px[0, 0, 3] = 0.0
    img.pixels.foreach_set(px.ravel())
    img.pack()
    return img


def _alpha_tree(rng, mat, source, desc):
    nt = mat.node_tree
    bsdf = _principled(mat)
    alpha = bsdf.inputs["Alpha"]
    if source == "constant":
        value = float(rng.choice((0.0, 1e-6, 0.5, 0.999)))
        alpha.default_value = value
        desc["alpha"] = value
        return
    if source == "fresnel":
        fres = nt.nodes.new("ShaderNodeFresnel")
        fres.inputs["IOR"].default_value = float(rng.choice((1.0, 1.5, 1e6, 0.0)))
        nt.links.new(fres.outputs["Fac"], alpha)
        desc["fresnel_ior"] = fres.inputs["IOR"].default_value
    elif source == "noise":
        tex = nt.nodes.new("ShaderNodeTexNoise")
        tex.inputs["Detail"].default_value = float(rng.choice((0.0, 15.0, 1e30)))
        tex.inputs["Scale"].default_value = float(rng.choice((0.0, 5.0, 1e30, -1e30)))
        _set(tex, ("Lacunarity",), float(rng.choice((0.0, 2.0, 1e30))))
        nt.links.new(tex.outputs["Fac"], alpha)
        desc["noise"] = [tex.inputs[n].default_value for n in ("Detail", "Scale")]
    elif source == "voronoi":
        tex = nt.nodes.new("ShaderNodeTexVoronoi")
        tex.feature = str(rng.choice(("F1", "SMOOTH_F1", "DISTANCE_TO_EDGE")))
        tex.inputs["Scale"].default_value = float(rng.choice((0.0, 5.0, 1e30)))
        _set(tex, ("Detail",), float(rng.choice((0.0, 15.0, 1e30))))
        _set(tex, ("Randomness",), float(rng.choice((0.0, 1.0, 1e30))))
        nt.links.new(tex.outputs["Distance"], alpha)
        desc["voronoi"] = [tex.feature, tex.inputs["Scale"].default_value]
    elif source == "math":
        # Extreme constants through Math and Mix, clamped to [0, 1] by the Math node.
        coord = nt.nodes.new("ShaderNodeTexCoord")
        sep = nt.nodes.new("ShaderNodeSeparateXYZ")
        math_node = nt.nodes.new("ShaderNodeMath")
        math_node.operation = str(rng.choice(("DIVIDE", "POWER", "LOGARITHM", "MULTIPLY", "SQRT", "MODULO")))
        math_node.inputs[1].default_value = float(rng.choice(EXTREMES))
        math_node.use_clamp = True
        nt.links.new(coord.outputs["Object"], sep.inputs[0])
        nt.links.new(sep.outputs[0], math_node.inputs[0])
        nt.links.new(math_node.outputs[0], alpha)
        desc["math"] = [math_node.operation, math_node.inputs[1].default_value]
    elif source == "image":
        tex = nt.nodes.new("ShaderNodeTexImage")
        tex.image = _image(rng, f"{mat.name}_alpha")
        tex.extension = str(rng.choice(("REPEAT", "EXTEND", "CLIP", "MIRROR")))
        tex.interpolation = str(rng.choice(("Linear", "Closest", "Cubic")))
        coord = nt.nodes.new("ShaderNodeTexCoord")
        nt.links.new(coord.outputs["Generated"], tex.inputs["Vector"])
        nt.links.new(tex.outputs["Alpha"], alpha)
        nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
        desc["image"] = [tex.image.size[0], tex.extension, tex.interpolation]
    elif source == "ramp":
        # The repro's shape: coordinates through Brick and White Noise, an extreme Mix factor,
        # into Fresnel's normal, then a ColorRamp.
        coord = nt.nodes.new("ShaderNodeTexCoord")
        brick = nt.nodes.new("ShaderNodeTexBrick")
        brick.inputs["Scale"].default_value = float(rng.choice((-1.0, 0.0, 5.0, 1e30)))
        brick.inputs["Mortar Size"].default_value = float(rng.choice((0.0, 0.02, 1e6)))
        noise = nt.nodes.new("ShaderNodeTexWhiteNoise")
        mix = nt.nodes.new("ShaderNodeMix")
        mix.data_type = "RGBA"
        mix.inputs["Factor"].default_value = float(rng.choice(EXTREMES))
        fres = nt.nodes.new("ShaderNodeFresnel")
        ramp = nt.nodes.new("ShaderNodeValToRGB")
        nt.links.new(coord.outputs["Object"], brick.inputs["Vector"])
        nt.links.new(brick.outputs["Color"], noise.inputs["Vector"])
        nt.links.new(noise.outputs["Color"], mix.inputs[6])
        nt.links.new(mix.outputs[2], fres.inputs["Normal"])
        nt.links.new(fres.outputs["Fac"], ramp.inputs["Fac"])
        nt.links.new(ramp.outputs["Alpha"], alpha)
        desc["ramp"] = [brick.inputs["Scale"].default_value, mix.inputs["Factor"].default_value]


def _material(form, rng, name, desc):
    color = tuple(float(x) for x in rng.random(3))
    mat = scenes.material(name, color, roughness=float(rng.choice((0.0, 0.05, 0.5, 1.0))))
    bsdf = _principled(mat)
    bsdf.inputs["Metallic"].default_value = float(rng.choice((0.0, 1.0)))
    _set(bsdf, ("IOR",), float(rng.choice((1.0, 1.5, 1e3))))
    source = str(form.choice(ALPHA_SOURCES))
    desc.update(material=name, color=color, alpha_source=source)
    if form.random() < 0.2:
        _set(bsdf, ("Emission Color", "Emission"), (*color, 1.0))
        _set(bsdf, ("Emission Strength",), float(rng.choice((0.0, 1.0, 1e4))))
        desc["emission"] = True
    if source != "opaque":
        blended = bool(form.integers(2))
        _set_render_method(mat, blended)
        desc["blended"] = blended
        _alpha_tree(rng, mat, source, desc)
    return mat


def _mesh(form, rng, scene, i, reach):
    shape = str(form.choice(SHAPES))
    name = f"Mesh{i}_{shape}"
    desc = {"shape": shape}
    if shape == "box":
        ob = scenes.box(scene, name)
    elif shape == "sphere":
        ob = scenes.uv_sphere(scene, name, segments=12, rings=6)
    elif shape == "monkey":
        ob = _monkey(scene, name)
    elif shape == "cone":
        ob = _cone(scene, name)
    elif shape == "plane":
        ob = scenes.plane(scene, name, size=2.0)
    else:  # zero-area and collapsed triangles beside a thin one
        verts = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 0, 0), (0, 0, 0), (1, 1e-7, 0), (0, 1, 0)]
        ob = scenes.mesh_object(scene, name, verts, [(0, 1, 2), (3, 4, 0), (0, 5, 6)])
    scale = 10.0 ** rng.uniform(-3.0, 2.0)
    spread = (10.0 ** rng.uniform(-1.0, 1.0, 3)) if rng.random() < 0.4 else np.ones(3)
    ob.scale = tuple(float(x) for x in scale * spread)
    ob.location = tuple(float(x) for x in rng.normal(0.0, 0.5, 3) * reach)
    ob.rotation_euler = tuple(float(x) for x in rng.uniform(-math.pi, math.pi, 3))
    desc.update(scale=list(ob.scale), location=list(ob.location))
    mat_desc = {}
    ob.data.materials.append(_material(form, rng, f"M{i}", mat_desc))
    desc["material"] = mat_desc
    return desc


def _light(form, rng, scene, i, reach):
    kind = str(form.choice(LIGHTS))
    energy = (
        float(rng.choice((0.0, 1e-3, 1.0, 100.0, 5711.0, 1e5)))
        if kind != "SUN"
        else float(rng.choice((0.0, 1.0, 20.0)))
    )
    location = tuple(float(x) for x in rng.normal(0.0, 1.0, 3) * reach)
    ob = scenes.light(scene, f"L{i}_{kind}", kind, energy, location=location, use_shadow=bool(form.random() < 0.8))
    data = ob.data
    size = float(rng.choice((0.0, 1e-4, 0.25, 1.0, 5.0))) * reach
    desc = {"type": kind, "energy": energy, "location": list(location), "shadow": data.use_shadow}
    if kind == "SUN":
        data.angle = float(rng.choice((0.0, 0.01, 0.5, math.pi)))
        desc["angle"] = data.angle
    elif kind == "AREA":
        data.shape = str(rng.choice(("SQUARE", "RECTANGLE", "DISK", "ELLIPSE")))
        data.size, data.size_y = size, float(rng.choice((0.0, 1.0, 4.6))) * reach
        if hasattr(data, "spread"):
            data.spread = float(rng.choice((0.01, 1.0, math.pi)))
        desc.update(shape=data.shape, size=[data.size, data.size_y])
    else:
        data.shadow_soft_size = size
        desc["radius"] = size
        if kind == "SPOT":
            data.spot_size = float(rng.choice((0.01, 1.0, math.pi)))
            data.spot_blend = float(rng.choice((0.0, 0.15, 1.0)))
            desc["spot"] = [data.spot_size, data.spot_blend]
    scenes.aim(ob, (0.0, 0.0, 0.0))
    return desc


def random_scene(seed, size=(24, 16), form=None):
    """Scene ``seed`` at ``size`` pixels; returns (scene, its description: a JSON-able dict).
    ``form`` (a seed, default ``seed``) draws what decides the programs a frame compiles: the
    meshes' shapes, the materials' alpha sources and modes, the lights' types and shadows, the
    shadow filter, the sample count, the film; ``seed`` draws every value (scales, positions,
    energies, sizes, extreme constants, the camera). Scenes of one form share most programs,
    so a suite can render many values for the cost of a few compiles."""
    rng = np.random.default_rng(seed)
    form_seed = seed if form is None else form
    form = rng if form is None else np.random.default_rng([form_seed, 1])  # one stream: its own form
    scene = scenes.empty_scene(*size)
    reach = 10.0 ** rng.uniform(-3.0, 2.0)  # the scene's size: tiny to huge
    desc = {"seed": int(seed), "form": int(form_seed), "reach": reach, "meshes": [], "lights": []}
    world = float(rng.choice((0.0, 0.05, 1.0)))
    scenes.set_world(scene, (world,) * 3)
    desc["world"] = world
    for i in range(int(form.integers(1, 4))):
        desc["meshes"].append(_mesh(form, rng, scene, i, reach))
    for i in range(int(form.integers(0, 4))):
        desc["lights"].append(_light(form, rng, scene, i, reach))
    distance = reach * float(rng.choice((0.5, 3.0, 30.0)))
    lens = float(rng.choice((12.0, 50.0, 122.0, 400.0)))
    direction = rng.normal(0.0, 1.0, 3)
    direction /= max(float(np.linalg.norm(direction)), 1e-9)
    cam = scenes.look_at(scene, tuple(float(x) for x in direction * distance), (0.0, 0.0, 0.0), lens=lens)
    cam.data.clip_start = distance * 1e-3
    cam.data.clip_end = distance * 1e3
    if form.random() < 0.2:
        cam.data.type = "ORTHO"
        cam.data.ortho_scale = 2.0 * reach
    opts = scene.penumbra
    opts.shadow_filter = str(form.choice(("NONE", "HARDWARE", "PCF", "JITTER", "PCSS")))
    opts.shadow_map_size = int(rng.choice((64, 256)))
    opts.render_samples = int(form.choice((1, 2, 4)))
    scene.render.film_transparent = bool(form.random() < 0.2)
    desc.update(
        camera={"distance": distance, "lens": lens, "type": cam.data.type},
        filter=opts.shadow_filter,
        map=opts.shadow_map_size,
        samples=opts.render_samples,
        transparent=scene.render.film_transparent,
    )
    return scene, desc


def _monkey(scene, name):
    import bmesh

    me = bpy.data.meshes.new(name)
    bm = bmesh.new()
    bmesh.ops.create_monkey(bm)
    bm.to_mesh(me)
    bm.free()
    return scenes.link(scene, bpy.data.objects.new(name, me))


def _cone(scene, name, segments=16):
    ring = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    verts = [(math.cos(a), math.sin(a), -1.0) for a in ring] + [(0.0, 0.0, 1.0)]
    faces = [(k, (k + 1) % segments, segments) for k in range(segments)] + [tuple(range(segments - 1, -1, -1))]
    return scenes.mesh_object(scene, name, verts, faces)


def transparent_hang_scene(width=64, height=36, alpha_linked=True):
    """The scene that once never finished a frame, rebuilt in code: a tiny, non-uniformly scaled
    Suzanne whose alpha comes from a Fresnel node (hashed), a small cone, an area light of
    5,711 W (3.5 x 4.6 m, spread 180 degrees) and two point lights, a 122 mm camera, 16 samples.
    ``alpha_linked`` False unlinks the alpha (the same scene, opaque): its baseline."""
    scene = scenes.empty_scene(width, height)
    scenes.set_world(scene, (0.05, 0.05, 0.05))
    scene.penumbra.render_samples = 16
    suzanne = _monkey(scene, "Suzanne")
    suzanne.location = (-3.4094, -1.1874, 2.2466)
    suzanne.rotation_euler = (0.4418, -2.5749, -1.3218)
    suzanne.scale = (0.005347, 0.0014595, 0.00090477)
    mat = scenes.material("Suzanne", (0.1253, 0.2467, 0.6451), roughness=0.8115)
    _set_render_method(mat, blended=False)
    if alpha_linked:
        nt = mat.node_tree
        fres = nt.nodes.new("ShaderNodeFresnel")
        nt.links.new(fres.outputs["Fac"], _principled(mat).inputs["Alpha"])
    suzanne.data.materials.append(mat)
    cone = _cone(scene, "Cone", segments=32)
    cone.location = (1.4655, -2.4578, -2.7091)
    cone.rotation_euler = (-2.1443, -2.9221, 0.7566)
    cone.scale = (0.14259, 0.19606, 0.29303)
    cone.data.materials.append(scenes.material("Cone", (0.658, 0.2494, 0.4497), roughness=0.3107))
    area = scenes.light(
        scene, "Area", "AREA", 5711.6, location=(-1.9485, 0.7681, 3.5012), rotation=(-3.0834, -3.0568, 1.02)
    )
    area.data.shape = "RECTANGLE"
    area.data.size, area.data.size_y = 3.4856, 4.5472
    if hasattr(area.data, "spread"):
        area.data.spread = math.pi
    scenes.light(scene, "Point", "POINT", 17.276, location=(-6.8362, -3.9591, -0.9414), shadow_soft_size=0.0)
    scenes.light(scene, "Point.001", "POINT", 0.11874, location=(3.1671, -7.1253, 2.4658), shadow_soft_size=1.1898)
    cam = scenes.camera(scene, (-11.1257, 5.8142, 12.3118), (0.7951, 0.0, -2.0524), lens=121.835)
    cam.data.sensor_width = 36.0
    return scene
