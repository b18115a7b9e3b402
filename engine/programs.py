"""The scene passes' shader programs and the structs/enums they share with Python.

Sizes, array lengths and enum values are defined here once and reach GLSL as defines and
generated struct source, so the CPU packing and the shader layout agree by construction.
"""

from ..shaders.loader import Program, Struct

LIGHT_TYPES = {"SUN": 0, "POINT": 1, "SPOT": 2, "AREA": 3}
SHADOW_FILTERS = {"NONE": 0, "PCF": 1}
SPECULAR_MODELS = {"BLINN": 0, "PHONG": 1}
MAX_LIGHTS = 64
MAX_PCF_TAPS = 15 * 15
SHADOW_SAMPLER = "shadow_atlas"

LIGHT_STRUCT = Struct(
    "LightData",
    (
        ("VEC4", "color"),  # rgb: colour * energy * 2^exposure, a: type
        ("VEC4", "position"),  # xyz, w: radius (soft falloff)
        ("VEC4", "direction"),  # xyz: where the light points, w: cos(spot_size / 2)
        ("VEC4", "params"),  # x: spot smooth width, y: shadow atlas tile or -1, z: texel size, w: depth/world
        ("MAT4", "shadow_matrix"),  # world -> shadow texture space [0, 1]^3
    ),
)

FRAME_STRUCT = Struct(
    "FrameData",
    (
        ("MAT4", "view_proj"),
        ("MAT4", "view"),
        ("VEC4", "camera_position"),  # xyz, w: 1 for orthographic
        ("VEC4", "camera_forward"),
        ("VEC4", "world_color"),
        ("VEC4", "counts"),  # x: light count
        ("VEC4", "shadow_params"),  # x: constant bias, y: slope bias, z: normal offset, w: spacing
        ("VEC4", "shadow_size"),  # x: tile size in texels, y: atlas columns
    ),
)

TAP_STRUCT = Struct("PcfTap", (("VEC4", "v"),))  # xy: texel offset, z: weight

MESH_VERTEX_IN = (("VEC3", "pos"), ("VEC3", "nor"))


def enum_defines(prefix, mapping):
    return {f"{prefix}_{k}": v for k, v in mapping.items()}


LIT = Program(
    name="lit",
    vertex="mesh.vert.glsl",
    fragment="lit.frag.glsl",
    libs=("lib/common.glsl", "lib/lights.glsl", "lib/shadow_filters.glsl"),
    vertex_in=MESH_VERTEX_IN,
    varyings=(
        ("smooth", "VEC3", "v_world"),
        ("smooth", "VEC3", "v_normal"),
        ("smooth", "FLOAT", "v_view_depth"),
    ),
    push_constants=(("MAT4", "model"), ("VEC4", "base_color"), ("VEC4", "material")),
    samplers=(("FLOAT_2D", SHADOW_SAMPLER),),
    uniform_blocks=(
        (FRAME_STRUCT, "frame", 0),
        (LIGHT_STRUCT, "lights", MAX_LIGHTS),
        (TAP_STRUCT, "pcf_taps", MAX_PCF_TAPS),
    ),
    outputs=(("VEC4", "out_color"), ("FLOAT", "out_depth")),
)

SHADOW_DEPTH = Program(
    name="shadow_depth",
    vertex="shadow_depth.vert.glsl",
    fragment="shadow_depth.frag.glsl",
    vertex_in=MESH_VERTEX_IN[:1],
    push_constants=(("MAT4", "model"), ("MAT4", "light_view_proj")),
    outputs=(("FLOAT", "out_depth"),),
)


def lit_defines(shadow_filter, pcf_taps, specular_model):
    d = {}
    d.update(enum_defines("LIGHT", LIGHT_TYPES))
    d.update(enum_defines("FILTER", SHADOW_FILTERS))
    d.update(enum_defines("SPECULAR", SPECULAR_MODELS))
    d["SHADOW_FILTER"] = f"FILTER_{shadow_filter}"
    d["SPECULAR_MODEL"] = f"SPECULAR_{specular_model}"
    # Only the PCF variant depends on the tap count; others share one compiled shader.
    d["PCF_TAPS"] = pcf_taps if shadow_filter == "PCF" else 1
    return d
