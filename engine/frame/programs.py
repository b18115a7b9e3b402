"""The lit pass's shader programs and the structs the scene passes share with Python.

Each other pass declares its programs beside it: the shadow depth pass's (and the camera
depth prepass's) in ``shadow_programs``, the film's in ``film_programs``, the background's in
``lit_pass``, the world reduction's in ``world/sh_light``.

Sizes, array lengths and enum values are defined once (here and in ``enums.py``) and reach
GLSL as defines and generated struct source, so the CPU packing and the shader layout agree
by construction. Every uniform member is named: no packed vec4 whose meaning lives in a
comment.
"""

import functools
from dataclasses import dataclass, fields, replace

import numpy as np

from ...shaders.loader import Program, ProgramPart, Struct, with_parts
from ..enums import DEPTH_FORMAT, LIGHT_TYPE, SHADOW_FILTER, SHADOW_MODE, SPECULAR_MODEL
from ..scene.materials import CHANNELS
from ..shadows import light_bins, lightspace
from ..shadows.planning import MAX_SHADOW_TILES

MAX_LIGHTS = 64
LIGHT_WORDS = MAX_LIGHTS // light_bins.WORD_BITS  # channels of a light-bin texel
JITTER_SIZE = 32  # the jitter texture repeats every 32x32 pixels
MAX_DISK_SAMPLES = 64
# The widest JITTER/PCSS kernel, in texels: a fixed fraction of the map's side.
max_filter_radius = lightspace.max_filter_radius


SHADOW_SAMPLER = "shadow_atlas"
AO_SAMPLER = "ao_depth"
AO_HORIZONS_SAMPLER = "ao_horizons"

LIGHT_STRUCT = Struct(
    "LightData",
    (
        ("VEC3", "color"),  # colour * energy * 2^exposure
        ("INT", "type"),  # LIGHT_*
        ("VEC3", "position"),
        ("FLOAT", "radius"),  # soft falloff radius (Blender's shadow_soft_size)
        ("VEC3", "direction"),  # where the light points
        ("FLOAT", "spot_cos_half"),  # cos(spot_size / 2); spots only
        ("FLOAT", "spot_blend_width"),  # (1 - cos(spot_size / 2)) * spot_blend
        ("VEC3", "spot_right"),  # the light's unit X axis
        ("FLOAT", "spot_scale_x"),  # how much the object's X scale (over Z) widens the cone along it
        ("VEC3", "spot_up"),  # the light's unit Y axis
        ("FLOAT", "spot_scale_y"),
        ("INT", "shadow_mode"),  # SHADOW_MODE_*
        ("FLOAT", "shadow_radius"),  # emitter radius for soft shadows (world units)
        ("FLOAT", "sun_tan_half_angle"),  # tan(sun angle / 2)
        ("IVEC4", "tiles"),  # atlas tile of cube faces 0..3 (x: the single map); -1: none
        ("IVEC2", "tiles_45"),  # atlas tiles of cube faces 4, 5
        ("FLOAT", "bias_scale"),  # light.penumbra.bias_scale
        ("FLOAT", "diffuse_factor"),  # Light > Influence > Diffuse (EEVEE's), on the diffuse term
        ("FLOAT", "specular_factor"),  # Light > Influence > Specular, on the specular term
        ("FLOAT", "volume_factor"),  # Light > Influence > Volume: on the light media scatter
        ("INT", "jittered"),  # 1: its maps move by a sub-texel offset in each of the frame's samples
        ("FLOAT", "offset_scale"),  # multiplies the normal offset (besides bias_scale)
        ("VEC4", "cascade_splits"),  # CASCADE: view depth where cascade 0..3 ends (tiles.xyzw)
        ("VEC4", "cascade_blend"),  # CASCADE: depth before each end over which the next one fades in
        # 1: a direction of the world's light (frame/world/directions.py), ``color`` its radiance
        # over its probability: it adds to the world ratio's sums (lit.frag.glsl WORLD_RATIO),
        # or with light portals its light itself.
        ("INT", "world"),
    ),
)

# One rendered shadow map (an atlas tile): world -> light view, view -> texture [0,1]^2, and
# its linear depth range; stored depth is (distance along the view axis - near) / (far - near).
TILE_STRUCT = Struct(
    "ShadowTile",
    (
        ("MAT4", "view"),
        ("MAT4", "proj_tex"),
        ("FLOAT", "near"),
        ("FLOAT", "far"),
        ("FLOAT", "texel"),  # world size of a texel (orthographic maps)
        ("FLOAT", "texel_per_distance"),  # world size of a texel per unit of distance (perspective)
        ("INT", "size"),  # texels per side of this map
        ("IVEC2", "origin"),  # its lower-left texel in the atlas
    ),
)


def packed_tiles(plan, origin):
    """The TILE_STRUCT block of ``plan``'s tiles (MAX_SHADOW_TILES elements) with positions
    relative to ``origin``: packed once per plan and origin, for the instanced depth pass and
    the lit pass read the same records (a plan's tiles are final once its maps are drawn)."""
    key = tuple(float(x) for x in np.asarray(origin, np.float64).ravel())
    memo = getattr(plan, "_packed_tiles", None)
    if memo is None or memo[0] != key:
        memo = (key, TILE_STRUCT.pack([t.record(origin) for t in plan.tiles], MAX_SHADOW_TILES))
        plan._packed_tiles = memo
    return memo[1]


FRAME_STRUCT = Struct(
    "FrameData",
    (
        ("MAT4", "view_proj"),
        ("MAT4", "view"),
        ("VEC3", "camera_position"),
        ("INT", "is_ortho"),
        ("VEC3", "camera_forward"),
        ("INT", "light_count"),
        ("INT", "shadowed_count"),  # lights [0, shadowed_count) have maps and come first
        ("IVEC4", "shadowed_mask"),  # the same lights as bits of the light-bin words
        ("INT", "sampled_count"),  # lights [0, sampled_count) move between samples (PCSS per sample)
        ("IVEC4", "sampled_mask"),
        ("VEC3", "world_color"),  # the world's mean radiance (SH band 0)
        ("FLOAT", "alpha_offset"),  # this sample's offset of the alpha-hash threshold
        ("VEC4", "world_sh1"),  # SH bands 1 and 2 of the world's radiance (xyz; w unused)
        ("VEC4", "world_sh2"),
        ("VEC4", "world_sh3"),
        ("VEC4", "world_sh4"),
        ("VEC4", "world_sh5"),
        ("VEC4", "world_sh6"),
        ("VEC4", "world_sh7"),
        ("VEC4", "world_sh8"),
        ("FLOAT", "constant_bias"),  # texels
        ("FLOAT", "slope_bias"),  # texels per unit of tan(angle)
        ("FLOAT", "normal_offset"),  # texels
        ("INT", "receiver_plane"),  # 1: taps biased by the receiver's plane, not by a growing slope bias
        ("FLOAT", "pcf_spacing"),  # texels between PCF taps
        ("FLOAT", "filter_radius"),  # JITTER radius, texels
        ("FLOAT", "max_filter_radius"),  # widest disk kernel, texels
        ("INT", "tile_size"),  # texels per side of the atlas's slots (its widest map)
        ("INT", "atlas_columns"),  # tiles per atlas row
        # WORLD_AO (lib/gtao.glsl): the raster camera's projection terms that take a view depth
        # to a position and back (P[0][0], P[1][1], P[0][2], P[1][2] and P[0][3], P[1][3],
        # P[3][2], P[3][3]), the film's size in pixels, the distance the occlusion looks in
        # world units, and this sample's rotation of the slices and offset of the steps.
        ("VEC4", "ao_projection"),
        ("VEC4", "ao_projection_w"),
        ("VEC2", "ao_viewport"),
        ("FLOAT", "ao_distance"),
        ("VEC2", "ao_jitter"),
        ("INT", "sample_index"),  # this sample's index in its frame (the bounce's sequence, INDIRECT_RSM)
        # The settle test's depth of field (``lens.coc_row``): x the aperture's radius times the
        # pixels per unit, y 1 / focus, z 1 with a lens (0: a pinhole).
        ("VEC4", "lens_coc"),
        # WORLD_ENV (features/world_env.py): the columns of the rotation from world directions
        # to the Environment Texture's, and (Background strength, the sun's clamp of the image
        # or 0, 1 where the image's texture is premultiplied, 0).
        ("VEC4", "env_rotation_x"),
        ("VEC4", "env_rotation_y"),
        ("VEC4", "env_rotation_z"),
        ("VEC4", "env_params"),
        # SSR (features/reflections.py, lib/ssr.glsl): (the longest ray in world units, a
        # surface's thickness as a fraction of its depth, 0, 0), and the view and projection
        # of the camera its depth prepass was drawn through (positions relative to the origin).
        ("VEC4", "ssr_params"),
        ("MAT4", "ssr_view"),
        ("MAT4", "ssr_view_proj"),
        # REFRACTION (features/refraction.py, lib/refraction.glsl): (the longest ray in world
        # units, a surface's thickness as a fraction of its depth, 0, 0).
        ("VEC4", "refr_params"),
        # PLANAR (features/planar.py, lib/planar.glsl): the mirrored camera its capture was
        # drawn through, the map into the probe's influence box (-1..1 inside), the mirror's
        # plane (normal, d: dot((P, 1), it) is the height over it) and (the
        # longest ray, a surface's thickness as a fraction of its depth, 0, 0); CLIP_PLANE (a
        # capture's lit pass): the plane under which nothing is drawn (dot((P, 1), it) < 0).
        ("MAT4", "planar_view"),
        ("MAT4", "planar_view_proj"),
        ("MAT4", "planar_influence"),
        ("VEC4", "planar_plane"),
        ("VEC4", "planar_params"),
        ("VEC4", "clip_plane"),
        # CUBES (features/cubes.py, lib/cubes.glsl): (a face's side in texels, the longest ray,
        # a surface's thickness as a fraction of its depth, 0); a Sphere probe's cube (its
        # centre, its row in the atlas or -1), the map into its influence and (1 for a box, its
        # falloff, 0, 0); the camera's cube (its centre, its row or -1).
        ("VEC4", "cube_params"),
        ("VEC4", "cube_probe"),
        ("MAT4", "cube_probe_influence"),
        ("VEC4", "cube_probe_shape"),
        ("VEC4", "cube_camera"),
        # VOLUMES (features/volumes.py, lib/volumes.glsl): (media in the ``media`` block, the
        # world medium's radius (the clip end), steps of the march, this sample's offset of them).
        ("VEC4", "volume_params"),
        # and the march's maps of clip space to positions (relative to the origin): the view
        # camera's (its clip start and end) and the raster camera's (its z-buffer).
        ("MAT4", "volume_inv_view"),
        ("MAT4", "volume_inv_raster"),
    ),
)

MESH_VERTEX_IN = (("VEC3", "pos"), ("VEC3", "nor"))
# Hair strips (``hair.strips``): per vertex its side of the strand (-1, 1) and the radius there;
# ``pos`` lies on the strand and ``nor`` is its tangent. The lit pass reads ``hair_pixel``: 0 for
# strips of the strands' radius (Render > Curves > Strip), else the half width of a pixel per
# unit of clip w (Strand: a pixel wide); shadow maps read ``hair_texels``: 0 (radius) or 1 (a
# map texel wide).
HAIR_VERTEX_IN = ("VEC2", "hair")
HAIR_PIXEL = ("FLOAT", "hair_pixel")

# One material's values and, per texture channel (materials.CHANNELS), the rows of its UV
# transform (uv' = (dot(row_u, uv1), dot(row_v, uv1))) and its mode (interpolation,
# extension, 1 = the image's alpha output, the component a value channel reads: 0 = luminance
# or alpha, 1-3 = R, G, B through a Separate Color node).
MATERIAL_STRUCT = Struct(
    "MaterialData",
    (
        ("VEC4", "base_color"),
        ("VEC4", "specular"),  # the dielectric's F0: rgb tinted, a untinted (materials.dielectric_f0)
        ("VEC3", "emission"),
        ("FLOAT", "roughness"),
        ("FLOAT", "metallic"),
        ("FLOAT", "alpha"),
        ("FLOAT", "normal_strength"),
        ("FLOAT", "transmission"),  # Principled Transmission Weight (features/refraction.py)
        ("FLOAT", "ior"),  # its IOR, for what it refracts
        *(f for c in CHANNELS for f in (("VEC4", f"{c}_uv_u"), ("VEC4", f"{c}_uv_v"), ("IVEC4", f"{c}_mode"))),
    ),
)
ALPHA_MODES = {"OPAQUE": 0, "HASHED": 1, "BLEND": 2}

# A compiled node tree's constants (engine/scene/nodetree.py): one vec4 row each, bound per
# material as the block ``node_constants`` (as many rows as the tree has, at least one).
NODE_CONSTANT_STRUCT = Struct("NodeConstant", (("VEC4", "v"),))


# An object's Object > Shading > Shadow Terminator (``scene.terminator``) as lit-pass features:
# TERMINATOR_OFFSET  Cycles' Geometry Offset: the shadow point lifted towards the smooth
#                    surface, from per-corner data (``batches.Batches.terminator``)
# TERMINATOR_NORMAL  EEVEE's Normal Offset: the shadow point moved along the normal
# TERMINATOR_SHADING Cycles' Shading Offset: the cosine term's frequency raised
# Each is a define of its own variant; objects without them compile and draw as before.
TERMINATOR_FEATURES = ("TERMINATOR_OFFSET", "TERMINATOR_NORMAL", "TERMINATOR_SHADING")


def material_defines(features):
    """Defines of a material variant: which channels sample a texture (TEX_<CHANNEL>), which
    vertex data exist (HAS_UV, HAS_VCOL, HAS_TANGENT), the alpha mode, holdout, and the
    object's Shadow Terminator features (TERMINATOR_FEATURES)."""
    out = {f"TEX_{c.upper()}": f"TEX_{c.upper()}" in features for c in CHANNELS}
    uv = any(out.values()) or "TREE_UV" in features
    out["HAS_UV"] = uv
    out["NODE_TREE"] = any(f.startswith("NODES_") for f in features)
    out["NODE_NORMAL"] = "TREE_NORMAL" in features  # the tree gives the shading normal
    out["NODE_COAT"] = "TREE_COAT" in features  # a Principled coat over the surface (lib/lit_bsdf.glsl)
    out["NODE_FILM"] = "TREE_FILM" in features  # a Principled thin film on its specular (lib/thin_film.glsl)
    out["NODE_SHEEN"] = "TREE_SHEEN" in features  # a Principled sheen over the surface (lib/sheen.glsl)
    out["NODE_ANISO"] = "TREE_ANISO" in features  # an anisotropic specular (lib/anisotropy.glsl)
    out["NODE_SSS"] = "TREE_SSS" in features  # a subsurface share of the diffuse (lib/subsurface.glsl)
    if "TREE_LOBES" in features:  # the tree gives two lobes (one-lobe variants keep their defines)
        out["NODE_LOBES"] = 2
    out["HAS_VCOL"] = "VCOL" in features
    out["HAS_TANGENT"] = "TEX_NORMAL" in features
    mode = next((m for m in ALPHA_MODES if f"ALPHA_{m}" in features), "OPAQUE")
    out["ALPHA_MODE"] = ALPHA_MODES[mode]
    out["HOLDOUT"] = "HOLDOUT" in features
    for name in TERMINATOR_FEATURES:
        out[name] = name in features
    out["HAIR_STRIP"] = "HAIR" in features  # hair strips widened in the vertex shader
    out["TRANSMISSION"] = "TRANSMISSION" in features  # light from behind (lib/refraction.glsl)
    out["THICKNESS_SLAB"] = "THICKNESS_SLAB" in features  # leaving it through a parallel face
    return out


_ENUM_DEFINES = {
    **DEPTH_FORMAT.defines(),
    **LIGHT_TYPE.defines(),
    **SHADOW_FILTER.defines(),
    **SPECULAR_MODEL.defines(),
    **SHADOW_MODE.defines(),
}

LIT = Program(
    name="lit",
    vertex="mesh.vert.glsl",
    fragment="lit.frag.glsl",
    vertex_in=MESH_VERTEX_IN,
    varyings=(
        ("smooth", "VEC3", "v_world"),
        ("smooth", "VEC3", "v_normal"),
        ("smooth", "FLOAT", "v_view_depth"),
    ),
    # What the three entry shaders (LIT_ENTRIES) call directly; the libraries under them (the
    # lights, shadow filters, BSDF, ...) come from these files' ``// requires:`` lines.
    libs=(
        "lib/lit_debug.glsl",
        "lib/gtao.glsl",
        "lib/world_ratio.glsl",
        "lib/lit_surface.glsl",
        "lib/lit_world.glsl",
        "lib/refraction.glsl",
        "lib/lit_settle.glsl",
        "lib/lit_lights.glsl",
        "lib/lit_outputs.glsl",
    ),
    # The material at the fragment and the surface from it: after a compiled tree's code.
    entry_libs=("lib/lit_inputs.glsl",),
    # light_mask: with LIGHT_LINKING, the lights (bits in shading order) that reach this object.
    # solid: 1 for a closed surface seen from outside (its facets turned from a light are in its shadow).
    # object_thickness: with TRANSMISSION, the object's smallest dimension (lib/refraction.glsl).
    push_constants=(("MAT4", "model"), ("IVEC4", "light_mask"), ("INT", "solid"), ("FLOAT", "object_thickness")),
    # The techniques' samplers come with their parts (``features.LitPart.program``).
    samplers=(
        ("FLOAT_2D", SHADOW_SAMPLER),
        ("FLOAT_3D", "jitter_tex"),
        ("FLOAT_2D", "light_bins"),
    ),
    uniform_blocks=(
        (FRAME_STRUCT, "frame", 0),
        (LIGHT_STRUCT, "lights", MAX_LIGHTS),
        (TILE_STRUCT, "shadow_tiles", MAX_SHADOW_TILES),
        (MATERIAL_STRUCT, "material", 0),
    ),
    # out_normal: the shading normal (xyz) and the view depth (w): the Normal and Depth passes.
    outputs=(("VEC4", "out_color"), ("FLOAT", "out_shadow"), ("VEC4", "out_normal")),
    defines=tuple(
        {
            **_ENUM_DEFINES,
            "JITTER_SIZE": JITTER_SIZE,
            "LIGHT_BIN_SIZE": light_bins.BIN_SIZE,
            "LIGHT_WORD_BITS": light_bins.WORD_BITS,
            "LIGHT_WORDS": LIGHT_WORDS,
            **material_defines(frozenset()),
            "EMISSION_OUTPUT": False,
            "EMISSION_ONLY": False,
            "COUNT_SHADED": False,
            # One light pass of Blender's alone (features/passes.py LIGHT_PASSES; 0: all of it).
            "LIGHT_PASS": 0,
            "LIGHT_GROUP_WORLD": False,
            # The techniques' switches, off; their parts turn them on (``features.LitPart``).
            "INDIRECT_RSM": False,
            "RSM_SAMPLES": 1,
            "SETTLE_TEST": False,
            "PILOT_SAMPLE": False,
            "VOLUMES": False,
        }.items()
    ),
)

# The viewport's lit pass: colour only, no auxiliary targets to clear or write.
LIT_COLOR = replace(LIT, name="lit_color", outputs=LIT.outputs[:1])

_FEATURE_INPUTS = {  # vertex data a material feature reads: (type, name, varying)
    "UV": ("VEC2", "uv", "v_uv"),
    "VCOL": ("VEC4", "col", "v_color"),
    "TANGENT": ("VEC4", "tan", "v_tangent"),
}
# The geometry offset's per-corner data (``terminator.corner_data``): (type, input, varying,
# interpolation); the parabola's coefficients are one per triangle. v_tnormal is the
# interpolated object normal moved by the model matrix (not normalised, as Cycles uses it).
_TERMINATOR_INPUTS = (
    ("VEC2", "tbary", "v_tbary", "smooth"),
    ("VEC3", "tabc", "v_tabc", "flat"),
    ("VEC3", "tfront", "v_tfront", "smooth"),
    ("VEC3", "tback", "v_tback", "smooth"),
)
# Per-draw values of the terminator features (the object's settings), set like ``model``:
TERMINATOR_UNIFORMS = {
    "TERMINATOR_OFFSET": ("terminator_geometry_offset",),  # Geometry Offset (0-1)
    "TERMINATOR_NORMAL": ("terminator_geometry_offset", "terminator_normal_offset"),  # world units
    "TERMINATOR_SHADING": ("terminator_shading_frequency",),  # 1 / (1 - Shading Offset / 2)
}


# Which images of a draw Blender stores premultiplied (``TextureCache.premultiplied``): bit i
# for the compiled tree's node_image_<i>, bit IMAGE_BIT_<channel> for a channel's texture.
IMAGE_PREMULTIPLIED = ("INT", "image_premultiplied")
IMAGE_CHANNEL_BITS = {c: 1 << (16 + i) for i, c in enumerate(CHANNELS)}


def image_premultiplied_bits(premultiplied, channels=(), tree_images=()):
    """The ``image_premultiplied`` value of a draw: ``premultiplied(image name)`` of each of
    its channel textures (``(channel, image name)`` pairs) and compiled-tree images."""
    bits = 0
    for channel, image in channels:
        bits |= IMAGE_CHANNEL_BITS[channel] if premultiplied(image) else 0
    for i, image in enumerate(tree_images):
        bits |= (1 << i) if premultiplied(image) else 0
    return bits


@functools.lru_cache(maxsize=256)
def material_part(features):
    """The ``ProgramPart`` of a material variant (``features``, a frozenset): the vertex inputs,
    varyings, texture samplers and per-draw values its features read, and its defines
    (``material_defines``). Named by its features, so a program's name lists them."""
    defines = material_defines(features)
    kinds = [
        k
        for k, on in (("UV", defines["HAS_UV"]), ("VCOL", defines["HAS_VCOL"]), ("TANGENT", defines["HAS_TANGENT"]))
        if on
    ]
    samplers = tuple(("FLOAT_2D", f"tex_{c}") for c in CHANNELS if defines[f"TEX_{c.upper()}"])
    vertex_in = tuple(_FEATURE_INPUTS[k][:2] for k in kinds)
    varyings = tuple(("smooth", _FEATURE_INPUTS[k][0], _FEATURE_INPUTS[k][2]) for k in kinds)
    if defines["TERMINATOR_OFFSET"]:
        vertex_in += tuple((typ, name) for typ, name, _v, _q in _TERMINATOR_INPUTS)
        varyings += tuple((q, typ, v) for typ, _n, v, q in _TERMINATOR_INPUTS) + (("smooth", "VEC3", "v_tnormal"),)
    if defines["HAIR_STRIP"]:
        vertex_in += (HAIR_VERTEX_IN,)
        varyings += (("smooth", "VEC4", "v_hair"),)
    uniforms = []
    for feature, names in TERMINATOR_UNIFORMS.items():
        uniforms += [n for n in names if defines[feature] and n not in uniforms]
    pushes = tuple(("FLOAT", n) for n in uniforms)
    if defines["HAIR_STRIP"]:
        pushes += (HAIR_PIXEL,)
    bits = ()
    if samplers:
        pushes += (IMAGE_PREMULTIPLIED,)
        bits = tuple((f"IMAGE_BIT_{c}", bit) for c, bit in IMAGE_CHANNEL_BITS.items())
    return ProgramPart(
        name="_".join(sorted(features)).lower(),
        vertex_in=vertex_in,
        varyings=varyings,
        push_constants=pushes,
        samplers=samplers,
        defines=tuple(defines.items()) + bits,
    )


def with_features(program, features, name):
    """``program`` with the vertex inputs, varyings and texture samplers ``features`` read
    (``material_part``), named ``name``."""
    return replace(with_parts(program, material_part(frozenset(features))), name=name)


def terminator_uniforms(features, terminator, matrix):
    """{push constant: value} of an instance's ``terminator.Terminator`` settings for a
    variant with ``features`` (its world matrix ``matrix`` scales EEVEE's Normal Offset)."""
    values = {
        "terminator_geometry_offset": terminator.geometry_offset,
        "terminator_normal_offset": terminator.world_normal_offset(matrix),
        "terminator_shading_frequency": terminator.frequency,
    }
    out = {}
    for feature, names in TERMINATOR_UNIFORMS.items():
        if feature in features:
            out.update({n: float(values[n]) for n in names})
    return out


# The lit pass's own parts (``ProgramPart``), by the targets a pass takes:
# EMISSION_PART   a final render with the Emission pass: each surface's emission too
# COUNTED_PART    the viewport's pass that also writes 1 into a second target for every pixel
#                 it shades (a fragment that passed the depth test): adaptive sampling's test
# EMISSION_ONLY   only what the surface emits, as its colour: the Emission pass of a frame
#                 whose lit pass has no room left for its target (Blender's gpu module binds
#                 six colour targets, and a technique's targets took the room)
EMISSION_PART = ProgramPart("emit", outputs=(("VEC4", "out_emission"),), defines=(("EMISSION_OUTPUT", True),))
COUNTED_PART = ProgramPart("counted", outputs=(("FLOAT", "out_shaded"),), defines=(("COUNT_SHADED", True),))
EMISSION_ONLY = ProgramPart("emission_only", defines=(("EMISSION_ONLY", True),))
LIT_EMIT = with_parts(LIT, EMISSION_PART)
LIT_COLOR_COUNTED = with_parts(LIT_COLOR, COUNTED_PART)


# The lit pass's entry shaders over the same libraries (lit.frag.glsl's header): the surface's
# colour, the settle test's flags, a debug view's values. A part with a ``fragment`` takes its
# own (``ENTRY_PARTS``); the surface's is the program's.
LIT_ENTRIES = {"surface": "lit.frag.glsl", "settle": "lit_settle.frag.glsl", "debug": "lit_debug.frag.glsl"}
ENTRY_PARTS = {name: ProgramPart(name, fragment=f) for name, f in LIT_ENTRIES.items() if name != "surface"}


_TREE_PARTS = {}  # what a compiled tree's program is made of -> its ProgramPart


def tree_part(tree):
    """The ``ProgramPart`` of compiled node tree ``tree``: its GLSL families, its generated
    code, its constants block and image samplers, and the per-draw values it reads. Made once
    per tree (trees equal in what they compile share it)."""
    key = (tree.key, tree.families, tree.needs, len(tree.constants), len(tree.images), tree.code, tree.aovs)
    part = _TREE_PARTS.get(key)
    if part is None:
        pushes = tuple(p for need in sorted(tree.needs) for p in TREE_UNIFORMS.get(need, ()))
        part = _TREE_PARTS[key] = ProgramPart(
            name="",  # the material's features name the tree (NODES_<key>)
            defines=(("NODE_PROCEDURAL", any(f.startswith("texture_") for f in tree.families)),)
            # Its AOV Output nodes (``nodetree.Compiler.compile_aovs``): the passes' draw calls them.
            + ((("NODE_AOVS", len(tree.aovs)), ("NODE_AOV_SLOTS", len(tree.aovs))) if tree.aovs else ()),
            # The generated code calls the families' functions (which bring what they need by
            # their ``// requires:`` lines) and, for its image textures, lib/material.glsl's sample_image.
            libs=(("lib/material.glsl",) if tree.images else ()) + tuple(f"nodes/{f}.glsl" for f in tree.families),
            generated=tree.code,
            uniform_blocks=((NODE_CONSTANT_STRUCT, "node_constants", max(len(tree.constants), 1)),),
            samplers=tuple(("FLOAT_2D", f"node_image_{i}") for i in range(len(tree.images))),
            push_constants=pushes + ((IMAGE_PREMULTIPLIED,) if tree.images else ()),
        )
    return part


def with_tree(program, tree):
    """``program`` with compiled node tree ``tree`` (``tree_part``)."""
    return with_parts(program, tree_part(tree))


@dataclass(frozen=True)
class LitKey:
    """One lit-pass program as one value: ``aux``, whether it writes the passes' targets
    (``LIT``; otherwise colour only, ``LIT_COLOR``); ``variant``, the typed switches of the
    lit pass itself (``LitVariant``: filters, lights, debug view); ``parts``, the
    ``ProgramPart`` values it combines with, in order: the pass's targets (``EMISSION_PART``,
    ``COUNTED_PART``), the frame's techniques' (``features.LitPart.program``), the material's
    (``material_part``), its tree's (``tree_part``) and an entry's (``ENTRY_PARTS``), each
    carrying its own defines.

    Frozen and hashable: a frame's keys can be listed (``LitPass.keys``), compiled ahead
    (``precompile``) and each compiled in a test; equal keys are one program."""

    aux: bool
    variant: "LitVariant"
    parts: tuple = ()

    def program(self):
        return _lit_program(self.aux, self.parts)

    def defines(self):
        """The variant's defines (``lit_defines``, made anew: they read the module's sizes)."""
        return {**self.variant.defines(), "AUX_OUTPUTS": bool(self.aux)}


@functools.lru_cache(maxsize=1024)
def _lit_program(aux, parts):
    return with_parts(LIT if aux else LIT_COLOR, *parts)


def lit_key(aux, variant, parts=(), features=frozenset(), tree=None, entry=None):
    """The ``LitKey`` of a draw: the pass's and the techniques' ``parts``, then the material's
    ``features`` (``Material.features``, plus "HOLDOUT") and ``tree`` (its
    ``nodetree.CompiledTree``), then ``entry`` (a ``ProgramPart`` with a fragment) if any."""
    parts = tuple(parts)
    if features:
        parts += (material_part(frozenset(features)),)
    if tree is not None:
        parts += (tree_part(tree),)
    if entry is not None:
        parts += (entry,)
    return LitKey(bool(aux), variant, parts)


def precompile(shaders, keys):
    """Compile every ``LitKey`` in ``keys`` into ``shaders`` (a ``ShaderCache``) ahead of the
    frame that draws them; returns how many were new."""
    before = shaders.compiled
    for key in keys:
        shaders.get(key.program(), key.defines())
    return shaders.compiled - before


def lit_program(features=frozenset(), aux=True, emission=False, counted=False, tree=None, parts=()):
    """The lit pass program of a material variant (``Material.features``, plus "HOLDOUT");
    ``emission``: the variant also writes the Emission pass's target; ``counted`` (colour
    only): it also writes the shading count; ``tree``: the material's
    ``nodetree.CompiledTree``; ``parts``: the techniques' ``ProgramPart`` values."""
    own = (EMISSION_PART,) if emission and aux else ((COUNTED_PART,) if counted and not aux else ())
    return lit_key(aux, LitVariant(aux_outputs=aux), own + tuple(parts), features, tree).program()


# Reflective shadow maps (Dachsbacher and Stamminger 2005): with Light Paths > Diffuse Bounces
# at 1 the shadow atlas has two more colour targets of its size, per texel the diffuse albedo
# of the surface the light sees there (rgb) and its world normal turned towards the light
# (xyz), both RGBA16F (``features/bounce.py`` adds the lit pass's part that reads them).
RSM_FLUX_SAMPLER = "rsm_flux"
RSM_NORMAL_SAMPLER = "rsm_normal"
RSM_FORMAT = "RGBA16F"
RSM_TEXEL_BYTES = 16  # both targets


# Per-draw values a compiled tree may read (set like ``model``): the object's texture space
# (Generated = object position * scale + offset), the world origin the positions are drawn
# relative to (``draw_list``: positions are shifted by the frame's origin), and the Object
# Info node's colour and random number.
TREE_UNIFORMS = {"GENERATED": (("VEC3", "node_texspace_scale"), ("VEC3", "node_texspace_offset"))}
TREE_UNIFORMS["ORIGIN"] = (("VEC3", "node_origin"),)
TREE_UNIFORMS["OBJECT_INFO"] = (("VEC4", "node_object_color"), ("FLOAT", "node_object_random"))


def depth_defines(depth_format):
    return {"DEPTH_FORMAT": DEPTH_FORMAT.define(depth_format)}


# Scenes with at most this many lights (and no light bins) get a lit-pass variant with their
# light counts compiled in (lit.frag.glsl writes out that many calls).
UNROLLED_LIGHTS = 4


@dataclass(frozen=True, kw_only=True)
class LitVariant:
    """Which lit-pass program a draw takes: every field named (keyword-only: no variant is
    built by position) and typed, checked when made (a wrong type or an unknown filter, model
    or format raises, naming the field), so two swapped switches cannot pass unnoticed.
    ``defines()`` is the program's defines (``lit_defines``).

    ``shadow_filter``, ``specular_model``, ``depth_format``: names of ``enums``
    (SHADOW_FILTER, SPECULAR_MODEL, DEPTH_FORMAT). Only what a filter reads varies its
    variant: the PCF kernel ``pcf_weights`` (compiled in as constants, so its loops unroll),
    the disk size ``disk_samples`` and the ``early_out`` switch for the disk filters.
    ``aux_outputs``: the variant also writes depth, shadow and normal (a final render's
    passes); without them it writes colour only (the viewport). ``binned``: each pixel loops
    over the lights its screen bin lists (``light_bins``). PCF with taps one texel apart
    (``pcf_spacing``) on a one-channel map reads 2x2 texels per fetch (gather). ``sampled``:
    some lights move between samples and take the PCSS loop. ``light_counts``: (sampled,
    with maps, all). With at most UNROLLED_LIGHTS lights and no bins the variant calls each
    light by its constant index, so its data is read at fixed offsets instead of through a
    loop (about a tenth of the demo's lit pass on llvmpipe); otherwise a class of lights the
    frame has none of gets no loop (a loop's body costs one masked pass on llvmpipe even when
    it runs zero times). ``light_linking``: some light lights only some objects; each
    object's ``light_mask`` says which. ``debug``: the variant writes what a lit debug view
    shows instead of colour (``DEBUG_LIT``: lights evaluated, sun cascade + 1, texel density
    of the worst-sampled light, coverage). ``world_lights``: some lights are directions of
    the world's light (``WORLD_LIGHTS``, ``world/directions.py``). ``debug_term``: the
    variant writes one term of its colour alone (``DEBUG_TERM``: 1 the world's light with its
    visibility, 2 the diffuse bounce; the WORLD_LIGHT and INDIRECT debug views).

    The frame's techniques (``features/``) are not fields here: each brings its switches as
    the defines of its ``ProgramPart`` (``LitKey.parts``), so a technique added or removed
    changes no field of the lit pass's own."""

    shadow_filter: str = "NONE"
    pcf_weights: tuple = (1.0,)
    specular_model: str = "GGX"
    depth_format: str = "FLOAT32"
    disk_samples: int = 16
    early_out: bool = True
    aux_outputs: bool = True
    binned: bool = False
    pcf_spacing: float = 1.0
    sampled: bool = False
    light_counts: tuple | None = None
    light_linking: bool = False
    debug: bool = False
    world_lights: bool = False
    debug_term: int = 0

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            kind = _VARIANT_KINDS[f.name]
            if kind is bool:
                ok = isinstance(value, (bool, np.bool_))
            elif kind is int:
                ok = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
            elif kind is float:
                ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
                    value, (bool, np.bool_)
                )
            elif kind is str:
                ok = isinstance(value, str) and value in _VARIANT_ENUMS[f.name]
            elif f.name == "pcf_weights":
                ok = isinstance(value, tuple) and all(isinstance(w, (int, float, np.floating)) for w in value)
            else:  # light_counts
                ok = value is None or (
                    isinstance(value, tuple)
                    and len(value) == 3
                    and all(isinstance(c, (int, np.integer)) and not isinstance(c, bool) for c in value)
                )
            if not ok:
                raise TypeError(f"LitVariant.{f.name}: {value!r} is not a valid {_VARIANT_WANTS[f.name]}")

    def defines(self):
        """The program's defines (``lit_defines``)."""
        return lit_defines(self)


_VARIANT_KINDS = {
    "shadow_filter": str,
    "pcf_weights": tuple,
    "specular_model": str,
    "depth_format": str,
    "disk_samples": int,
    "early_out": bool,
    "aux_outputs": bool,
    "binned": bool,
    "pcf_spacing": float,
    "sampled": bool,
    "light_counts": None,
    "light_linking": bool,
    "debug": bool,
    "world_lights": bool,
    "debug_term": int,
}
_VARIANT_ENUMS = {
    "shadow_filter": SHADOW_FILTER,
    "specular_model": SPECULAR_MODEL,
    "depth_format": DEPTH_FORMAT,
}
_VARIANT_WANTS = {
    **{k: v.__name__ for k, v in _VARIANT_KINDS.items() if v is not None},
    "shadow_filter": "shadow filter",
    "specular_model": "specular model",
    "depth_format": "depth format",
    "pcf_weights": "tuple of weights",
    "light_counts": "(sampled, with maps, all) tuple of ints, or None",
}


def lit_defines(variant):
    """The defines of the lit-pass program ``variant`` (a ``LitVariant``): a dict of its own,
    made once per variant (a frame's samples and passes ask for the same few)."""
    if not isinstance(variant, LitVariant):
        raise TypeError(f"lit_defines takes a LitVariant, not {type(variant).__name__}")
    return dict(_lit_defines(variant, UNROLLED_LIGHTS))


@functools.lru_cache(maxsize=256)
def _lit_defines(variant, unrolled_lights):
    """``lit_defines``, kept per variant and the module's UNROLLED_LIGHTS as the call reads it."""
    v = variant
    shadow_filter, pcf_weights, depth_format, pcf_spacing = (
        v.shadow_filter,
        v.pcf_weights,
        v.depth_format,
        v.pcf_spacing,
    )
    light_counts, binned, sampled = v.light_counts, v.binned, v.sampled
    filt = SHADOW_FILTER[shadow_filter]
    unrolled = light_counts is not None and not binned and light_counts[2] <= unrolled_lights
    counts = tuple(int(c) for c in light_counts) if unrolled else (0, 0, 0)
    # Which classes of light the loops must walk (with a map but not sampled, without a map);
    # unknown counts keep both loops.
    sampled_n, shadowed_n, total_n = light_counts if light_counts is not None else (0, 1, 2)
    gather = bool(filt.pcf_taps and pcf_spacing == 1.0 and DEPTH_FORMAT[depth_format].channels == 1)
    weights = [float(w) for w in pcf_weights] if filt.pcf_taps else [1.0]
    return tuple(
        {
            **depth_defines(depth_format),
            "SHADOW_FILTER": SHADOW_FILTER.define(shadow_filter),
            "SPECULAR_MODEL": SPECULAR_MODEL.define(v.specular_model),
            "PCF_RADIUS": len(weights) // 2,
            "PCF_WEIGHTS_LIST": ", ".join(f"{w:.9g}" for w in weights),
            "DISK_SAMPLES": v.disk_samples if filt.disk or sampled else 8,
            "SAMPLED_LIGHTS": bool(sampled),
            "EARLY_OUT": bool(v.early_out) or not filt.early_out,
            "AUX_OUTPUTS": bool(v.aux_outputs),
            "LIGHT_BINS": bool(binned),
            "PCF_GATHER": gather,
            "UNROLLED_LIGHTS": unrolled,
            "HAS_SHADOWED": shadowed_n > sampled_n,
            "HAS_UNSHADOWED": total_n > shadowed_n,
            "SAMPLED_COUNT": counts[0],
            "SHADOWED_COUNT": counts[1],
            "LIGHT_COUNT": counts[2],
            "LIGHT_LINKING": bool(v.light_linking),
            "DEBUG_LIT": bool(v.debug),
            "WORLD_LIGHTS": bool(v.world_lights),
            "DEBUG_TERM": int(v.debug_term),
        }.items()
    )
