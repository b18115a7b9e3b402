"""The world's ambient occlusion (World > Ambient Occlusion; ``world/occlusion.py``,
lib/gtao.glsl): in a one-sample frame and the first sample of a frame of several, the world's
light is occluded by screen-space ground-truth ambient occlusion over a camera depth prepass,
its horizons marched at half resolution (the frame's first image shows contact shadows at once).

Off (not registered), no sample draws the prepass and the world's light is unoccluded."""

from ....shaders.loader import ProgramPart
from ..draw_list import corners_of
from ..frame_data import ao_row
from ..programs import AO_HORIZONS_SAMPLER, AO_SAMPLER
from ..sampling import ao_jitter, world_ao_distance, world_ao_sample
from ..world.occlusion import WorldAO
from .base import Feature, LitPart

# The lit program's part: the prepass's depth and the horizons marched over it (lib/gtao.glsl).
_OCCLUSION = ProgramPart(
    "ao", samplers=(("FLOAT_2D", AO_SAMPLER), ("FLOAT_2D", AO_HORIZONS_SAMPLER)), defines=(("WORLD_AO", True),)
)


class WorldOcclusion(Feature):
    name = "world_occlusion"

    def __init__(self, renderer):
        super().__init__(renderer)
        self.prepass = WorldAO(renderer.caches.pool)  # the camera depth prepass and its horizons

    def wanted(self, frame):
        """Not where light portals send the world's directions into every sample, nor where
        the world's light is under the frame's noise (occluding it could change no pixel), but
        in the WORLD_AO view, which shows the estimate."""
        if frame.cones:
            return False
        return not frame.world_negligible or frame.debug.id == "WORLD_AO"

    def plan(self, frame):
        # A sample with occlusion (a frame's first) takes no directions of the world: their
        # sequence starts at the next one.
        if frame.directions and frame.accumulate and self.occlusion(frame, 0) is not None:
            frame.first_directions = 1

    def occlusion(self, frame, s):
        """Sample ``s``'s occlusion: (distance, jitter) or None (``sampling.world_ao_sample``)."""
        snapshot = frame.snapshot
        world = snapshot.world if snapshot.world is not None else snapshot.world_color
        if not world_ao_sample(s, frame.accumulate, frame.settings, world, frame.debug.id):
            return None
        if frame.ao_distance is None:  # once a frame, where some sample occludes
            frame.ao_distance = world_ao_distance(frame.settings, corners_of(frame.draws)) if frame.draws else 0.0
        return (frame.ao_distance, ao_jitter(s)) if frame.ao_distance > 0.0 else None

    def prepare(self, frame, sample):
        # The pilot stands in for the first sample (settling).
        sample.ao = None if sample.settle_test else self.occlusion(frame, 0 if sample.pilot else sample.index)

    def before_lit(self, frame, sample):
        if sample.ao is None:
            return
        with frame.clock.stage("world ao"):
            raster = sample.cameras[0]
            self.prepass.draw(
                sample.draws, raster, frame.size, frame.origin, frame.caches, frame.stats, sample.alpha_offset
            )

    def lit(self, frame, sample):
        if sample.ao is None:
            return super().lit(frame, sample)
        prepass = self.prepass
        return LitPart(
            program=_OCCLUSION,
            rows=ao_row(sample.cameras[0].projection, frame.size, *sample.ao),
            samplers={AO_SAMPLER: prepass.texture, AO_HORIZONS_SAMPLER: prepass.horizons},
            begin=lambda block, stats: prepass.march(block, frame.caches.shaders, stats),
        )

    def memory_bytes(self, frame):
        return self.prepass.memory_bytes if frame.stats.ao_prepasses else 0

    def release(self):
        self.prepass.release()
