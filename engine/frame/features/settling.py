"""Settling (``settle.py``): before a frame's second sample, a pilot sample (the centred pixel,
every light at its centre) and the settle test's variant of the lit pass over its surfaces
(SETTLE_TEST, lit_settle.frag.glsl) flag the pixels no later sample can change by the Noise
Threshold's settle share; the film's settle pass then keeps the pilot's value there and those
pixels take no more samples.

Only in frames of several samples with adaptive sampling's settling on, without motion blur
(a moving surface's pixels change with the sample's time) and with depth of field only where
no blur reaches past the test's neighbourhood. Off (not registered), every pixel takes every
sample the frame's other checks leave it."""

import dataclasses

from ....shaders.loader import ProgramPart
from ..lens import coc_row
from ..programs import LIT_ENTRIES
from ..settle import flag_reach, settle
from ..stats import FrameStats
from .base import Feature, LitPart

# The lit program's parts: the pilot's, and the settle test's entry shader and its switch.
_PILOT = LitPart(program=ProgramPart("pilot", defines=(("PILOT_SAMPLE", True),)))
_TEST = ProgramPart("settle", fragment=LIT_ENTRIES["settle"], defines=(("SETTLE_TEST", True),))


class Settling(Feature):
    name = "settling"

    def wanted(self, frame):
        adaptive = frame.adaptive
        return (
            frame.motion is None
            and adaptive is not None
            and adaptive.settle > 0.0
            and flag_reach(frame.settings.filter_size, frame.lens_reach) is not None
        )

    def film(self, frame):
        return {"settle": True}

    def before_sample(self, frame, s):
        """The settle stage, before the frame's second sample."""
        if s != 1:
            return
        renderer = self.renderer
        centred = [
            dataclasses.replace(lt, sampled=True, jittered=frame.jitter) if i in frame.moving else lt
            for i, lt in enumerate(frame.lights)
        ]
        pilot = renderer.sample(frame, 0, pilot=True, lights=centred)
        renderer.draw_sample(frame, pilot)
        with frame.clock.stage("settle"):
            test = dataclasses.replace(
                pilot, pilot=False, settle_test=True, alpha_offset=0.5, sample_count=frame.sample_count, ao=None
            )
            test.stats = FrameStats()  # the test's draws are not the frame's samples
            film = renderer.film
            renderer.lit(frame, test, target=film.settle_framebuffer())
            frame.stats.lit_keys |= test.stats.lit_keys  # its programs are the frame's to list
            frame.stats.pixels_settled = settle(
                film,
                frame.settings,
                frame.adaptive,
                frame.sample_count,
                frame.aux,
                frame.emission,
                frame.lens_reach,
            )

    def lit(self, frame, sample):
        if sample.settle_test:  # where the lens blurs, a pixel keeps sampling (lib/lit_settle.glsl)
            return LitPart(program=_TEST, rows={"lens_coc": coc_row(sample.cameras[0], *frame.size)})
        return _PILOT if sample.pilot else super().lit(frame, sample)
