"""Shadow-map resources and the depth pass.

All maps of a frame are tiles of one float texture (an atlas), so the lit pass binds a single
sampler whatever the number of shadowed lights. A light that casts no shadow, or has no caster
in reach, gets no tile and costs nothing.
"""

import math
from dataclasses import dataclass

import numpy as np

from . import lightspace
from .programs import SHADOW_DEPTH


@dataclass
class ShadowView:
    """One rendered map: where it lives and how world points reach it."""

    tile: int
    view_proj: np.ndarray  # light view-projection (clip space)
    texel_world: float  # size of one texel in world units at the map
    depth_per_world: float  # normalised depth per world unit

    @property
    def matrix(self):
        """World -> shadow texture space [0, 1]^3."""
        return lightspace.BIAS_MATRIX @ self.view_proj


def plan_sun(light, world_points, map_size):
    """Light-space fit for a sun; ``None`` when there is nothing to cast a shadow."""
    fit = lightspace.fit_sun_ortho(light.direction, world_points, map_size)
    if fit is None:
        return None
    view, proj, texel = fit
    depth_per_world = proj[2, 2] * -0.5  # ortho: NDC z spans 2/(far-near); [0,1] depth half that
    return view, proj, texel, depth_per_world


class ShadowMaps:
    """The shadow atlas of one engine instance: every map of a frame is a square tile of one
    float texture (tiles in a grid, ``columns`` wide), so the lit pass binds one sampler
    whatever the number of shadowed lights, on every Blender line."""

    def __init__(self):
        self.size = 0
        self.count = 0
        self.columns = 1
        self.texture = None
        self._zbuffer = None
        self._framebuffer = None

    @staticmethod
    def grid(count):
        columns = max(1, math.ceil(math.sqrt(count)))
        rows = max(1, math.ceil(count / columns))
        return columns, rows

    def ensure(self, size, count):
        import gpu

        count = max(1, count)
        columns, rows = self.grid(count)
        if self.texture is not None and self.size == size and self.columns == columns and self.count >= count:
            return
        self.free()
        self.size, self.count, self.columns = size, columns * rows, columns
        dims = (columns * size, rows * size)
        # Read with texelFetch only, so the sampler's filter mode never matters.
        self.texture = gpu.types.GPUTexture(dims, format="R32F")
        self._zbuffer = gpu.types.GPUTexture(dims, format="DEPTH_COMPONENT32F")
        self._framebuffer = gpu.types.GPUFrameBuffer(depth_slot=self._zbuffer, color_slots=(self.texture,))

    def tile_origin(self, tile):
        return (tile % self.columns) * self.size, (tile // self.columns) * self.size

    @property
    def memory_bytes(self):
        if self.texture is None:
            return 0
        return self.texture.width * self.texture.height * 8

    def free(self):
        self._framebuffer = None
        self.texture = None
        self._zbuffer = None
        self.size = self.count = 0
        self.columns = 1

    def clear(self):
        with self._framebuffer.bind():
            self._framebuffer.clear(color=(1.0, 1.0, 1.0, 1.0), depth=1.0)

    def render_tile(self, tile, view_proj, draws, shaders, cull_front, stats):
        """Rasterise ``draws`` [(batch, model Matrix, det)] into atlas tile ``tile``."""
        import gpu
        from mathutils import Matrix

        shader = shaders.get(SHADOW_DEPTH)
        x0, y0 = self.tile_origin(tile)
        with self._framebuffer.bind():
            gpu.state.viewport_set(x0, y0, self.size, self.size)
            gpu.state.depth_test_set("LESS")
            gpu.state.depth_mask_set(True)
            shader.bind()
            shader.uniform_float("light_view_proj", Matrix(view_proj.tolist()))
            for batch, model, det in draws:
                if cull_front:
                    gpu.state.face_culling_set("FRONT")
                    gpu.state.front_facing_set(det < 0.0)
                shader.uniform_float("model", model)
                batch.draw(shader)
                stats.draws += 1
            gpu.state.face_culling_set("NONE")
            gpu.state.front_facing_set(False)
            gpu.state.depth_test_set("NONE")
            gpu.state.depth_mask_set(False)
        stats.passes += 1
        stats.shadow_maps += 1
