"""Subsurface scattering (a Principled BSDF's Subsurface Weight, a Subsurface Scattering node:
``materials.Material.subsurface``) as screen-space diffusion with Burley's profile (Golubev
2018; EEVEE's approach). The lit pass leaves the share of the diffuse that scatters below the
surface out of its colour (SUBSURFACE 1, lib/lit_inputs.glsl). After it, those surfaces alone
are drawn again over its z-buffer (``LitPass.draw_light``, LIGHT_PASS_SUBSURFACE): the light on
that share with its albedo, Burley's distance per channel and the view depth
(lib/subsurface.glsl). A full-frame pass then spreads the light entering each point over the
profile (shaders/subsurface.frag.glsl, lib/burley.glsl: points drawn anew each sample, so the
frame's samples converge to the profile's integral) and adds it to the sample's colour before
the film takes it; a one-sample frame draws more points.

Translucency (Jimenez et al. 2010): the same draw adds, at points a light reaches from behind,
its light through the thickness its shadow map holds in front of them, as far as Burley's
profile lets it through (lib/subsurface.glsl subsurface_through). Cycles' Random Walk is drawn
as the Burley profile fitted to it (``node_sss_walk``, tools/fit_random_walk.py): wider, and
leaving the surface unlike a Lambertian one.

What stays approximate is said once in the render report: the diffusion is over what the
camera sees (no light from hidden sides), the profile isotropic (no Anisotropy), light through
thin parts only from lights with a shadow map, and a blended surface's share stays on its
surface. A capture (a Plane probe's mirror, a cube's face) draws the share as diffuse.

Wanted where the camera sees a subsurface material; a frame without one pays nothing."""

from ....shaders.loader import Program, ProgramPart
from ...gpu_pool import new_texture
from .base import Feature, LitPart, outputs_of

TAPS = 16  # points a pixel and sample in a frame of several samples
TAPS_ONE_SAMPLE = 48  # in a one-sample frame (the viewport while the view moves)
LIGHT_PASS_SUBSURFACE = 7  # lib/lit_surface.glsl
SUBSURFACE_TERM = 6  # the Subsurface Light debug view's DEBUG_TERM: surfaces write 0, the diffusion adds its light

# The lit pass's variant: the share below the surface left out (blended surfaces keep theirs).
SPLIT = LitPart(
    program=ProgramPart("sss", defines=(("SUBSURFACE", 1),)),
    blended=ProgramPart("sss_blended", defines=(("SUBSURFACE", 0),)),
)
# The subsurface draw's part: that share's light, its albedo and depth, Burley's distances.
LIGHT = ProgramPart(
    "sss_light",
    libs=("lib/subsurface.glsl",),
    outputs=(("VEC4", "out_sss_albedo"), ("VEC4", "out_sss_radius")),
    defines=(("LIGHT_PASS", LIGHT_PASS_SUBSURFACE),),
)
DIFFUSION = Program(
    name="subsurface",
    vertex="fullscreen.vert.glsl",
    fragment="subsurface.frag.glsl",
    libs=("lib/burley.glsl", "lib/material.glsl"),
    vertex_in=(("VEC2", "pos"),),
    push_constants=(
        ("MAT4", "projection"),
        ("VEC2", "viewport_size"),
        ("FLOAT", "is_ortho"),
        ("INT", "sample_index"),
        ("INT", "taps"),
    ),
    samplers=(("FLOAT_2D", "sss_light"), ("FLOAT_2D", "sss_albedo"), ("FLOAT_2D", "sss_radius")),
)

APPROXIMATE = (
    "Penumbra: subsurface scattering is Burley diffusion over what the camera sees (isotropic; Random Walk as "
    "the profile fitted to it; light through thin parts from lights with shadow maps alone)"
)


def sees_subsurface(draws):
    return any(m is not None and m.subsurface for d in draws if d.instance.camera for m in (d.instance.materials or ()))


def _select(material, blended):
    return not blended and material is not None and material.subsurface


class Subsurface(Feature):
    name = "subsurface"

    def __init__(self, renderer):
        super().__init__(renderer)
        self.targets = None  # (light, albedo and depth, distances): RGBA32F at the film's size
        self.scratch = []  # the other techniques' outputs the subsurface draw writes (not kept)
        self._fbs = {}

    def wanted(self, frame):
        shown = frame.debug.id == "NONE" or (frame.debug.lit and frame.debug.term == SUBSURFACE_TERM)
        return shown and sees_subsurface(frame.draws)

    def plan(self, frame):
        frame.stats.messages.append(APPROXIMATE)

    def _ensure(self, size, scratch):
        pool = self.renderer.caches.pool
        if self.targets is not None and (self.targets[0].width, self.targets[0].height) != tuple(size):
            self._give()
        if self.targets is None:
            self.targets = tuple(new_texture(pool, size, "RGBA32F") for _ in range(3))
        while len(self.scratch) < scratch:
            self.scratch.append(new_texture(pool, size, "RGBA32F"))

    def _framebuffer(self, film, outputs):
        import gpu

        if outputs not in self._fbs:
            light, albedo, radius = self.targets
            slots = (light, *self.scratch[:outputs], albedo, radius)
            self._fbs[outputs] = gpu.types.GPUFrameBuffer(depth_slot=film.zbuffer, color_slots=slots)
        return self._fbs[outputs]

    def lit(self, frame, sample):
        return LitPart() if sample.settle_test else SPLIT

    def after_lit(self, frame, sample):
        """The sample's subsurface draw and its diffusion, added to the sample's colour."""
        if sample.settle_test:
            return
        from mathutils import Matrix

        film = self.renderer.film
        outputs = outputs_of(sample.data.parts)
        with frame.clock.stage("subsurface"):
            self._ensure(film.size, outputs)
            for target in self.targets:
                target.clear(format="FLOAT", value=(0.0, 0.0, 0.0, 0.0))
            fb = self._framebuffer(film, outputs)
            self.renderer.lit_pass.draw_light(sample, (fb, fb), LIGHT, select=_select)
            camera = sample.view_camera
            light, albedo, radius = self.targets
            film.fullscreen(
                DIFFUSION,
                film.fb_color,
                {"sss_light": light, "sss_albedo": albedo, "sss_radius": radius},
                {
                    "projection": Matrix(camera.projection.tolist()),
                    "viewport_size": tuple(float(x) for x in film.size),
                    "is_ortho": 1.0 if camera.is_ortho else 0.0,
                    "sample_index": int(sample.index),
                    "taps": TAPS if frame.accumulate else TAPS_ONE_SAMPLE,
                },
                "ADDITIVE_PREMULT",
            )
            frame.stats.subsurface_samples += 1

    def memory_bytes(self, frame):
        if self.targets is None:
            return 0
        return 16 * (3 + len(self.scratch)) * frame.size[0] * frame.size[1]

    def _give(self):
        pool = self.renderer.caches.pool
        textures = [*(self.targets or ()), *self.scratch]
        if pool is not None and textures:
            pool.give(textures)
        self.targets, self.scratch, self._fbs = None, [], {}

    def release(self):
        self._give()
