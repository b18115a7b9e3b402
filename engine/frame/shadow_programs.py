"""The shadow depth pass's programs (``shadow_maps.ShadowAtlas``, ``shadow_pass``): a map's
depth in each stored format, drawn tile by tile or instanced into every tile of a sample,
casters with alpha, hair strips, compiled node trees; the reflective shadow maps' outputs; and
the camera depth prepass of the world's ambient occlusion, which is the same pass seen from
the camera. The structs they share with the lit pass are ``programs``'."""

from dataclasses import replace

from ...shaders.loader import Program, Struct
from ..enums import DEPTH_FORMAT
from ..shadows.planning import MAX_SHADOW_TILES
from .programs import (
    HAIR_VERTEX_IN,
    MATERIAL_STRUCT,
    MESH_VERTEX_IN,
    TILE_STRUCT,
    material_defines,
    with_features,
    with_tree,
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
    defines=tuple(
        {
            **DEPTH_FORMAT.defines(),
            "ALPHA_CUTOUT": False,
            "HAS_UV": False,
            "RASTER_DEPTH": False,
            "HAIR_STRIP": False,
            "CAMERA_DEPTH": False,
            "RSM_OUTPUT": False,
            "RSM_MATERIAL": False,
            "INSTANCED": False,
        }.items()
    ),
)


# FLOAT32 maps are the depth buffer itself: the linear depth goes to gl_FragDepth, so a tile
# needs no colour target and no second buffer.
SHADOW_DEPTH_ONLY = replace(SHADOW_DEPTH, name="shadow_depth_only", outputs=(), depth_write="ANY")
# An orthographic tile (a sun's) already rasterises that linear depth: its projection maps the
# tile's [near, far] to window depth [0, 1], and pancaking clamps below 0 as the fragment stage
# would. It writes no gl_FragDepth, which keeps the rasteriser's early depth test (no fragment
# work for covered texels).
SHADOW_DEPTH_RASTER = replace(
    SHADOW_DEPTH_ONLY,
    name="shadow_depth_raster",
    depth_write="",
    defines=tuple({**dict(SHADOW_DEPTH.defines), "RASTER_DEPTH": True}.items()),
)
# (Reflective shadow maps: each of these, and the cut-out and hair programs below, gets its
# ``with_rsm_output`` variant, with ``rsm`` in the functions that choose them.)

# Instanced submission (``ShadowAtlas.render``): one draw of a caster's batch fills every map of
# the sample it is in. Instance i reads the tile ``instance_tiles`` names at instance_base + i
# (four tile indices to an ivec4) from the array of all the sample's tiles, and is confined to
# that tile of the atlas by four clip distances (``gpu.state.clip_distances_set``).
INSTANCE_STRUCT = Struct("InstanceTiles", (("IVEC4", "tile"),))
# ivec4 rows of one table upload: 512 (caster, map) pairs in 2 KB (a sample uploads the whole
# block); a sample with more submits in several tables.
INSTANCE_TABLE_ROWS = 128


def instanced_shadow_program(depth_format, raster_depth=False):
    """``shadow_program``'s depth-buffer map, drawn instanced into every tile of a sample at
    once (``INSTANCED``): the tiles and the instance table as uniform blocks, the atlas's size
    and the draw's first table entry as push constants."""
    base = shadow_program(depth_format, raster_depth)
    if not DEPTH_FORMAT[depth_format].depth_only:
        raise ValueError(f"instanced depth pass: {depth_format} maps are drawn tile by tile")
    return replace(
        base,
        name=f"{base.name}_instanced",
        varyings=base.varyings + (("flat", "INT", "v_tile"),),
        push_constants=base.push_constants + (("INT", "instance_base"), ("VEC2", "atlas_size")),
        uniform_blocks=(
            (TILE_STRUCT, "tiles", MAX_SHADOW_TILES),
            (INSTANCE_STRUCT, "instance_tiles", INSTANCE_TABLE_ROWS),
        ),
        defines=tuple({**dict(base.defines), "INSTANCED": True}.items()),
    )


# The camera depth prepass of the world's ambient occlusion (``world/occlusion.py``): the same depth
# pass seen from the camera (its "tile" is the lit pass's raster camera), writing the view depth
# itself into a float colour target (full float precision at every distance) and clipping at the
# near plane as the lit pass does instead of pancaking.
CAMERA_DEPTH = replace(
    SHADOW_DEPTH,
    name="camera_depth",
    defines=tuple({**dict(SHADOW_DEPTH.defines), "CAMERA_DEPTH": True}.items()),
)


# Shadow casters with alpha (leaves, fences, glass panes drawn with alpha): a texel is
# covered in a fraction alpha of the samples (``textured``: the alpha comes from a texture).
def shadow_cutout_program(depth_format, textured, raster_depth=False, camera=False, rsm=False):
    if rsm:
        return with_rsm_output(shadow_cutout_program(depth_format, textured, raster_depth))
    base = shadow_program(depth_format, raster_depth, camera)
    program = replace(
        base,
        libs=base.libs + ("lib/material.glsl",),
        push_constants=base.push_constants + (("FLOAT", "alpha_offset"),),
        uniform_blocks=base.uniform_blocks + ((MATERIAL_STRUCT, "material", 0),),
        defines=base.defines + (("ALPHA_CUTOUT", True),),
    )
    features = frozenset({"TEX_ALPHA"}) if textured else frozenset()
    defines = material_defines(features)
    program = replace(program, defines=program.defines + tuple(defines.items()))
    if not textured:
        return replace(program, name=f"{base.name}_alpha")
    return with_features(program, features, f"{base.name}_alpha_tex")


def shadow_hair_program(depth_format, raster_depth=False, camera=False, rsm=False):
    """The depth pass of hair strips: widened across the strand facing the light (the map's
    eye), by the strands' radius or one map texel (``hair_texels``)."""
    if rsm:
        return with_rsm_output(shadow_hair_program(depth_format, raster_depth), material=False)
    base = shadow_program(depth_format, raster_depth, camera)
    return replace(
        base,
        name=f"{base.name}_hair",
        vertex_in=MESH_VERTEX_IN + (HAIR_VERTEX_IN,),
        push_constants=base.push_constants + (("FLOAT", "hair_texels"),),
        defines=base.defines + (("HAIR_STRIP", True),),
    )


def shadow_tree_program(depth_format, tree, raster_depth=False, camera=False, rsm=False):
    """The alpha cut-out of a caster whose alpha a compiled node tree gives (``tree``:
    ``nodetree.CompiledTree`` without FRAME in its needs): the tree runs in the depth pass,
    with the surface data it reads, so a procedural alpha casts the shadow it draws (and,
    with ``rsm``, the base colour it gives bounces)."""
    if rsm:
        return with_rsm_output(shadow_tree_program(depth_format, tree, raster_depth))
    base = shadow_program(depth_format, raster_depth, camera)
    program = replace(
        base,
        libs=base.libs + ("lib/material.glsl",),
        vertex_in=MESH_VERTEX_IN,
        varyings=base.varyings + (("smooth", "VEC3", "v_world"), ("smooth", "VEC3", "v_normal")),
        push_constants=base.push_constants + (("FLOAT", "alpha_offset"),),
        uniform_blocks=base.uniform_blocks + ((MATERIAL_STRUCT, "material", 0),),
        defines=base.defines + (("ALPHA_CUTOUT", True),),
    )
    features = {f"NODES_{tree.key}"} | ({"TREE_UV"} if "UV" in tree.needs else set())
    features |= {"VCOL"} if "VCOL" in tree.needs else set()
    program = with_features(program, frozenset(features), f"{base.name}_alpha_{'_'.join(sorted(features)).lower()}")
    return with_tree(program, tree)


def shadow_program(depth_format, raster_depth=False, camera=False, rsm=False):
    """The depth pass of a map stored as ``depth_format``; ``raster_depth``: the tile is
    orthographic, so a depth-buffer map takes the rasterised depth as it is. ``camera``: the
    camera depth prepass instead (``CAMERA_DEPTH``; the format does not matter); ``rsm``: it
    also writes the reflective shadow map's targets (``with_rsm_output``)."""
    if camera:
        return CAMERA_DEPTH
    if rsm:
        return with_rsm_output(shadow_program(depth_format, raster_depth))
    if not DEPTH_FORMAT[depth_format].depth_only:
        return SHADOW_DEPTH
    return SHADOW_DEPTH_RASTER if raster_depth else SHADOW_DEPTH_ONLY


def with_rsm_output(program, material=True):
    """A depth-pass program that also writes a reflective shadow map's albedo and normal
    (``RSM_OUTPUT``); ``material``: it reads the caster's MaterialData block for the albedo
    (hair strips do not: they reflect nothing into the bounce)."""
    vertex_in = program.vertex_in
    if not any(name == "nor" for _t, name in vertex_in):
        vertex_in = vertex_in[:1] + MESH_VERTEX_IN[1:] + vertex_in[1:]
    blocks = program.uniform_blocks
    if material and not any(name == "material" for _s, name, _c in blocks):
        blocks = blocks + ((MATERIAL_STRUCT, "material", 0),)
    return replace(
        program,
        name=f"{program.name}_rsm",
        vertex_in=vertex_in,
        varyings=program.varyings + (("smooth", "VEC3", "v_rsm_normal"), ("smooth", "VEC3", "v_rsm_to_light")),
        uniform_blocks=blocks,
        outputs=program.outputs + (("VEC4", "out_rsm_flux"), ("VEC4", "out_rsm_normal")),
        defines=program.defines + (("RSM_OUTPUT", True), ("RSM_MATERIAL", bool(material))),
    )
