"""The world's light as a ratio (lit_world.glsl WORLD_RATIO, lib/world_ratio.glsl): without
light portals, a frame of several samples draws directions of the world's light with shadow
maps (``world/directions.py``), as many per sample as the world's share of the light in view
asks for, and they shadow its SH light as a ratio of their sums over the frame's samples,
accumulated in the film's world targets (``RatioTargets``) and divided at its resolve (never
negative).

Off (not registered), a frame without portals lights its surfaces with the unshadowed SH light."""

from ....shaders.loader import Program, ProgramPart
from ...gpu_pool import new_texture
from ..film import FilmPart, clear_zero, gpu_framebuffer
from ..world.directions import directions_per_sample, needs_directions
from .base import Feature, LitPart

# The lit program's targets after the pass's: the SH light by lobe (diffuse, specular: rgb,
# coverage) and the ratio's sums (N_d, D_d, N_s, D_s), which the film accumulates; blended
# surfaces write only the first two (what they leave of the light behind them).
OUTPUTS = (("VEC4", "out_world_diffuse"), ("VEC4", "out_world_specular"), ("VEC4", "out_world_sums"))
OPAQUE = ProgramPart("ratio1", outputs=OUTPUTS, defines=(("WORLD_RATIO", True), ("WORLD_RATIO_OUT", 1)))
BLENDED = ProgramPart("ratio2", outputs=OUTPUTS[:2], defines=(("WORLD_RATIO", True), ("WORLD_RATIO_OUT", 2)))
_RATIO = LitPart(program=OPAQUE, blended=BLENDED)
# A capture's (a Plane probe's mirror, a cube's face: ``Feature.capture``): its surfaces take
# the ratio of this sample's directions within the sample (lit.frag.glsl), no film targets.
_CAPTURE = LitPart(program=ProgramPart("ratio0", defines=(("WORLD_RATIO", True), ("WORLD_RATIO_OUT", 0))))

NAMES = ("world_diffuse", "world_specular", "world_sums")  # the targets' samplers, in order
_SAMPLERS = tuple(("FLOAT_2D", name) for name in NAMES)

# A sample's targets added to their accumulations in one pass, where not converged (WITH_MASK,
# ``converged`` then bound).
RESOLVE = Program(
    name="world_ratio_resolve",
    vertex="fullscreen.vert.glsl",
    fragment="world_ratio.frag.glsl",
    vertex_in=(("VEC2", "pos"),),
    push_constants=(("FLOAT", "scale"), ("FLOAT", "per_pixel")),
    samplers=(("FLOAT_2D", "src_color"), ("FLOAT_2D", "weight")) + _SAMPLERS,
    outputs=(("VEC4", "out_color"),),
    libs=("lib/world_ratio.glsl",),
)

# The convergence check's part: both means it compares take the world's light through its
# ratio, so the noise of its directions counts (the sums' every-other-sample accumulation too).
CONVERGENCE = ProgramPart(
    "ratio",
    libs=("lib/world_ratio.glsl",),
    samplers=_SAMPLERS + (("FLOAT_2D", "half_world_sums"),),
    defines=(("WORLD_RATIO", True),),
)


class RatioTargets(FilmPart):
    """The ratio's targets in the film: per sample (what the lit pass writes), their
    accumulations with the colour's weights, and the sums' every-other-sample accumulation
    for the noise estimate; ``resolve`` shadows the SH light in the colour by their ratio."""

    name = "world_ratio"
    lit_targets = len(OUTPUTS)
    resolves_colour = True  # ``RESOLVE`` writes the colour from its accumulation and weight

    def __init__(self):
        self.size = None
        self.sample = None  # the per-sample targets
        self.accum = None  # [(accumulation, its framebuffer)] of each
        self.half = None  # (the sums' every-other-sample accumulation, its framebuffer)
        self.fbs = {}

    def _targets(self, film):
        """The per-sample targets at the film's size, made on first use."""
        if self.size != film.size:
            self.release(film)
            self.size = film.size
        if self.sample is None:
            self.sample = [new_texture(film.pool, film.size, "RGBA32F") for _ in range(3)]
        return self.sample

    def framebuffer(self, film, slots, blended=False):
        import gpu

        targets = self._targets(film)
        key = (blended, tuple(id(s) for s in slots))
        if key not in self.fbs:
            mine = targets[:2] if blended else targets
            self.fbs[key] = gpu.types.GPUFrameBuffer(depth_slot=film.zbuffer, color_slots=tuple(slots) + tuple(mine))
        return self.fbs[key]

    def clear(self, film):
        import gpu

        targets = self._targets(film)
        if "clear" not in self.fbs:
            self.fbs["clear"] = gpu.types.GPUFrameBuffer(color_slots=tuple(targets))
        with self.fbs["clear"].bind():  # one clear of all three
            self.fbs["clear"].clear(color=(0.0, 0.0, 0.0, 0.0))

    def begin(self, film):
        """A fresh frame: the accumulations (and, when the noise is estimated, the sums'
        every-other-sample one) at the film's size, cleared."""
        import gpu

        self._targets(film)
        if self.accum is None:
            targets = [new_texture(film.pool, film.size, "RGBA32F") for _ in range(3)]
            self.accum = [(t, gpu.types.GPUFrameBuffer(color_slots=(t,))) for t in targets]
        if film.tracking and self.half is None:
            half = new_texture(film.pool, film.size, "RGBA32F")
            self.half = (half, gpu.types.GPUFrameBuffer(color_slots=(half,)))
        for target, _fb in self.accum:
            clear_zero(target)
        if film.tracking:
            clear_zero(self.half[0])

    def copies(self, film, sample):
        """Its three targets into their accumulations, and the sums into their every-other-sample
        accumulation (odd samples, when the noise is estimated)."""
        targets = self._targets(film)
        out = [(target, accum) for target, (accum, _fb) in zip(targets, self.accum, strict=True)]
        if film.tracking and sample % 2 == 1:
            out.append((targets[2], self.half[0]))
        return out

    def accumulations(self):
        """{sampler name: accumulation} of the ratio's targets (what its resolve reads)."""
        return {name: target for name, (target, _fb) in zip(NAMES, self.accum, strict=True)}

    def accumulated(self, film):
        return [(target, source) for (target, _fb), source in zip(self.accum, self.sample, strict=True)]

    def convergence(self, film):
        return CONVERGENCE, {**self.accumulations(), "half_world_sums": self.half[0]}

    def resolve(self, film, framebuffer=None):
        """The colour resolved anew with the world's light through its ratio (over the shadow
        and Emission passes the plain resolve wrote), into the film's colour or
        ``framebuffer``."""
        sums = self.accumulations()
        target = gpu_framebuffer(film.color) if framebuffer is None else framebuffer
        self._resolve(film, film.accum_color, target, sums["world_diffuse"], sums["world_specular"])

    def _resolve(self, film, source, framebuffer, world_diffuse, world_specular):
        """``source`` (an accumulation) over its weight, shadowed by the ratio of the
        accumulated sums (``RESOLVE``), its SH light ``world_diffuse`` and ``world_specular``."""
        per_pixel = film.weight is not None
        total = film.weight_sum
        samplers = {
            "src_color": source,
            "weight": film.weight if per_pixel else source,
            "world_diffuse": world_diffuse,
            "world_specular": world_specular,
            "world_sums": self.accumulations()["world_sums"],
        }
        uniforms = {"scale": 1.0 / total if total > 0.0 else 0.0, "per_pixel": 1.0 if per_pixel else 0.0}
        film.fullscreen(RESOLVE, framebuffer, samplers, uniforms)

    def resolve_light(self, film, source, framebuffer, lobes, scratch):
        """A light pass carrying the world's SH light of ``lobes``: its average shadowed by the
        frame's ratio, as the colour's (the other lobe's U taken as 0: ``scratch``, cleared)."""
        clear_zero(scratch)
        sums = self.accumulations()
        diffuse = sums["world_diffuse"] if lobes[0] else scratch
        specular = sums["world_specular"] if lobes[1] else scratch
        self._resolve(film, source, framebuffer, diffuse, specular)
        return True

    def bytes_per_pixel(self, film):
        return 6 * 16 + (16 if film.tracking else 0)

    def release(self, film):
        """Every target back to the film's pool (a new size, the end of a render)."""
        film.give([*(self.sample or ()), *(t for t, _fb in self.accum or ()), self.half[0] if self.half else None])
        self.sample = self.accum = self.half = None
        self.fbs = {}
        self.size = None


class WorldRatio(Feature):
    name = "world_ratio"

    def __init__(self, renderer):
        super().__init__(renderer)
        self.targets = RatioTargets()

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

    def film_part(self, frame):
        return self.targets

    def lit(self, frame, sample):
        # The settle test's variant weighs the world's light but accumulates nothing.
        return super().lit(frame, sample) if sample.settle_test else _RATIO

    def capture(self, frame, sample):
        return _CAPTURE
