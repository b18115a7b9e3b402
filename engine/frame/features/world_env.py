"""The world's Environment Texture in glossy lobes, prefiltered by roughness (lit_world.glsl
WORLD_ENV, ``world/prefilter.py``): a surface's specular world light reads the image about its
reflected direction, sharp for a mirror and blurred as its GGX lobe blurs it, instead of the
image's order-2 spherical harmonics (which ring and turn a mirror into coloured blotches).

Wanted where the world has an Environment Texture and the surfaces take the world's light
around the reflected direction (not with light portals, whose directions carry all of it). A
constant world needs none of it: its SH light is exact for every lobe, and a frame without an
image pays nothing.

Off (not registered), glossy lobes read the world's SH light."""

import numpy as np

from ....shaders.loader import ProgramPart
from ..world.prefilter import LEVEL_STEP, LEVELS, atlas_bytes, levels_define, prefilter_environment
from .base import Feature, LitPart

IMAGE_SAMPLER = "world_env_image"
ATLAS_SAMPLER = "world_env_atlas"

PART = ProgramPart(
    "env",
    samplers=(("FLOAT_2D", IMAGE_SAMPLER), ("FLOAT_2D", ATLAS_SAMPLER)),
    defines=(
        ("WORLD_ENV", True),
        ("WORLD_ENV_COUNT", len(LEVELS)),
        ("WORLD_ENV_STEP", float(LEVEL_STEP)),
        ("WORLD_ENV_LEVELS", levels_define()),
    ),
)


def source_clamp(world):
    """What the image's texels are clamped to before they are reflected, in the image's units:
    the world's sun threshold over the Background strength where the sun took the light above
    it (``world/sun.py``), else 0 (none)."""
    if world.sun_clamp is None or not world.strength > 0.0:
        return 0.0
    clamp = float(world.sun_clamp) / float(world.strength)
    return clamp if np.isfinite(clamp) and clamp > 0.0 else 0.0


def rotation_rows(world):
    """The frame block's rows of the rotation from world directions to the image's (its
    columns) and (strength, clamp, premultiplied, 0)."""
    turn = np.eye(3) if world.rotation is None else np.asarray(world.rotation, np.float64)[:3, :3]
    return {f"env_rotation_{axis}": (*map(float, turn[:, k]), 0.0) for k, axis in enumerate("xyz")}


class WorldEnvironment(Feature):
    name = "world_env"

    def __init__(self, renderer):
        super().__init__(renderer)
        self._part = None  # this frame's LitPart (the same for all of its samples)

    def wanted(self, frame):
        world = frame.snapshot.world
        return world is not None and world.image is not None and world.sh is not None and frame.world_sh

    def plan(self, frame):
        world = frame.snapshot.world
        textures, shaders = self.renderer.textures, self.renderer.shaders
        clamp = source_clamp(world)

        def build(texture, premultiplied):
            return prefilter_environment(shaders, texture, premultiplied, clamp)

        atlas = textures.world_prefiltered(world.image, clamp, build, atlas_bytes())
        premultiplied = float(textures.premultiplied(world.image))
        rows = rotation_rows(world)
        rows["env_params"] = (float(world.strength), clamp, premultiplied, 0.0)
        self._part = LitPart(
            program=PART,
            rows=rows,
            samplers={IMAGE_SAMPLER: textures.get(world.image), ATLAS_SAMPLER: atlas},
        )

    def lit(self, frame, sample):
        return self._part

    def capture(self, frame, sample):
        return self._part  # a capture's glossy lobes read the world's image too

    def resolve(self, frame):
        self._part = None  # the atlas stays in the texture cache (counted in its bytes)
