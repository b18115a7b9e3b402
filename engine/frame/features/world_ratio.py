"""The world's light as a ratio (lit_world.glsl WORLD_RATIO, lib/world_ratio.glsl): without
light portals, a frame of several samples draws directions of the world's light with shadow
maps (``world/directions.py``), as many per sample as the world's share of the light in view
asks for, and they shadow its SH light as a ratio of their sums over the frame's samples,
accumulated in the film's world targets and divided at its resolve (never negative).

Off (not registered), a frame without portals lights its surfaces with the unshadowed SH light."""

from ..world.directions import directions_per_sample, needs_directions
from .base import Feature, LitPart

_RATIO = LitPart(variant={"world_ratio": True})


class WorldRatio(Feature):
    name = "world_ratio"

    def wanted(self, frame):
        """A frame of several samples whose world gives light above its noise, and no light
        portal (or interior's opening) to take all of it through its directions."""
        return (
            frame.accumulate
            and not frame.cones
            and not frame.world_negligible
            and frame.world_share is not None
            and int(frame.settings.world_samples) > 0
            and needs_directions(frame.snapshot.world, frame.settings)
        )

    def plan(self, frame):
        """The directions per sample: the world's light costs what it adds, in proportion to
        its share of the light reaching what the camera sees."""
        frame.directions = directions_per_sample(frame.world_share, int(frame.settings.world_samples))

    def film(self, frame):
        return {"world_ratio": True}

    def lit(self, frame, sample):
        # The settle test's variant weighs the world's light but accumulates nothing.
        return super().lit(frame, sample) if sample.settle_test else _RATIO
