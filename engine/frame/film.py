"""The film: a frame's render targets (colour, and the passes' depth, shadow, normal and
emission), the float32 accumulation of its samples and their resolve into the filtered
average, and read-back to numpy. Targets come from the engine's ``gpu_pool.TexturePool`` in
final renders and go back to it on ``release``."""

from dataclasses import dataclass

import numpy as np

from ..gpu_pool import new_texture
from ..post.base import PostContext
from .programs import SCALED_COPY, SCALED_COPY_SHADOW


@dataclass
class FrameOutput:
    color: object  # GPUTexture, scene-linear RGBA float
    depth: object  # GPUTexture, view-space distance along the camera axis
    shadow: object  # GPUTexture, fraction of direct light not blocked (1 for background)
    stats: object  # stats.FrameStats
    width: int
    height: int
    lit: object = None  # GPUTexture, the lit pass before the post stack
    normal: object = None  # GPUTexture, world-space shading normal (0 for the background)
    depth_data: object = None  # arrays of the centred sample when several were accumulated
    normal_data: object = None
    emission: object = None  # GPUTexture, the Emission pass (when asked for)

    def emission_array(self):
        return texture_array(self.emission, 4)[..., :3]

    def normal_array(self):
        if self.normal_data is not None:
            return self.normal_data[..., :3]
        return texture_array(self.normal, 4)[..., :3]

    def lit_array(self):
        return texture_array(self.lit, 4)

    def color_array(self):
        return texture_array(self.color, 4)

    def depth_array(self):
        if self.depth_data is not None:
            return self.depth_data
        return texture_array(self.depth, 1)[..., 0]

    def shadow_array(self):
        return texture_array(self.shadow, 1)[..., 0]


def buffer_array(buf):
    """A ``gpu.types.Buffer`` as a C-ordered numpy array of its dimensions.

    Blender 4.5's buffer protocol reports reversed strides, so ``np.asarray`` alone scrambles
    multi-dimensional data there; reading the memory in its own order is right on every line."""
    a = np.asarray(buf)
    return a.ravel(order="K").reshape(tuple(buf.dimensions))


def texture_array(texture, channels):
    """Read a float texture back as an array (height, width, channels), row 0 at the bottom."""
    return buffer_array(texture.read()).astype(np.float32, copy=False).reshape(texture.height, texture.width, channels)


class Film:
    """The targets of one renderer at the frame's size. The lit pass draws into ``fb_color``
    (colour and z-buffer), ``fb`` (with the depth, shadow and normal passes) or ``fb_emit``
    (with Emission too); a multi-sample frame adds each sample into the accumulation targets
    (``accumulate``) and ``resolve`` writes their filtered average back into ``color`` (and
    ``shadow``), which the post stack and the passes then read as a single sample's."""

    def __init__(self, shaders, pool=None):
        self.shaders = shaders
        self.pool = pool
        self.size = None
        self.color = self.zbuffer = self.depth = self.shadow = self.normal = self.emission = None
        self.fb = self.fb_color = self.fb_emit = None
        self.post_ctx = None  # the post stack's targets at this size
        self.centre = None  # (depth, normal) arrays of a multi-sample frame's centred sample
        self._accum_color = self._accum_shadow = self._accum_fb = self._resolve_fb = None
        self._emission_targets = None  # (accumulation, its framebuffer, the resolve's framebuffer)
        self._weight_sum = 0.0
        self._fullscreen_batch = None

    # --- targets --------------------------------------------------------------------------

    def ensure(self, width, height, aux, emission=False):
        """The lit pass's targets at this size; the auxiliary ones (depth, shadow, normal) only
        once a frame asks for them, the Emission pass's likewise."""
        import gpu

        if self.size != (width, height):
            self._give_targets()
            self.color = new_texture(self.pool, (width, height), "RGBA32F")
            self.zbuffer = new_texture(self.pool, (width, height), "DEPTH_COMPONENT32F")
            self.fb_color = gpu.types.GPUFrameBuffer(depth_slot=self.zbuffer, color_slots=(self.color,))
            if self.post_ctx is not None:
                self.post_ctx.release()
            self.post_ctx = PostContext(self.shaders, width, height, texture_pool=self.pool)
            self.size = (width, height)
        if aux and self.fb is None:
            self.depth = new_texture(self.pool, (width, height), "R32F")
            self.shadow = new_texture(self.pool, (width, height), "R32F")
            self.normal = new_texture(self.pool, (width, height), "RGBA16F")
            self.fb = gpu.types.GPUFrameBuffer(
                depth_slot=self.zbuffer, color_slots=(self.color, self.depth, self.shadow, self.normal)
            )
        if emission and self.fb_emit is None:
            self.emission = new_texture(self.pool, (width, height), "RGBA32F")
            self.fb_emit = gpu.types.GPUFrameBuffer(
                depth_slot=self.zbuffer,
                color_slots=(self.color, self.depth, self.shadow, self.normal, self.emission),
            )

    def clear(self, background, aux, emission):
        """Every target the lit pass writes, cleared to what the background is: ``background``
        colour (premultiplied), and for the passes an "infinitely" far depth (as Blender's own
        Depth pass), full light, no normal, no emission."""
        self.color.clear(format="FLOAT", value=background)
        if aux:
            self.depth.clear(format="FLOAT", value=(1e10,))
            self.shadow.clear(format="FLOAT", value=(1.0,))
            self.normal.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
        if emission:
            self.emission.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))

    def target_bytes(self, aux, accumulate):
        """Bytes per pixel of the frame's targets: colour, z-buffer, and with ``aux`` depth,
        shadow and normal; accumulation adds colour (and shadow)."""
        per_pixel = 16 + 4 + (4 + 4 + 8 if aux else 0)
        if accumulate:
            per_pixel += 16 + (4 if aux else 0)
        return per_pixel * self.size[0] * self.size[1]

    # --- samples --------------------------------------------------------------------------

    def begin(self, aux, emission, fresh):
        """Before a multi-sample frame's samples: the accumulation targets, cleared when the
        frame starts afresh (``fresh``)."""
        self._ensure_accumulation(aux)
        if fresh:
            self._accum_color.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
            if self._accum_shadow is not None:
                self._accum_shadow.clear(format="FLOAT", value=(0.0,))
            if emission:
                self._emission_accumulation().clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
            self._weight_sum = 0.0

    def accumulate(self, weight, aux, emission):
        """accumulation += weight * this sample (colour, shadow with ``aux``, and Emission)."""
        self._scaled_copy(self._accum_fb, (self.color, self.shadow), weight, aux, blend="ADDITIVE_PREMULT")
        if emission:
            _accum, accum_fb, _resolve_fb = self._emission_targets
            self.fullscreen(SCALED_COPY, accum_fb, {"src_color": self.emission}, {"scale": weight}, "ADDITIVE_PREMULT")
        self._weight_sum += weight

    def keep_centre(self):
        """Keep the centred sample's depth and normal (a multi-sample frame's Depth and Normal
        passes are that sample's, not an average)."""
        self.centre = (texture_array(self.depth, 1)[..., 0].copy(), texture_array(self.normal, 4).copy())

    def resolve(self, aux, emission):
        """The filtered average (accumulation / total weight) into the colour (and shadow,
        Emission) targets, which the post stack and the passes read as a single-sample frame's."""
        import gpu

        with_shadow = aux and self._accum_shadow is not None
        if self._resolve_fb is None or self._resolve_fb[0] != (self.size, with_shadow):
            slots = (self.color, self.shadow) if with_shadow else (self.color,)
            self._resolve_fb = ((self.size, with_shadow), gpu.types.GPUFrameBuffer(color_slots=slots))
        inverse = 1.0 / self._weight_sum if self._weight_sum > 0.0 else 0.0
        self._scaled_copy(self._resolve_fb[1], (self._accum_color, self._accum_shadow), inverse, aux)
        if emission:
            accum, _accum_fb, resolve_fb = self._emission_targets
            self.fullscreen(SCALED_COPY, resolve_fb, {"src_color": accum}, {"scale": inverse})

    def _ensure_accumulation(self, aux):
        """The float32 accumulation targets of a multi-sample frame (colour, and shadow for a
        final render's Shadow pass), and the targets their resolve writes."""
        import gpu

        width, height = self.size
        if self._accum_color is None or (self._accum_color.width, self._accum_color.height) != (width, height):
            self._give([self._accum_color, self._accum_shadow])
            self._accum_color = new_texture(self.pool, (width, height), "RGBA32F")
            self._accum_shadow = None
            self._accum_fb = gpu.types.GPUFrameBuffer(color_slots=(self._accum_color,))
        if aux and self._accum_shadow is None:
            self._accum_shadow = new_texture(self.pool, (width, height), "R32F")
            self._accum_fb = gpu.types.GPUFrameBuffer(color_slots=(self._accum_color, self._accum_shadow))
        self.centre = None

    def _emission_accumulation(self):
        """The Emission pass's accumulation target (and the framebuffers that add to it and
        resolve it into the pass's target), made on first use at this size."""
        import gpu

        if self._emission_targets is None:
            width, height = self.size
            accum = new_texture(self.pool, (width, height), "RGBA32F")
            self._emission_targets = (
                accum,
                gpu.types.GPUFrameBuffer(color_slots=(accum,)),
                gpu.types.GPUFrameBuffer(color_slots=(self.emission,)),
            )
        return self._emission_targets[0]

    def _scaled_copy(self, framebuffer, sources, scale, aux, blend="NONE"):
        """framebuffer (<blend>)= scale * sources: colour, and shadow when ``aux`` and the
        accumulation carries it."""
        with_shadow = aux and self._accum_shadow is not None
        samplers = {"src_color": sources[0]}
        if with_shadow:
            samplers["src_shadow"] = sources[1]
        program = SCALED_COPY_SHADOW if with_shadow else SCALED_COPY
        self.fullscreen(program, framebuffer, samplers, {"scale": scale}, blend)

    def fullscreen(self, program, framebuffer, samplers, uniforms, blend="NONE"):
        """One full-frame triangle of ``program`` into ``framebuffer``."""
        import gpu
        from gpu_extras.batch import batch_for_shader

        shader = self.shaders.get(program)
        if self._fullscreen_batch is None:
            self._fullscreen_batch = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
        width, height = self.size
        with framebuffer.bind():
            gpu.state.viewport_set(0, 0, width, height)
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set(blend)
            shader.bind()
            for name, tex in samplers.items():
                shader.uniform_sampler(name, tex)
            if any(pc[1] == "origin" for pc in program.push_constants):
                shader.uniform_int("origin", (0, 0))
            for name, value in uniforms.items():
                shader.uniform_float(name, value)
            self._fullscreen_batch.draw(shader)
            gpu.state.blend_set("NONE")

    # --- resources ------------------------------------------------------------------------

    def _give(self, textures):
        """Hand textures back to the pool (final renders); without a pool they are freed when
        the last reference goes."""
        if self.pool is not None:
            self.pool.give([t for t in textures if t is not None])

    def _give_targets(self):
        """Every size-bound target back to the pool: a new size, or the end of the render."""
        accum = self._emission_targets[0] if self._emission_targets is not None else None
        self._give(
            [
                self.color,
                self.zbuffer,
                self.depth,
                self.shadow,
                self.normal,
                self.emission,
                self._accum_color,
                self._accum_shadow,
                accum,
            ]
        )
        self.fb = self.fb_color = self.fb_emit = self._accum_fb = self._resolve_fb = None
        self._emission_targets = None
        self.color = self.zbuffer = self.depth = self.shadow = self.normal = self.emission = None
        self._accum_color = self._accum_shadow = None
        self.size = None

    def release(self):
        """Give every target back to the pool: at the end of a final render, inside its GPU
        context."""
        self._give_targets()
        if self.post_ctx is not None:
            self.post_ctx.release()
            self.post_ctx = None
