"""The world's Environment Texture prefiltered for glossy lobes, on the GPU (``world_env.glsl``).

Order-2 spherical harmonics hold only the slow variations of an environment: a mirror or a
polished surface that reads its reflection from them shows a few coloured blotches where the
image has a horizon, buildings or a sun, and their ringing goes below zero (clamped: black).
Glossy lobes read the image itself instead, prefiltered by roughness as Karis' split sum does
(2013, "Real Shading in Unreal Engine 4"): for each level of ``LEVELS``, an equirectangular
image whose texel at direction R holds the image's radiance over a GGX lobe of that roughness
about R with N = V = R, cosine-weighted. The lit pass reads the image itself for roughness 0,
the levels above it, and between them linearly (``lit_world.glsl`` ``world_env_radiance``).

Each level is drawn by one fullscreen pass (``shaders/world_prefilter.frag.glsl``) of
its count of GGX directions per texel (a Hammersley set) over a source of the image
box-filtered to a size that holds what its lobe shows (the world's SH reduction pass,
``sh_light.WORLD_REDUCE``: a 4K image is read once per source, never by Python), into one atlas
(``LEVELS`` stacked upwards). It is kept per image and World › Sun clamp until the image changes
(``TextureCache.world_prefiltered``): a frame pays a lookup; final renders find it in the
extension's store by the content of the image (``engine/store.py``). A constant world needs none (its
SH light is exact for every lobe).

Where the world's sun took the light above its threshold (``sun.py``), the sources are clamped
to it as the SH light is, so the sun is not reflected twice.
"""

import numpy as np

from ....shaders.loader import Program

# (Principled roughness, width, height, source width, GGX directions a texel) of each
# prefiltered level, in order of roughness, one every LEVEL_STEP: the level's GGX lobe is a few
# texels of its source wide; the wider lobes, over fewer texels, take more directions (a bright
# patch of the image under a wide lobe is what their noise would show).
LEVEL_STEP = 0.2
LEVELS = (
    (0.2, 256, 128, 512, 256),
    (0.4, 128, 64, 128, 512),
    (0.6, 64, 32, 64, 1024),
    (0.8, 64, 32, 32, 1024),
    (1.0, 64, 32, 32, 1024),
)
ATLAS_WIDTH = max(level[1] for level in LEVELS)


def level_rows():
    """(first row, width, height) of each level in the atlas (level 0 at the bottom)."""
    rows, y = [], 0
    for _rough, w, h, _src, _n in LEVELS:
        rows.append((y, w, h))
        y += h
    return rows


ATLAS_HEIGHT = sum(level[2] for level in LEVELS)


def levels_define():
    """WORLD_ENV_LEVELS: the levels as GLSL ``ivec3`` constructors (``world_env.glsl``)."""
    return ", ".join(f"ivec3({y}, {w}, {h})" for y, w, h in level_rows())


WORLD_PREFILTER = Program(
    name="world_prefilter",
    vertex="fullscreen.vert.glsl",
    fragment="world_prefilter.frag.glsl",
    libs=("lib/world_env.glsl",),
    vertex_in=(("VEC2", "pos"),),
    push_constants=(
        ("IVEC3", "target_level"),
        ("IVEC3", "source_level"),
        ("FLOAT", "level_alpha"),
        ("FLOAT", "source_clamp"),
        ("INT", "sample_count"),
    ),
    samplers=(("FLOAT_2D", "source"),),
    outputs=(("VEC4", "out_color"),),
)


def prefilter_environment(shaders, texture, premultiplied, clamp=0.0):
    """The prefiltered atlas (ATLAS_WIDTH x ATLAS_HEIGHT, RGBA32F) of Blender's GPU ``texture``
    of an Environment Texture (``premultiplied``: it holds premultiplied colour), each source
    texel clamped to ``clamp`` (0: none)."""
    import gpu
    from gpu_extras.batch import batch_for_shader

    from .sh_light import reduced_texture

    sources = {}
    for _rough, _w, _h, src, _n in LEVELS:
        if src not in sources:
            width = max(1, min(src, texture.width))
            height = max(1, min(src // 2, texture.height))
            sources[src] = reduced_texture(shaders, texture, premultiplied, width, height)
    atlas = gpu.types.GPUTexture((ATLAS_WIDTH, ATLAS_HEIGHT), format="RGBA32F")
    atlas.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 1.0))
    framebuffer = gpu.types.GPUFrameBuffer(color_slots=(atlas,))
    shader = shaders.get(WORLD_PREFILTER)
    batch = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
    clamp = float(clamp) if np.isfinite(clamp) and clamp > 0.0 else 0.0
    with framebuffer.bind():
        gpu.state.depth_test_set("NONE")
        gpu.state.blend_set("NONE")
        for (rough, _w, _h, src, count), (y, w, h) in zip(LEVELS, level_rows(), strict=True):
            source = sources[src]
            gpu.state.viewport_set(0, y, w, h)
            shader.bind()
            shader.uniform_sampler("source", source)
            shader.uniform_int("target_level", (y, w, h))
            shader.uniform_int("source_level", (0, source.width, source.height))
            shader.uniform_float("level_alpha", float(rough) ** 2)
            shader.uniform_float("source_clamp", clamp)
            shader.uniform_int("sample_count", count)
            batch.draw(shader)
    return atlas


def atlas_bytes():
    return ATLAS_WIDTH * ATLAS_HEIGHT * 16
