"""What transmissive surfaces show through them (lib/refraction.glsl): a Principled BSDF's
Transmission Weight and a Glass BSDF (``materials.Material.transmits``). Their surfaces are
drawn after every other opaque one, over a copy of this sample's colour so far (the
``between`` of the lit pass: what they see through), and each pixel's refracted ray (one
interface, Snell's law, a GGX microfacet drawn anew each sample) is traced in screen space
against a camera depth prepass of what is not transmissive, drawn once a frame through the
frame's camera at the pixels' centres (the reflections' program, ``WorldAO.draw_depth``).
Where the ray meets nothing on the screen it takes the world's light along its direction.

Unlike the reflections, the first sample and one-sample frames (the viewport while the view
moves) refract too: what they read is this sample's own image of the opaque surfaces. What
stays approximate (one interface, no caustics, no dispersion, nothing seen through two
transmissive surfaces) is said once in the render report.

Wanted where the camera sees a transmissive surface; a frame without one pays nothing."""

import dataclasses

from ....shaders.loader import ProgramPart
from ...gpu_pool import new_texture
from ...shadows import lightspace
from ..draw_list import longest_ray
from ..film_programs import SCALED_COPY
from ..world.occlusion import WorldAO
from .base import Feature, LitPart

THICKNESS = 0.02  # a surface's thickness, as a fraction of its depth, that a ray behind it still meets
DEPTH_SAMPLER = "refr_depth"
BEHIND_SAMPLER = "refr_behind"

PART = ProgramPart(
    "refraction",
    samplers=(("FLOAT_2D", DEPTH_SAMPLER), ("FLOAT_2D", BEHIND_SAMPLER)),
    defines=(("REFRACTION", True),),
)

APPROXIMATE = (
    "Penumbra: transmissive surfaces refract at one interface, in screen space (no caustics, no "
    "dispersion, nothing seen through two of them)"
)


def transmissive(draw):
    """Whether every material of ``draw`` transmits (it is left out of the prepass)."""
    return all(m is not None and m.transmits for m in (draw.instance.materials or (None,)))


def sees_transmission(draws):
    return any(m is not None and m.transmits for d in draws if d.instance.camera for m in (d.instance.materials or ()))


class Refraction(Feature):
    name = "refraction"

    def __init__(self, renderer):
        super().__init__(renderer)
        self.prepass = WorldAO(renderer.caches.pool)  # its camera depth (the horizons unused)
        self.behind = None  # RGBA32F: this sample's colour of the opaque surfaces
        self._framebuffer = None
        self._drawn = False
        self._distance = 0.0

    def wanted(self, frame):
        return sees_transmission(frame.draws)

    def plan(self, frame):
        if frame.request.samples[0] == 0 or self.prepass.size != tuple(frame.size):
            self._drawn = False
        self._distance = longest_ray(frame.draws)
        frame.stats.messages.append(APPROXIMATE)

    def _ensure(self, size):
        import gpu

        if self.behind is not None and (self.behind.width, self.behind.height) == tuple(size):
            return
        self._give()
        self.behind = new_texture(self.renderer.caches.pool, size, "RGBA32F")
        self._framebuffer = gpu.types.GPUFrameBuffer(color_slots=(self.behind,))

    def before_lit(self, frame, sample):
        if sample.pilot or sample.settle_test:
            return
        with frame.clock.stage("refraction"):
            if not self._drawn:
                camera = sample.camera
                fitted = lightspace.depth_fitted(camera.projection, camera.is_ortho, sample.depth_range)
                raster = dataclasses.replace(camera, projection=fitted)
                draws = [d for d in sample.draws if not transmissive(d)]
                self.prepass.draw_depth(draws, raster, frame.size, frame.origin, frame.caches, 0.5)
                frame.stats.refraction_prepasses += 1
                self._drawn = True
            self._ensure(frame.size)

    def _copy(self, film, stats):
        """The colour the opaque surfaces left, into ``behind`` (the lit pass's ``between``)."""
        film.fullscreen(SCALED_COPY, self._framebuffer, {"src_color": film.color}, {"scale": 1.0})
        stats.refraction_samples += 1

    def lit(self, frame, sample):
        if sample.pilot or sample.settle_test or self.behind is None:
            return LitPart()
        return LitPart(
            program=PART,
            rows={"refr_params": (self._distance, THICKNESS, 0.0, 0.0)},
            samplers={DEPTH_SAMPLER: self.prepass.texture, BEHIND_SAMPLER: self.behind},
            between=self._copy,
        )

    def memory_bytes(self, frame):
        if not frame.stats.refraction_prepasses or self.behind is None:
            return 0
        return self.prepass.memory_bytes + 16 * self.behind.width * self.behind.height

    def _give(self):
        pool = self.renderer.caches.pool
        if pool is not None and self.behind is not None:
            pool.give([self.behind])
        self.behind = self._framebuffer = None

    def release(self):
        self.prepass.release()
        self._give()
        self._drawn = False
