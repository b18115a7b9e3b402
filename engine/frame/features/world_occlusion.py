"""The world's ambient occlusion (World > Ambient Occlusion; ``world/occlusion.py``,
lib/gtao.glsl): in a one-sample frame and the first sample of a frame of several, the world's
light is occluded by screen-space ground-truth ambient occlusion over a camera depth prepass,
its horizons marched at half resolution (the frame's first image shows contact shadows at once).

Off (not registered), no sample draws the prepass and the world's light is unoccluded."""

import math

import numpy as np

from ....shaders.loader import ProgramPart
from ...enums import DEBUG_VIEW
from ..draw_list import corners_of
from ..programs import AO_HORIZONS_SAMPLER, AO_SAMPLER
from ..sampling import world_is_black
from ..world.occlusion import WorldAO
from .base import Feature, LitPart

# The lit program's part: the prepass's depth and the horizons marched over it (lib/gtao.glsl).
_OCCLUSION = ProgramPart(
    "ao",
    samplers=(("FLOAT_2D", AO_SAMPLER), ("FLOAT_2D", AO_HORIZONS_SAMPLER)),
    # GTAO_UPSAMPLE: the lit pass reads the half-resolution horizons.
    defines=(("WORLD_AO", True), ("GTAO_UPSAMPLE", True)),
)


# The world's ambient occlusion (``world/occlusion.py``, ``shaders/lib/gtao.glsl``): with World ›
# Ambient Occlusion › Distance at 0 (automatic) it looks this fraction of the diagonal of the
# bounds of what the frame draws, so it does the same in a scene of millimetres or kilometres.
AO_AUTO_FRACTION = 0.1


def world_ao_sample(s, accumulate, settings, world, debug="NONE"):
    """Whether sample ``s`` of a frame (``accumulate``: one of several samples) occludes the
    world's light by screen-space ambient occlusion (``world/occlusion.py``): with World › Ambient
    Occlusion on and a world that gives light, a one-sample frame (the viewport while the view
    moves, a render of one sample) and the first sample of a frame of several, so the frame's
    first image shows contact shadows at once (a frame's pilot sample stands in for its first,
    ``features/settling.py``: ask with ``s`` 0). The WORLD_AO debug view occludes every sample (it shows
    that estimate), the other lit debug views none. A black world, or the setting off, costs
    nothing: no prepass, no occlusion code in the lit pass."""
    if not bool(getattr(settings, "world_ao", False)) or world_is_black(world):
        return False
    if debug == "WORLD_AO":
        return True
    if DEBUG_VIEW[debug].lit and not DEBUG_VIEW[debug].term:
        return False  # the other lit debug views show the lights' numbers, not the world's
    return not accumulate or s == 0


def world_ao_distance(settings, corners):
    """How far (world units) the ambient occlusion looks: World › Ambient Occlusion ›
    Distance, or with 0 (automatic) AO_AUTO_FRACTION of the diagonal of the box around
    ``corners`` ((n, 3) world points: the bounds of what the frame draws); 0 when there is
    nothing (no occlusion)."""
    distance = float(getattr(settings, "world_ao_distance", 0.0))
    if distance > 0.0 and math.isfinite(distance):
        return distance
    pts = np.asarray(corners, np.float64).reshape(-1, 3) if corners is not None else np.zeros((0, 3))
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) == 0:
        return 0.0
    diagonal = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))
    return AO_AUTO_FRACTION * diagonal if math.isfinite(diagonal) else 0.0


def ao_jitter(s):
    """Sample ``s``'s rotation of the ambient occlusion's slices and offset of its steps, each
    in [0, 1): the additive recurrence of the plastic number's powers (an R2 sequence), so the
    samples of a frame spread evenly over both; sample 0 unshifted."""
    return (math.fmod(s * 0.7548776662466927, 1.0), math.fmod(s * 0.5698402909980532, 1.0))


def ao_row(projection, size, distance, jitter):
    """The frame row's WORLD_AO fields (``lib/gtao.glsl``): the terms of the raster camera's
    ``projection`` that take a view depth at a pixel to a view-space position and back, the
    film's ``size`` (width, height), the distance in world units and the sample's ``jitter``
    (``ao_jitter``)."""
    p = np.asarray(projection, np.float64)
    return {
        "ao_projection": (p[0, 0], p[1, 1], p[0, 2], p[1, 2]),
        "ao_projection_w": (p[0, 3], p[1, 3], p[3, 2], p[3, 3]),
        "ao_viewport": (float(size[0]), float(size[1])),
        "ao_distance": float(distance),
        "ao_jitter": tuple(float(j) for j in jitter),
    }


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
        """Sample ``s``'s occlusion: (distance, jitter) or None (``world_ao_sample``)."""
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
