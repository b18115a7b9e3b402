"""The scene passes' shader programs and the structs/enums they share with Python.

Sizes, array lengths and enum values are defined here once and reach GLSL as defines and
generated struct source, so the CPU packing and the shader layout agree by construction.
"""

from ..shaders.loader import Program, Struct

LIGHT_TYPES = {"SUN": 0, "POINT": 1, "SPOT": 2, "AREA": 3}
SHADOW_FILTERS = {"NONE": 0, "HARDWARE": 1, "PCF": 2, "JITTER": 3, "PCSS": 4}
DEPTH_FORMATS = {"FLOAT32": 0, "FLOAT16": 1, "RGBA8": 2}  # atlas texel encodings
SHADOW_MODES = {"NONE": -1, "SINGLE": 0, "CUBE": 1}
SPECULAR_MODELS = {"BLINN": 0, "PHONG": 1}
MAX_LIGHTS = 64
MAX_PCF_TAPS = 15 * 15
MAX_SHADOW_TILES = 48
JITTER_SIZE = 32  # the jitter texture repeats every 32x32 pixels
MAX_DISK_SAMPLES = 64
SHADOW_SAMPLER = "shadow_atlas"

LIGHT_STRUCT = Struct(
    "LightData",
    (
        ("VEC4", "color"),  # rgb: colour * energy * 2^exposure, a: type
        ("VEC4", "position"),  # xyz, w: radius (soft falloff)
        ("VEC4", "direction"),  # xyz: where the light points, w: cos(spot_size / 2)
        ("VEC4", "params"),  # x: spot smooth width, y: shadow mode, z: radius (world), w: tan(sun angle / 2)
        ("VEC4", "tiles"),  # atlas tile per cube face 0..3 (or x for single maps); -1: no map
        ("VEC4", "tiles2"),  # tiles of faces 4, 5; z: bias scale
    ),
)

# One rendered shadow map (an atlas tile): world -> light view, view -> texture [0,1]^2, and
# its linear depth range; stored depth is (distance along the view axis - near) / (far - near).
TILE_STRUCT = Struct(
    "ShadowTile",
    (
        ("MAT4", "view"),
        ("MAT4", "proj_tex"),
        ("VEC4", "range"),  # x: near, y: far, z: texel world size (ortho), w: texel size per distance
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
        ("VEC4", "shadow_size"),  # x: tile size in texels, y: atlas columns, z: disk samples
        ("VEC4", "filter_params"),  # x: filter radius (texels), y: max penumbra (texels)
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
    libs=("lib/common.glsl", "lib/lights.glsl", "lib/depth_encoding.glsl", "lib/shadow_filters.glsl"),
    vertex_in=MESH_VERTEX_IN,
    varyings=(
        ("smooth", "VEC3", "v_world"),
        ("smooth", "VEC3", "v_normal"),
        ("smooth", "FLOAT", "v_view_depth"),
    ),
    push_constants=(("MAT4", "model"), ("VEC4", "base_color"), ("VEC4", "material")),
    samplers=(("FLOAT_2D", SHADOW_SAMPLER), ("FLOAT_3D", "jitter_tex")),
    uniform_blocks=(
        (FRAME_STRUCT, "frame", 0),
        (LIGHT_STRUCT, "lights", MAX_LIGHTS),
        (TAP_STRUCT, "pcf_taps", MAX_PCF_TAPS),
        (TILE_STRUCT, "shadow_tiles", MAX_SHADOW_TILES),
    ),
    outputs=(("VEC4", "out_color"), ("FLOAT", "out_depth"), ("FLOAT", "out_shadow")),
)

SHADOW_DEPTH = Program(
    name="shadow_depth",
    vertex="shadow_depth.vert.glsl",
    fragment="shadow_depth.frag.glsl",
    libs=("lib/depth_encoding.glsl",),
    vertex_in=MESH_VERTEX_IN[:1],
    varyings=(("smooth", "FLOAT", "v_distance"),),
    push_constants=(("MAT4", "model"),),
    uniform_blocks=((TILE_STRUCT, "tile", 0),),
    outputs=(("VEC4", "out_depth"),),
)


def depth_defines(depth_format):
    d = enum_defines("DEPTH", DEPTH_FORMATS)
    d["DEPTH_FORMAT"] = f"DEPTH_{depth_format}"
    return d


def lit_defines(shadow_filter, pcf_taps, specular_model, depth_format="FLOAT32", disk_samples=16, early_out=True):
    d = depth_defines(depth_format)
    d.update(enum_defines("LIGHT", LIGHT_TYPES))
    d.update(enum_defines("FILTER", SHADOW_FILTERS))
    d.update(enum_defines("SPECULAR", SPECULAR_MODELS))
    d["SHADOW_FILTER"] = f"FILTER_{shadow_filter}"
    d["SPECULAR_MODEL"] = f"SPECULAR_{specular_model}"
    # Only the PCF variant depends on the tap count; others share one compiled shader.
    d["PCF_TAPS"] = pcf_taps if shadow_filter == "PCF" else 1
    d.update(enum_defines("SHADOW_MODE", SHADOW_MODES))
    d["JITTER_SIZE"] = JITTER_SIZE
    d["DISK_SAMPLES"] = disk_samples if shadow_filter in ("JITTER", "PCSS") else 8
    d["EARLY_OUT"] = bool(early_out) or shadow_filter not in ("JITTER", "PCSS")  # no variant for others
    return d
