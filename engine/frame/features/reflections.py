"""Reflections of the scene in glossy lobes (lib/ssr.glsl, lit_world.glsl SSR): every sample of a
frame after its first traces, for each lobe of Principled roughness under 0.5 (fading out from
0.4), one ray in screen space
against a camera depth prepass (drawn once a call of the frame), and where the ray meets a
surface the lobe reflects the frame's image there as the samples so far made it
(``Film.mean_into``: the world's ratio and every other technique's resolve included), instead
of the world's light. A mirror shows the objects beside it, a polished floor what stands on
it, and through the samples (each draws its lobe's direction and its steps anew) the
reflection converges: sharp where the lobe is sharp.

What the screen does not hold (behind the camera, off the image, behind what is in front)
the ray does not meet: the lobe keeps the world's light, unshadowed there. The first sample
of a frame (it has no image yet) and a one-sample frame (the viewport while the view moves)
take the world's light alone: a viewport frame costs nothing more.

The prepass is drawn once a frame, through the frame's camera at the pixels' centres (where
the film's image lies), at the sample that first traces, and the rays are traced through that
camera (``ssr_view``, ``ssr_view_proj``), whatever the sample's pixel offset or point of the
lens: the viewport, which draws a frame's samples one call at a time, keeps it over its calls
and so shows what the final render of as many samples does. With motion blur the rays see the
scene where that sample put it.

Wanted in frames of several samples with Screen Space Reflections on whose surfaces may have
such a lobe (a material whose roughness is under 0.5, or comes from a texture or a node tree);
a scene of rough or matte materials pays nothing (``reflective_materials``).

Off (not registered), glossy lobes take the world's light alone."""

import dataclasses

import numpy as np

from ....shaders.loader import ProgramPart
from ...gpu_pool import new_texture
from ...shadows import lightspace
from ..draw_list import longest_ray, reflective_materials
from ..world.occlusion import WorldAO
from .base import NO_PART, Feature, LitPart

# A surface's thickness, as a fraction of its depth, that a ray behind it still meets.
THICKNESS = 0.02
STEPS = 32

DEPTH_SAMPLER = "ssr_depth"
RADIANCE_SAMPLER = "ssr_radiance"

PART = ProgramPart(
    "ssr",
    samplers=(("FLOAT_2D", DEPTH_SAMPLER), ("FLOAT_2D", RADIANCE_SAMPLER)),
    defines=(("SSR", True), ("SSR_STEPS", STEPS)),
)
# The settle test's: a pixel a later sample traces never settles (lit_settle.frag.glsl).
SETTLE_PART = ProgramPart("ssr_settle", defines=(("SSR_SETTLE", True),))
# The REFLECTIONS debug view's: the lit debug variant writes where the rays met the scene
# (lit_debug.frag.glsl), from every sample (``DEBUG_PART`` where a sample does not trace).
DEBUG_VIEW = "REFLECTIONS"
DEBUG_PART = ProgramPart("ssr_debug", defines=(("DEBUG_REFLECTIONS", True),))
DEBUG_TRACE_PART = ProgramPart(
    "ssr_debug_trace",
    samplers=PART.samplers,
    defines=PART.defines + (("DEBUG_REFLECTIONS", True),),
)


class Reflections(Feature):
    name = "reflections"

    def __init__(self, renderer):
        super().__init__(renderer)
        self.prepass = WorldAO(renderer.caches.pool)  # its camera depth (the horizons unused)
        self.radiance = None  # RGBA32F: the frame's image so far
        self._framebuffer = None
        self._rows = None  # the prepass camera's rows, once this frame drew it
        self._distance = 0.0
        self._traced = False  # this frame traces (``wanted`` but for the debug view)

    @staticmethod
    def _traced_in(frame):
        debug = frame.debug.id == DEBUG_VIEW
        return (
            (debug or (frame.accumulate and frame.sample_count > 1))
            and bool(getattr(frame.settings, "screen_space_reflections", True))
            and reflective_materials(frame.draws)
        )

    def wanted(self, frame):
        return frame.debug.id == DEBUG_VIEW or self._traced_in(frame)

    def plan(self, frame):
        # A later call of the same frame (the viewport's next samples: nothing changed, or the
        # frame would start afresh) keeps the prepass the frame drew.
        if frame.request.samples[0] == 0 or self.prepass.size != tuple(frame.size):
            self._rows = None
        self._traced = self._traced_in(frame)
        self._distance = longest_ray(frame.draws) if self._traced else 0.0

    def traces(self, frame, sample):
        """Sample ``sample`` traces: not the frame's first, pilot or settle test, with an image
        so far (in the REFLECTIONS view every sample, the first too)."""
        if not self._traced or sample.pilot or sample.settle_test or not self._distance > 0.0:
            return False
        return frame.debug.id == DEBUG_VIEW or (sample.index > 0 and self.renderer.film.weight_sum > 0.0)

    def _ensure(self, size):
        import gpu

        if self.radiance is not None and (self.radiance.width, self.radiance.height) == tuple(size):
            return
        self._give()
        self.radiance = new_texture(self.renderer.caches.pool, size, "RGBA32F")
        self._framebuffer = gpu.types.GPUFrameBuffer(color_slots=(self.radiance,))

    def before_lit(self, frame, sample):
        if not self.traces(frame, sample):
            return
        with frame.clock.stage("reflections"):
            if self._rows is None:
                camera = sample.camera
                fitted = lightspace.depth_fitted(camera.projection, camera.is_ortho, sample.depth_range)
                raster = dataclasses.replace(camera, projection=fitted)
                self.prepass.draw_depth(sample.draws, raster, frame.size, frame.origin, frame.caches, 0.5)
                view = np.asarray(raster.view, np.float64) @ lightspace.from_origin(frame.origin)
                self._rows = {"ssr_view": view, "ssr_view_proj": np.asarray(fitted, np.float64) @ view}
                frame.stats.reflection_prepasses += 1
            self._ensure(frame.size)
            self.renderer.film.mean_into(self._framebuffer)
            frame.stats.reflection_samples += 1

    def lit(self, frame, sample):
        debug = frame.debug.id == DEBUG_VIEW
        if sample.settle_test:
            return LitPart(program=SETTLE_PART) if self._traced else NO_PART
        if not self.traces(frame, sample):
            return LitPart(program=DEBUG_PART) if debug else NO_PART
        return LitPart(
            program=DEBUG_TRACE_PART if debug else PART,
            rows={"ssr_params": (self._distance, THICKNESS, 0.0, 0.0), **self._rows},
            samplers={DEPTH_SAMPLER: self.prepass.texture, RADIANCE_SAMPLER: self.radiance},
        )

    def memory_bytes(self, frame):
        if not frame.stats.reflection_prepasses or self.radiance is None:
            return 0
        return self.prepass.memory_bytes + 16 * self.radiance.width * self.radiance.height

    def _give(self):
        pool = self.renderer.caches.pool
        if pool is not None and self.radiance is not None:
            pool.give([self.radiance])
        self.radiance = self._framebuffer = None

    def release(self):
        self.prepass.release()
        self._give()
        self._rows = None
