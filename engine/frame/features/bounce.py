"""One diffuse bounce from reflective shadow maps (Light Paths > Diffuse Bounces at 1;
Dachsbacher and Stamminger 2005; lib/indirect_rsm.glsl): the frame's shadow maps also hold
what each light sees (albedo and normal, ``shadow_maps``), and each pixel gathers
``indirect_samples`` texels of them per light and sample.

Off (not registered), the maps hold depth alone and the lit pass gathers nothing."""

from ....shaders.loader import ProgramPart
from ..frame_data import indirect_samples
from ..programs import RSM_FLUX_SAMPLER, RSM_NORMAL_SAMPLER
from .base import Feature, LitPart


def gather_part(texels):
    """The lit program's part that gathers the bounce, ``texels`` per light and sample."""
    return ProgramPart(
        "rsm",
        libs=("lib/indirect_rsm.glsl",),
        samplers=(("FLOAT_2D", RSM_FLUX_SAMPLER), ("FLOAT_2D", RSM_NORMAL_SAMPLER)),
        defines=(("INDIRECT_RSM", True), ("RSM_SAMPLES", int(texels))),
    )


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
            program=gather_part(indirect_samples(frame.settings)),
            samplers={RSM_FLUX_SAMPLER: atlas.flux, RSM_NORMAL_SAMPLER: atlas.normal},
        )
