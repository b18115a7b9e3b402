"""One diffuse bounce from reflective shadow maps (Light Paths > Diffuse Bounces at 1;
Dachsbacher and Stamminger 2005; lib/indirect_rsm.glsl): the frame's shadow maps also hold
what each light sees (albedo and normal, ``shadow_maps``), and each pixel gathers
``indirect_samples`` texels of them per light and sample.

Off (not registered), the maps hold depth alone and the lit pass gathers nothing."""

from ..frame_data import indirect_samples
from ..programs import RSM_FLUX_SAMPLER, RSM_NORMAL_SAMPLER
from .base import Feature, LitPart


class Bounce(Feature):
    name = "bounce"

    def wanted(self, frame):
        return indirect_samples(frame.settings) > 0

    def plan(self, frame):
        # Maps hold every visible surface a light reaches, with its reflective targets.
        frame.reflective = True

    def lit(self, frame, sample):
        atlas = sample.atlas
        # Only where some light has a map, and the GPU gave the reflective targets.
        if atlas is None or not atlas.rsm or not any(i in sample.plan.lights for i in range(len(sample.lights))):
            return super().lit(frame, sample)
        return LitPart(
            variant={"indirect_samples": indirect_samples(frame.settings)},
            samplers={RSM_FLUX_SAMPLER: atlas.flux, RSM_NORMAL_SAMPLER: atlas.normal},
        )
