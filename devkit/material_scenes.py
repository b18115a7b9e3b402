"""Material test scenes built in code: each one shows ONE thing an artist sets up in Blender
that a render engine has to honour (textures, colour attributes, emission, alpha, normal maps,
metals, the world, light colour, object visibility, hair).

Every builder takes ``(width, height)``, starts from ``devkit.scenes.empty_scene``, adds a
camera, a light (none in ``world_hdri``) and its one feature, and returns the scene. Images are
generated with numpy and packed, so a saved .blend carries them. Unless a builder says
otherwise the world is a dim grey (``WORLD``), the sun has ``SUN_STRENGTH`` W/m² and surfaces
are Lambertian (Principled BSDF, Roughness 1, Specular IOR Level 0), so every scene is well
exposed under the 'Standard' view transform.

texture_base_color    plane filling the frame (top orthographic camera, sun straight down);
                      a 64x64 sRGB byte image, 4x4 checker of CHECKER_A / CHECKER_B (cell (0, 0)
                      at the plane's -x -y corner is A) -> Image Texture (Vector unlinked: the
                      mesh's UV map "UVMap", uv = (x, y) mapped to [0, 1]) -> Base Color
texture_closest_clip  the same plane; a 4x4-pixel checker (one pixel a cell), interpolation
                      'Closest', extension 'CLIP'; Texture Coordinate UV -> Mapping (Point,
                      Scale 2, Location -0.5) -> Vector, so the image covers the middle half
                      of the plane and the border (outside the image) is black
color_attribute       plane whose corners carry the BYTE_COLOR corner attribute "Col": red,
                      green, blue, white at (-x -y), (+x -y), (+x +y), (-x +y); Color Attribute
                      node -> Base Color
emission              sphere, Principled Emission Color (1, 0.5, 0.2), Strength 2; a dim sun
emission_shader       sphere, an Emission node (0.2, 0.6, 1.0), Strength 1, into the output
diffuse_bsdf          sphere, a Diffuse BSDF (0.2, 0.6, 0.3), Roughness 0, into the output
rgb_node              sphere, an RGB node (0.8, 0.2, 0.6) -> Principled Base Color
mix_shader            sphere, Mix Shader (Factor 0.5) of a Principled (0.2, 0.4, 0.8) and a
                      Glossy BSDF (0.9, 0.9, 0.9, Roughness 0.2)
alpha_quarter         red plane (Alpha 0.25, default render method 'DITHERED') at z = 1 over
                      a blue ground; top camera, sun straight down
alpha_blend           the same with surface_render_method = 'BLENDED'
alpha_checker_shadow  plane at z = 1 with a 128x128 sRGB image (extension 'EXTEND') whose ALPHA
                      is a 4x4 checker of 1 / 0 (Color -> Base Color, Alpha -> Alpha, the
                      render method left at 'DITHERED'), sun straight down, a white
                      ground at z = 0. The orthographic camera looks straight down from z = 0.5,
                      between the two, so it sees the ground and the shadow pattern only. The
                      geometry is in scene custom properties (see ``alpha_checker_shadow``)
normal_map            white plane; a constant Non-Color float image, the tangent-space normal
                      (0, sin 30°, cos 30°) (tilted 30° about the U axis, towards +V = +y) ->
                      Normal Map node (Tangent space, "UVMap") -> Principled Normal; the sun
                      shines from (0, 1, 1)/√2, so the tilt lifts N·L from cos 45° to cos 15°
metal_grid            4x4 smooth UV spheres, base colour (0.8, 0.6, 0.3); rows (top to bottom)
                      Metallic 0, 0.33, 0.67, 1; columns (left to right) Roughness 0.1, 0.3,
                      0.6, 1; world Background white at Strength 0.5 plus one sun; 256x256
world_hdri            white sphere; world Background Color from an Environment Texture of a
                      64x32 float image: top half sky (0.6, 1.0, 2.0), bottom half ground
                      (0.4, 0.3, 0.2); no lights
light_temperature     white plane under a sun of strength 1 with use_temperature = True,
                      temperature = 2000 K (mostly red: strength 3 would clip)
visibility            four things over a ground under a slanted sun: "NoCamera" (cube,
                      visible_camera False: only its shadow shows), "NoShadow" (cube,
                      visible_shadow False), "Holdout" (sphere, is_holdout True), "Emitter" (a
                      plane whose EMITTER particle system instances the cube "Instance",
                      itself hide_render; show_instancer_for_render False, so only the 16
                      instances show)
hair                  sphere with a HAIR particle system (300 strands), and next to it a
                      Curves (hair) object of 49 strands where ``bpy.data.hair_curves`` exists
noise_texture,        the sphere (as emission_shader: a sun from the upper left, the dim
voronoi_texture,      world) with a compiled procedural tree on Generated coordinates: Noise
wave_texture,         Color (Scale 4, Detail 4) -> Base Color; Voronoi F1 Color -> Base Color and
brick_texture,        its Distance -> Roughness; Wave bands (Scale 3, Distortion 4) Color -> Base
magic_texture,        Color; Brick (Scale 4) -> Base Color; Magic (Depth 3) -> Base Color; a
noise_ramp            Color Ramp (Constant, three stops) of a Noise -> Base Color and a second
                      ramp of it -> Roughness

``BUILDERS`` maps each name to its builder, in this order.
"""

import math

import bpy
import numpy as np

from devkit import engines, scenes

SIZE = 96  # default width and height (metal_grid: 256)
SUN_STRENGTH = 3.0  # W/m²: a white (0.8) surface facing the sun is 0.76, just under display white
WORLD = (0.05, 0.05, 0.05)
CHECKER_A = (0.9, 0.75, 0.2)  # sRGB display values of the two checker colours
CHECKER_B = (0.15, 0.3, 0.8)
CHECKER_CELLS = 4
PLANE = 2.0  # side of the frame-filling planes (and the orthographic scale that frames them)


def srgb_decoded(c):
    """sRGB display values ``c`` as an 8-bit image stores them (the nearest code), decoded to
    linear by the exact sRGB curve."""
    c = np.floor(np.asarray(c, dtype=np.float64) * 255.0 + 0.5) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def srgb_decode_tolerance(c):
    """How far a GPU's decode of the 8-bit sRGB codes of ``c`` may lie from ``srgb_decoded``:
    half the step to the next code. Image textures are Blender's sRGB8 textures, which the GPU
    decodes; a conformant decode lands within the code's own interval (Mesa's llvmpipe
    approximates the curve: 1.2 % low at code 38, a quarter of a step), so a test of exact
    texels allows this much and no more."""
    code = np.floor(np.asarray(c, dtype=np.float64) * 255.0 + 0.5)
    return 0.5 * (srgb_decoded(np.minimum(code + 1.0, 255.0) / 255.0) - srgb_decoded(code / 255.0))


# --- materials ----------------------------------------------------------------------------


def node_material(name):
    """A new material with its node tree: (material, Principled BSDF, Material Output)."""
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:  # Blender 4.5; 5.x materials always have nodes (use_nodes is deprecated)
        mat.use_nodes = True
    return node_parts(mat)


def node_parts(mat):
    """(material, its Principled BSDF, its Material Output)."""
    nodes = mat.node_tree.nodes
    bsdf = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    output = next(n for n in nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    return mat, bsdf, output


def lambertian(bsdf, color=None):
    """Make a Principled BSDF purely diffuse (Roughness 1, no specular layer)."""
    bsdf.inputs["Roughness"].default_value = 1.0
    bsdf.inputs["Specular IOR Level"].default_value = 0.0
    if color is not None:
        bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    return bsdf


def diffuse_material(name, color):
    mat, bsdf, _ = node_material(name)
    lambertian(bsdf, color)
    mat.diffuse_color = (*color, 1.0)
    return mat


def replace_shader(mat, bl_idname):
    """Remove the Principled BSDF and link a new ``bl_idname`` node into the Surface output."""
    _, bsdf, output = node_parts(mat)
    tree = mat.node_tree
    tree.nodes.remove(bsdf)
    node = tree.nodes.new(bl_idname)
    tree.links.new(node.outputs[0], output.inputs["Surface"])
    return node


# --- images -------------------------------------------------------------------------------


def image(name, pixels, data=False, float_buffer=False):
    """A packed image of ``pixels`` (h, w, 4), row 0 at the bottom (v = 0). Byte images hold
    sRGB-encoded values (or data, with ``data``); float images linear values (keep alpha 1: a
    packed float image is stored premultiplied)."""
    h, w, _ = pixels.shape
    img = bpy.data.images.new(name, w, h, alpha=True, float_buffer=float_buffer)
    if data:
        img.colorspace_settings.name = "Non-Color"
    img.pixels.foreach_set(np.ascontiguousarray(pixels, np.float32).ravel())
    img.pack()
    return img


def checker(cells, cell_px, a, b):
    """(h, w, 4) pixels of a ``cells`` x ``cells`` checker of RGBA ``a`` and ``b``, ``cell_px``
    pixels a cell; cell (0, 0) (bottom left, at uv (0, 0)) is ``a``."""
    idx = np.arange(cells * cell_px) // cell_px
    parity = (idx[:, None] + idx[None, :]) % 2
    return np.where(parity[..., None] == 0, np.float32(a), np.float32(b)).astype(np.float32)


def image_node(mat, img, interpolation="Linear", extension="REPEAT"):
    node = mat.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = img
    node.interpolation = interpolation
    node.extension = extension
    return node


# --- geometry, camera, lights -------------------------------------------------------------


def uv_plane(scene, name="Plane", size=PLANE, z=0.0, mat=None):
    """A square plane of side ``size`` at height ``z`` with the UV map "UVMap": uv = (x, y)
    mapped from [-size/2, size/2] to [0, 1]."""
    ob = scenes.plane(scene, name, size=size, z=z, mat=mat)
    me = ob.data
    layer = me.uv_layers.new(name="UVMap")
    co = np.array([me.vertices[loop.vertex_index].co[:2] for loop in me.loops], np.float32)
    layer.data.foreach_set("uv", (co / size + 0.5).ravel())
    return ob


def default_engine():
    """'PENUMBRA' when the engine is registered, else EEVEE (the builders work without it).
    Add-on engines are not listed in the RNA enum's static items, so ask RenderEngine."""
    if any(getattr(cls, "bl_idname", "") == "PENUMBRA" for cls in bpy.types.RenderEngine.__subclasses__()):
        return "PENUMBRA"
    return engines.eevee_id()


def base(width, height, world=WORLD):
    scene = scenes.empty_scene(width, height, engine=default_engine())
    scenes.set_world(scene, world)
    return scene


def sun(scene, strength=SUN_STRENGTH, toward=None, name="Sun"):
    """A sun shining straight down, or from the direction ``toward`` (pointing at the sun)."""
    ob = scenes.light(scene, name, "SUN", strength)
    if toward is not None:
        ob.location = toward
        scenes.aim(ob, (0.0, 0.0, 0.0))
    return ob


def top_view(scene, ortho_scale=PLANE, height=10.0):
    return scenes.top_camera(scene, height=height, ortho_scale=ortho_scale)


def sphere_view(scene, mat, sun_strength=SUN_STRENGTH):
    """A smooth unit sphere at the origin seen from the front and slightly above, lit by a sun
    from the upper left of the camera."""
    scenes.uv_sphere(scene, "Sphere", radius=1.0, mat=mat)
    scenes.look_at(scene, (0.0, -4.0, 1.5), (0.0, 0.0, 0.0), lens=50.0)
    sun(scene, sun_strength, toward=(-3.0, -4.0, 5.0))
    return scene


def textured_plane_scene(width, height, name):
    """Top camera, sun straight down, a Lambertian plane filling the frame: (scene, material,
    Principled BSDF)."""
    scene = base(width, height)
    mat, bsdf, _ = node_material(name)
    lambertian(bsdf)
    uv_plane(scene, "Plane", mat=mat)
    top_view(scene)
    sun(scene)
    return scene, mat, bsdf


# --- builders -----------------------------------------------------------------------------


def texture_base_color(width=SIZE, height=SIZE):
    scene, mat, bsdf = textured_plane_scene(width, height, "Checker")
    img = image("Checker", checker(CHECKER_CELLS, 16, (*CHECKER_A, 1.0), (*CHECKER_B, 1.0)))
    tex = image_node(mat, img)
    mat.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    scene["checker_cells"] = CHECKER_CELLS
    scene["checker_srgb"] = (*CHECKER_A, *CHECKER_B)
    return scene


def texture_closest_clip(width=SIZE, height=SIZE):
    scene, mat, bsdf = textured_plane_scene(width, height, "ClosestClip")
    img = image("Checker4", checker(CHECKER_CELLS, 1, (*CHECKER_A, 1.0), (*CHECKER_B, 1.0)))
    tex = image_node(mat, img, interpolation="Closest", extension="CLIP")
    tree = mat.node_tree
    coords = tree.nodes.new("ShaderNodeTexCoord")
    mapping = tree.nodes.new("ShaderNodeMapping")
    mapping.vector_type = "POINT"
    mapping.inputs["Scale"].default_value = (2.0, 2.0, 1.0)
    mapping.inputs["Location"].default_value = (-0.5, -0.5, 0.0)
    tree.links.new(coords.outputs["UV"], mapping.inputs["Vector"])
    tree.links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
    tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    scene["checker_cells"] = CHECKER_CELLS
    scene["checker_srgb"] = (*CHECKER_A, *CHECKER_B)
    scene["uv_scale"], scene["uv_offset"] = 2.0, -0.5  # image uv = 2 * uv - 0.5
    return scene


def color_attribute(width=SIZE, height=SIZE):
    scene, mat, bsdf = textured_plane_scene(width, height, "ColorAttribute")
    me = scene.objects["Plane"].data
    attr = me.color_attributes.new("Col", "BYTE_COLOR", "CORNER")
    corner_colors = {(-1, -1): (1, 0, 0, 1), (1, -1): (0, 1, 0, 1), (1, 1): (0, 0, 1, 1), (-1, 1): (1, 1, 1, 1)}
    colors = []
    for loop in me.loops:
        co = me.vertices[loop.vertex_index].co
        colors.extend(corner_colors[(int(math.copysign(1, co.x)), int(math.copysign(1, co.y)))])
    attr.data.foreach_set("color", colors)
    me.color_attributes.active_color = attr
    me.color_attributes.render_color_index = me.color_attributes.active_color_index
    node = mat.node_tree.nodes.new("ShaderNodeVertexColor")
    node.layer_name = "Col"
    mat.node_tree.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
    return scene


def emission(width=SIZE, height=SIZE):
    scene = base(width, height)
    mat, bsdf, _ = node_material("Emission")
    bsdf.inputs["Emission Color"].default_value = (1.0, 0.5, 0.2, 1.0)
    bsdf.inputs["Emission Strength"].default_value = 2.0
    return sphere_view(scene, mat, sun_strength=0.3)


def _shader_sphere(width, height, name, node_type, **inputs):
    """The sphere with a material whose output is one ``node_type`` shader with ``inputs``."""
    scene = base(width, height)
    mat, _, _ = node_material(name)
    node = replace_shader(mat, node_type)
    for key, value in inputs.items():
        node.inputs[key].default_value = value
    return sphere_view(scene, mat)


def emission_shader(width=SIZE, height=SIZE):
    return _shader_sphere(
        width, height, "EmissionShader", "ShaderNodeEmission", Color=(0.2, 0.6, 1.0, 1.0), Strength=1.0
    )


def diffuse_bsdf(width=SIZE, height=SIZE):
    return _shader_sphere(width, height, "Diffuse", "ShaderNodeBsdfDiffuse", Color=(0.2, 0.6, 0.3, 1.0), Roughness=0.0)


def rgb_node(width=SIZE, height=SIZE):
    scene = base(width, height)
    mat, bsdf, _ = node_material("RGB")
    rgb = mat.node_tree.nodes.new("ShaderNodeRGB")
    rgb.outputs["Color"].default_value = (0.8, 0.2, 0.6, 1.0)
    mat.node_tree.links.new(rgb.outputs["Color"], bsdf.inputs["Base Color"])
    return sphere_view(scene, mat)


def mix_shader(width=SIZE, height=SIZE):
    scene = base(width, height)
    mat, bsdf, output = node_material("MixShader")
    tree = mat.node_tree
    bsdf.inputs["Base Color"].default_value = (0.2, 0.4, 0.8, 1.0)
    glossy = tree.nodes.new("ShaderNodeBsdfGlossy")
    glossy.inputs["Color"].default_value = (0.9, 0.9, 0.9, 1.0)
    glossy.inputs["Roughness"].default_value = 0.2
    mix = tree.nodes.new("ShaderNodeMixShader")
    mix.inputs[0].default_value = 0.5  # "Fac" on 4.5, "Factor" on 5.x
    tree.links.new(bsdf.outputs["BSDF"], mix.inputs[1])
    tree.links.new(glossy.outputs["BSDF"], mix.inputs[2])
    tree.links.new(mix.outputs["Shader"], output.inputs["Surface"])
    return sphere_view(scene, mat)


def _alpha_plane(width, height, method):
    scene = base(width, height)
    scenes.plane(scene, "Ground", size=4.0, mat=diffuse_material("Ground", (0.1, 0.3, 0.8)))
    mat, bsdf, _ = node_material("Alpha")
    lambertian(bsdf, (0.9, 0.2, 0.1))
    bsdf.inputs["Alpha"].default_value = 0.25
    if method is not None:
        mat.surface_render_method = method
    uv_plane(scene, "AlphaPlane", size=1.5, z=1.0, mat=mat)
    top_view(scene, ortho_scale=3.0)
    sun(scene)
    scene["alpha"] = 0.25
    scene["alpha_plane_size"] = 1.5
    return scene


def alpha_quarter(width=SIZE, height=SIZE):
    return _alpha_plane(width, height, None)


def alpha_blend(width=SIZE, height=SIZE):
    return _alpha_plane(width, height, "BLENDED")


def alpha_checker_shadow(width=SIZE, height=SIZE):
    """The checker plane (object "Checker", side ``scene["checker_size"]``, centred on the z
    axis at ``scene["checker_z"]``) is cut into ``scene["checker_cells"]`` x ``checker_cells``
    cells; cell (i, j) (i along +x, j along +y, (0, 0) at the -x -y corner) is opaque when
    (i + j) % 2 == ``scene["checker_opaque_parity"]`` and fully transparent otherwise. The sun
    shines straight down (-z), so the ground (object "Ground", z = 0, side
    ``scene["ground_size"]``) is shadowed exactly below the opaque cells. The camera is
    orthographic, straight down from ``scene["camera_z"]`` (below the checker plane, above the
    ground) with ortho scale ``scene["view_size"]``: pixel (x, y) sees ground point
    ((x + 0.5) / width - 0.5, (y + 0.5) / height - 0.5) * view_size."""
    scene = base(width, height)
    cells, size, z = CHECKER_CELLS, PLANE, 1.0
    scenes.plane(scene, "Ground", size=4.0, mat=scenes.white("Ground"))
    mat, bsdf, _ = node_material("AlphaChecker")
    lambertian(bsdf)
    img = image("AlphaChecker", checker(cells, 32, (*CHECKER_A, 1.0), (*CHECKER_A, 0.0)))
    tex = image_node(mat, img, extension="EXTEND")  # no wrapped half texel along the border
    mat.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    mat.node_tree.links.new(tex.outputs["Alpha"], bsdf.inputs["Alpha"])
    uv_plane(scene, "Checker", size=size, z=z, mat=mat)
    view = 3.0
    scenes.camera(scene, (0.0, 0.0, 0.5), (0.0, 0.0, 0.0), ortho_scale=view, clip=(0.1, 10.0))
    sun(scene)
    scene["checker_cells"] = cells
    scene["checker_size"] = size
    scene["checker_z"] = z
    scene["checker_opaque_parity"] = 0
    scene["ground_size"] = 4.0
    scene["camera_z"] = 0.5
    scene["view_size"] = view
    return scene


def normal_map(width=SIZE, height=SIZE):
    scene = base(width, height)
    tilt = math.radians(30.0)
    normal = (0.0, math.sin(tilt), math.cos(tilt))
    mat, bsdf, _ = node_material("NormalMap")
    lambertian(bsdf, (scenes.WHITE_ALBEDO,) * 3)
    pixels = np.empty((4, 4, 4), np.float32)
    pixels[...] = (*(0.5 * c + 0.5 for c in normal), 1.0)
    img = image("NormalMap", pixels, data=True, float_buffer=True)
    tex = image_node(mat, img)
    nmap = mat.node_tree.nodes.new("ShaderNodeNormalMap")
    nmap.space = "TANGENT"
    nmap.uv_map = "UVMap"
    mat.node_tree.links.new(tex.outputs["Color"], nmap.inputs["Color"])
    mat.node_tree.links.new(nmap.outputs["Normal"], bsdf.inputs["Normal"])
    uv_plane(scene, "Plane", mat=mat)
    top_view(scene)
    toward = (0.0, math.sqrt(0.5), math.sqrt(0.5))
    sun(scene, toward=tuple(5.0 * c for c in toward))
    scene["normal_tilt_degrees"] = 30.0
    scene["mapped_normal"] = normal  # world space: the plane's UV axes are +x, +y
    scene["sun_direction"] = toward  # towards the sun
    return scene


def metal_grid(width=256, height=256):
    scene = base(width, height)
    world = scene.world
    bg = next(n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    bg.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bg.inputs["Strength"].default_value = 0.5
    world.color = (0.5, 0.5, 0.5)
    metallic = (0.0, 0.33, 0.67, 1.0)
    roughness = (0.1, 0.3, 0.6, 1.0)
    for row, m in enumerate(metallic):
        for col, r in enumerate(roughness):
            mat = scenes.material(f"Metal_m{m:.2f}_r{r:.1f}", (0.8, 0.6, 0.3), roughness=r, metallic=m)
            center = (col - 1.5, 0.0, 1.5 - row)
            scenes.uv_sphere(scene, f"Sphere_{row}{col}", center=center, radius=0.4, mat=mat)
    scenes.camera(scene, (0.0, -7.0, 0.0), (math.radians(90.0), 0.0, 0.0), lens=50.0)
    sun(scene, toward=(-3.0, -5.0, 4.0))
    scene["metallic_rows"] = metallic  # top to bottom
    scene["roughness_columns"] = roughness  # left to right
    return scene


def world_hdri(width=SIZE, height=SIZE):
    scene = base(width, height)
    pixels = np.ones((32, 64, 4), np.float32)
    pixels[16:, :, :3] = (0.6, 1.0, 2.0)  # rows 16..31: the upper half of the image, the sky
    pixels[:16, :, :3] = (0.4, 0.3, 0.2)
    img = image("Sky", pixels, float_buffer=True)
    tree = scene.world.node_tree
    bg = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
    env = tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = img
    tree.links.new(env.outputs["Color"], bg.inputs["Color"])
    scenes.uv_sphere(scene, "Sphere", radius=1.0, mat=diffuse_material("White", (scenes.WHITE_ALBEDO,) * 3))
    scenes.look_at(scene, (0.0, -4.5, 0.0), (0.0, 0.0, 0.0), lens=50.0)
    scene["sky_radiance"] = (0.6, 1.0, 2.0)  # the world above the horizon
    scene["ground_radiance"] = (0.4, 0.3, 0.2)  # and below it
    return scene


def light_temperature(width=SIZE, height=SIZE):
    scene = base(width, height)
    uv_plane(scene, "Plane", mat=diffuse_material("White", (scenes.WHITE_ALBEDO,) * 3))
    top_view(scene)
    data = sun(scene, strength=1.0).data  # 2000 K is mostly red: keep it under display white
    if hasattr(data, "use_temperature"):
        data.use_temperature = True
        data.temperature = 2000.0
    return scene


def visibility(width=SIZE, height=SIZE):
    scene = base(width, height)
    white = scenes.white("White")
    scenes.plane(scene, "Ground", size=6.0, mat=white)
    red = diffuse_material("Red", (0.8, 0.15, 0.1))
    green = diffuse_material("Green", (0.15, 0.7, 0.2))
    blue = diffuse_material("Blue", (0.15, 0.3, 0.8))
    yellow = diffuse_material("Yellow", (0.85, 0.7, 0.1))
    scenes.box(scene, "NoCamera", center=(-1.2, 1.2, 0.5), size=(0.8, 0.8, 1.0), mat=red).visible_camera = False
    scenes.box(scene, "NoShadow", center=(1.2, 1.2, 0.5), size=(0.8, 0.8, 1.0), mat=green).visible_shadow = False
    scenes.uv_sphere(scene, "Holdout", center=(-1.2, -1.2, 0.5), radius=0.5, mat=blue).is_holdout = True
    instance = scenes.box(scene, "Instance", center=(0.0, 0.0, -3.0), size=(0.2, 0.2, 0.2), mat=yellow)
    instance.hide_render = True  # only its instances render
    emitter = scenes.plane(scene, "Emitter", size=1.2, z=0.0, mat=yellow)
    emitter.location = (1.2, -1.2, 0.4)
    emitter.show_instancer_for_render = False
    emitter.modifiers.new("Particles", "PARTICLE_SYSTEM")
    ps = emitter.particle_systems[0].settings
    ps.type = "EMITTER"
    ps.count = 16
    ps.frame_start = ps.frame_end = 1.0
    ps.lifetime = 1000.0
    ps.emit_from = "FACE"
    ps.distribution = "JIT"
    ps.physics_type = "NO"
    ps.render_type = "OBJECT"
    ps.instance_object = instance
    ps.particle_size = 1.0
    scenes.look_at(scene, (0.0, -6.5, 6.5), (0.0, 0.0, 0.0), lens=40.0)
    sun(scene, toward=(-4.0, -1.5, 5.0))
    return scene


def particle_hair(ob, count, length, radius_scale):
    """A hair particle system of ``count`` strands ``length`` long on ``ob``, rendered as paths;
    returns its settings."""
    ob.modifiers.new("Hair", "PARTICLE_SYSTEM")
    ps = ob.particle_systems[0].settings
    ps.type = "HAIR"
    ps.count = count
    ps.hair_length = length
    ps.render_type = "PATH"
    ps.radius_scale = radius_scale
    return ps


def hair(width=SIZE, height=SIZE):
    scene = base(width, height)
    brown = scenes.material("Hair", (0.45, 0.25, 0.1), roughness=0.6)
    body = scenes.uv_sphere(scene, "HairBall", center=(-0.9, 0.0, 0.0), radius=0.6, mat=brown)
    particle_hair(body, 300, 0.5, 0.02)
    if hasattr(bpy.data, "hair_curves"):
        curves = bpy.data.hair_curves.new("Curves")
        side, points = 7, 5
        curves.add_curves([points] * side * side)
        grid = np.linspace(-0.5, 0.5, side)
        roots = np.array([(x, y) for y in grid for x in grid], np.float32)
        t = np.linspace(0.0, 1.0, points, dtype=np.float32)
        pos = np.empty((side * side, points, 3), np.float32)
        pos[:, :, 0] = roots[:, None, 0] + 0.15 * np.sin(3.0 * t)[None, :]
        pos[:, :, 1] = roots[:, None, 1]
        pos[:, :, 2] = 1.2 * t[None, :]
        curves.position_data.foreach_set("vector", pos.ravel())
        radius = curves.attributes.new("radius", "FLOAT", "POINT")
        radius.data.foreach_set("value", np.full(side * side * points, 0.02, np.float32))
        curves.materials.append(brown)
        ob = scenes.link(scene, bpy.data.objects.new("Curves", curves))
        ob.location = (1.0, 0.0, -0.6)
    scenes.look_at(scene, (0.0, -5.0, 1.0), (0.0, 0.0, 0.0), lens=40.0)
    sun(scene, toward=(-3.0, -4.0, 5.0))
    return scene


HAIR_STRANDS = 2500  # strands of ``hair_patch``'s Curves object
HAIR_PATCH = 0.5  # half side of the square its strands grow from, centred at the origin


def hair_curves(name, strands=HAIR_STRANDS, points=4, half=HAIR_PATCH, height=0.5, radius=0.004, seed=7):
    """A Curves datablock of ``strands`` strands of ``points`` points growing up from random roots
    in [-half, half]^2 (z = 0), leaning a little in +x, each ``height`` tall and of ``radius``."""
    rng = np.random.default_rng(seed)
    curves = bpy.data.hair_curves.new(name)
    curves.add_curves([points] * strands)
    roots = rng.uniform(-half, half, (strands, 2))
    t = np.linspace(0.0, 1.0, points)
    lean = rng.uniform(0.05, 0.15, strands)
    pos = np.empty((strands, points, 3), np.float32)
    pos[:, :, 0] = roots[:, None, 0] + lean[:, None] * t[None, :] ** 2
    pos[:, :, 1] = roots[:, None, 1]
    pos[:, :, 2] = height * t[None, :]
    curves.position_data.foreach_set("vector", pos.ravel())
    attr = curves.attributes.new("radius", "FLOAT", "POINT")
    attr.data.foreach_set("value", np.full(strands * points, radius, np.float32))
    return curves


def hair_patch(width=240, height=135, particles=True, top=False):
    """Hair over a white ground under a sun from +x and above: a Curves object of HAIR_STRANDS
    strands on [-HAIR_PATCH, HAIR_PATCH]^2 and (``particles``) a sphere with particle hair and
    interpolated children beside it; seen from the front and above, or (``top``) straight
    down by an orthographic camera, where the strands' shadow falls on the ground at +x."""
    scene = base(width, height)
    ground = scenes.material("Ground", (0.8, 0.8, 0.8), roughness=0.8)
    brown = scenes.material("Hair", (0.45, 0.25, 0.1), roughness=0.6)
    scenes.plane(scene, "Ground", size=8.0, mat=ground)
    curves = hair_curves("Strands")
    curves.materials.append(brown)
    scenes.link(scene, bpy.data.objects.new("Strands", curves))
    if particles:
        body = scenes.uv_sphere(scene, "HairBall", center=(-1.4, 0.6, 0.45), radius=0.35, mat=brown)
        ps = particle_hair(body, 200, 0.3, 0.01)
        ps.child_type = "INTERPOLATED"
        ps.child_percent = 5
        ps.rendered_child_count = 5
        ps.display_step = ps.render_step = 2
    if top:
        scenes.top_camera(scene, height=10.0, ortho_scale=3.2)
    else:
        scenes.look_at(scene, (0.0, -3.4, 2.0), (-0.3, 0.2, 0.2), lens=40.0)
    sun(scene, toward=(4.0, -1.0, 4.0))
    return scene


def _procedural_sphere(width, height, name, node_type, output="Color", props=None, **inputs):
    """The sphere whose Principled Base Color is output ``output`` of texture ``node_type``
    (Generated coordinates) with node properties ``props`` and ``inputs``: (scene, material,
    texture node, Principled BSDF)."""
    scene = base(width, height)
    mat, bsdf, _ = node_material(name)
    tex = mat.node_tree.nodes.new(node_type)
    for key, value in (props or {}).items():
        setattr(tex, key, value)
    for key, value in inputs.items():
        tex.inputs[key.replace("_", " ")].default_value = value
    out = next(s for s in tex.outputs if s.identifier == output)
    mat.node_tree.links.new(out, bsdf.inputs["Base Color"])
    return sphere_view(scene, mat), mat, tex, bsdf


def noise_texture(width=SIZE, height=SIZE):
    return _procedural_sphere(width, height, "Noise", "ShaderNodeTexNoise", Scale=4.0, Detail=4.0)[0]


def voronoi_texture(width=SIZE, height=SIZE):
    scene, mat, tex, bsdf = _procedural_sphere(width, height, "Voronoi", "ShaderNodeTexVoronoi", Scale=5.0)
    mat.node_tree.links.new(tex.outputs["Distance"], bsdf.inputs["Roughness"])
    return scene


def wave_texture(width=SIZE, height=SIZE):
    return _procedural_sphere(width, height, "Wave", "ShaderNodeTexWave", Scale=3.0, Distortion=4.0)[0]


def brick_texture(width=SIZE, height=SIZE):
    return _procedural_sphere(width, height, "Brick", "ShaderNodeTexBrick", Scale=4.0)[0]


def magic_texture(width=SIZE, height=SIZE):
    return _procedural_sphere(width, height, "Magic", "ShaderNodeTexMagic", props={"turbulence_depth": 3})[0]


def noise_ramp(width=SIZE, height=SIZE):
    scene, mat, tex, bsdf = _procedural_sphere(width, height, "NoiseRamp", "ShaderNodeTexNoise", "Fac", Scale=3.0)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    color, rough = nodes.new("ShaderNodeValToRGB"), nodes.new("ShaderNodeValToRGB")
    color.color_ramp.interpolation = "CONSTANT"
    stops = ((0.0, (0.05, 0.15, 0.5, 1.0)), (0.45, (0.8, 0.7, 0.3, 1.0)), (0.55, (0.1, 0.5, 0.1, 1.0)))
    color.color_ramp.elements.new(0.5)
    for element, (position, rgba) in zip(color.color_ramp.elements, stops, strict=True):
        element.position, element.color = position, rgba
    rough.color_ramp.elements[0].color = (0.1, 0.1, 0.1, 1.0)
    for ramp in (color, rough):
        links.new(tex.outputs["Fac"], ramp.inputs["Fac"])
    links.new(color.outputs["Color"], bsdf.inputs["Base Color"])
    links.new(rough.outputs["Color"], bsdf.inputs["Roughness"])
    return scene


BUILDERS = {
    "texture_base_color": texture_base_color,
    "texture_closest_clip": texture_closest_clip,
    "color_attribute": color_attribute,
    "emission": emission,
    "emission_shader": emission_shader,
    "diffuse_bsdf": diffuse_bsdf,
    "rgb_node": rgb_node,
    "mix_shader": mix_shader,
    "alpha_quarter": alpha_quarter,
    "alpha_blend": alpha_blend,
    "alpha_checker_shadow": alpha_checker_shadow,
    "normal_map": normal_map,
    "metal_grid": metal_grid,
    "world_hdri": world_hdri,
    "light_temperature": light_temperature,
    "visibility": visibility,
    "hair": hair,
    "noise_texture": noise_texture,
    "voronoi_texture": voronoi_texture,
    "wave_texture": wave_texture,
    "brick_texture": brick_texture,
    "magic_texture": magic_texture,
    "noise_ramp": noise_ramp,
}
