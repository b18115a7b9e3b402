"""Shadow-map resources and the depth pass.

All maps of a frame are layers of one float 2D-array texture, so the lit pass binds a single
sampler whatever the number of shadowed lights. A light that casts no shadow, or has no caster
in reach, gets no layer and costs nothing.
"""

from dataclasses import dataclass

import numpy as np

from . import lightspace
from .programs import SHADOW_DEPTH


@dataclass
class ShadowView:
    """One rendered map: where it lives and how world points reach it."""

    layer: int
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
    """The array texture, its depth buffer and per-layer framebuffers of one engine instance."""

    def __init__(self):
        self.size = 0
        self.layers = 0
        self.texture = None
        self._zbuffer = None
        self._framebuffers = []

    def ensure(self, size, layers):
        import gpu

        layers = max(1, layers)
        if self.texture is not None and self.size == size and self.layers >= layers:
            return
        self.free()
        self.size = size
        self.layers = layers
        self.texture = gpu.types.GPUTexture((size, size), layers=layers, format="R32F")
        self.texture.filter_mode(False)
        self._zbuffer = gpu.types.GPUTexture((size, size), format="DEPTH_COMPONENT32F")
        self._framebuffers = [
            gpu.types.GPUFrameBuffer(
                depth_slot=self._zbuffer, color_slots=({"texture": self.texture, "layer": i},)
            )
            for i in range(layers)
        ]

    @property
    def memory_bytes(self):
        if self.texture is None:
            return 0
        return self.size * self.size * (4 * self.layers + 4)

    def free(self):
        self._framebuffers = []
        self.texture = None
        self._zbuffer = None
        self.size = 0
        self.layers = 0

    def render_layer(self, layer, view_proj, draws, shaders, cull_front, stats):
        """Rasterise ``draws`` [(batch, model matrix)] into ``layer``."""
        import gpu
        from mathutils import Matrix

        shader = shaders.get(SHADOW_DEPTH)
        fb = self._framebuffers[layer]
        vp = Matrix(view_proj.tolist())
        with fb.bind():
            gpu.state.viewport_set(0, 0, self.size, self.size)
            fb.clear(color=(1.0, 1.0, 1.0, 1.0), depth=1.0)
            gpu.state.depth_test_set("LESS")
            gpu.state.depth_mask_set(True)
            shader.bind()
            shader.uniform_float("light_view_proj", vp)
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
