"""The world's light from its Environment Texture, on the GPU (``TextureCache.world_sh``).

A world whose Background reads an Environment Texture lights the scene through order-2
spherical harmonics of the image (``materials.equirect_sh``). They are projected from the
image box-filtered to at most 128 x 64 texels by one fullscreen pass over Blender's GPU
texture (``shaders/world_reduce.frag.glsl``) and a read-back of that small image: the image's
pixels are never read into Python, and an F12 render of a large HDRI pays a pass and a
128 x 64 read-back, not a conversion of the image.
"""

import dataclasses

from ....shaders.loader import Program
from ...scene.materials import equirect_sh
from ...scene.textures import world_background

# The world's Environment Texture box-filtered to a small image, read back for its SH light
# (``world/sh_light.py``).
WORLD_REDUCE = Program(
    name="world_reduce",
    vertex="fullscreen.vert.glsl",
    fragment="world_reduce.frag.glsl",
    vertex_in=(("VEC2", "pos"),),
    push_constants=(("VEC2", "target_size"), ("FLOAT", "env_premultiplied")),
    samplers=(("FLOAT_2D", "env"),),
    outputs=(("VEC4", "out_color"),),
)


def with_sh_light(world, textures, shaders):
    """``world`` (a ``materials.World``) with its SH light: a world whose Environment Texture's
    light is not yet known (``sh`` None) gets it from ``textures`` (cached per image)."""
    if world is None or world.image is None or world.sh is not None:
        return world

    def reduce(texture, premultiplied, width, height):
        return reduce_environment(shaders, texture, premultiplied, width, height)

    sh = textures.world_sh(world.image, reduce) * world.strength
    env = textures.world_env(world.image)
    if world.rotation is not None and env is not None:  # a Mapping node turns the image
        sh = equirect_sh(env, world.rotation) * world.strength
    env = env * world.strength if env is not None else None
    return dataclasses.replace(world, sh=sh, background=world_background(sh), env=env)


def reduce_environment(shaders, texture, premultiplied, width, height):
    """``texture`` box-filtered to ``width`` x ``height`` texels on the GPU, read back as an
    array (height, width, 4), row 0 at the bottom."""
    from ..film import texture_array

    return texture_array(reduced_texture(shaders, texture, premultiplied, width, height), 4)


def reduced_texture(shaders, texture, premultiplied, width, height):
    """``texture`` box-filtered to ``width`` x ``height`` texels on the GPU (RGBA32F, straight
    colour, finite)."""
    import gpu
    from gpu_extras.batch import batch_for_shader

    target = gpu.types.GPUTexture((width, height), format="RGBA32F")
    framebuffer = gpu.types.GPUFrameBuffer(color_slots=(target,))
    shader = shaders.get(WORLD_REDUCE)
    batch = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
    with framebuffer.bind():
        gpu.state.viewport_set(0, 0, width, height)
        gpu.state.depth_test_set("NONE")
        gpu.state.blend_set("NONE")
        shader.bind()
        shader.uniform_sampler("env", texture)
        shader.uniform_float("target_size", (float(width), float(height)))
        shader.uniform_float("env_premultiplied", float(premultiplied))
        batch.draw(shader)
    return target
