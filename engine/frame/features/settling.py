"""Settling: a pixel that no later sample of its frame can change takes no more samples.

A frame's samples differ in three ways (``sampling``): where in the pixel they look (the pixel
filter's offsets), where each light with an extent shines from, and how each map's texel grid
is shifted. After the first sample (or Min Samples, when set), one pass asks of every pixel
whether any of these could move it by the Noise Threshold, in Cycles' error units:

* **Lights.** The settle test's entry shader over the lit pass's libraries (``SETTLE_TEST``,
  ``lit_settle.frag.glsl``, ``lib/lit_settle.glsl``, ``lib/shadow_filters.glsl``) runs over
  the surfaces the sample drew, with each light at its whole size: a moving light's visibility
  must be the same from every point of it and on every map shift (the map's region the light's
  whole width around the point shows no occluder at all, or occluders everywhere), no facet
  may turn across the light, and the light the surface reflects may change only a little over
  the light's extent (it moves the light by its radius each way: highlights and close lights
  do not settle). Dithered and blended surfaces never settle (what is behind them shows in
  some samples). A pixel needs its neighbourhood settled as far as the pixel filter reaches
  (``flag_reach``: 2 pixels each way at the default 1.5).
* **The pixel filter.** For an image smooth over the pixel, the samples taken so far average
  to the whole frame's filtered value up to gradient . (mean offset difference) + 1/2 Hessian :
  (second-moment difference) (``settle_shifts``, exact for the frame's own offsets); the
  gradient and Hessian come from central differences of the image so far. Edges, thin lines,
  texture detail and noise give large values and keep sampling.

Settled pixels join adaptive sampling's converged pixels (``Film``): later samples do not shade
or add them, and the resolve divides by their own weight. With Noise Threshold 0 (or adaptive
sampling off) nothing settles and every sample is the plain one.

Not caught (named in docs/design.md): an occluder thinner than the test's grid spacing in a map
region wider than 8 texels (a large light far from its casters), and detail under a pixel that
the first sample missed entirely (a sub-pixel wire between pixel centres).

The technique's module: before a frame's second sample a pilot sample (the centred pixel,
every light at its centre) and the settle test's variant of the lit pass over its surfaces
(``SETTLE_TEST``) draw the flags into its target (``SettleTargets``), and its pass over the
film keeps the pilot's value where they allow. Only in frames of several samples with
adaptive sampling's settling on, without motion blur (a moving surface's pixels change with
the sample's time) and with depth of field only where no blur reaches past the test's
neighbourhood. Off (not registered), every pixel takes every sample the frame's other checks
leave it.
"""

import dataclasses
import functools
from dataclasses import replace

import numpy as np

from ....shaders.loader import Program, ProgramPart
from ...counts import ceil_count
from ...gpu_pool import new_texture
from .. import sampling
from ..film import FilmPart, gpu_framebuffer
from ..lens import coc_row
from ..programs import LIT_ENTRIES
from ..stats import FrameStats
from .base import Feature, LitPart

# The lit program's parts: the pilot's, and the settle test's entry shader and its switch.
_PILOT = LitPart(program=ProgramPart("pilot", defines=(("PILOT_SAMPLE", True),)))
# The settle test reads a map's region up to SETTLE_REACH texels around a point (the light's
# half width seen from there); a wider region (a large light far from its casters) may change.
# It reads every texel up to SETTLE_GRID texels away, beyond that (2 SETTLE_GRID + 1)^2 taps.
SETTLE_REACH = 128
SETTLE_GRID = 4
_TEST = ProgramPart(
    "settle",
    fragment=LIT_ENTRIES["settle"],
    defines=(("SETTLE_TEST", True), ("SETTLE_REACH", SETTLE_REACH), ("SETTLE_GRID", SETTLE_GRID)),
)

ENDLESS_MOMENTS = 1024  # the samples a frame without end is taken to have (its filter's moments)


MAX_FLAG_REACH = 4  # pixels: a wider filter keeps the 9x9 test (its weight beyond is tiny)


def flag_reach(filter_size, lens=0.0):
    """How many pixels around a pixel the light test must hold: the nearest pixel centres
    the pixel filter reaches (Filter Size pixels each way; at least the 3x3 neighbourhood),
    and with depth of field as far as the widest circle of confusion's radius (``lens``, in
    pixels: a blurred surface reaches that far). None where that is beyond MAX_FLAG_REACH
    with depth of field: the frame does not settle (a wider neighbourhood is not tested)."""
    reach = ceil_count(float(filter_size) + float(lens) - 1e-6, 1, MAX_FLAG_REACH + 1)
    if lens > 0.0 and reach > MAX_FLAG_REACH:
        return None
    return min(reach, MAX_FLAG_REACH)


@functools.lru_cache(maxsize=16)
def settle_shifts(kept, count, filter_size):
    """How the points samples 0 .. ``kept`` - 1 are seen at differ from those of all ``count``
    samples of the frame (0: without end; ``kept`` 1: the pilot's own pixel), as image offsets
    weighted as the film weighs them (``sampling.sample_taps``): (mean dx, mean dy), (mean
    dx^2, mean dy^2, mean dx dy), the kept ones' minus the whole frame's. A smooth image's kept average
    differs from the frame's by gradient . mean + 1/2 Hessian : moments (``settle.frag.glsl``).
    Cached: a frame without end takes 1024 offsets (a few ms), and every viewport refinement
    asks again."""

    def moments(n):
        # Every point the samples are seen at from a pixel, by its weight (a gathering film's
        # sample reaches the pixel from each of its neighbours, ``sampling.sample_taps``); as
        # offsets of the image, the negative of where the point lies.
        taps = np.array([t for s in range(n) for t in sampling.sample_taps(s, filter_size)], np.float64)
        w = taps[:, 2] / taps[:, 2].sum()
        dx, dy = -taps[:, 0], -taps[:, 1]
        return np.array([w @ dx, w @ dy]), np.array([w @ (dx * dx), w @ (dy * dy), w @ (dx * dy)])

    total = int(count) if count > 0 else ENDLESS_MOMENTS
    if int(kept) <= 1:  # the pilot: a settled pixel takes its own value, ungathered
        mean_k, second_k = np.zeros(2), np.zeros(3)
    else:
        mean_k, second_k = moments(int(kept))
    mean_n, second_n = moments(max(total, int(kept)))
    return tuple(mean_k - mean_n), tuple(second_k - second_n)


# The film's settle pass: the settle test's flags and the image so far give the pixels no later
# sample can change; they join the converged mask (``settle.frag.glsl``), and their
# accumulations take the pilot's value (``settled_copy.frag.glsl``).
SETTLE = Program(
    name="settle",
    vertex="fullscreen.vert.glsl",
    fragment="settle.frag.glsl",
    vertex_in=(("VEC2", "pos"),),
    push_constants=(
        ("FLOAT", "threshold"),
        ("FLOAT", "weight_sum"),
        ("VEC2", "mean_shift"),
        ("VEC3", "moment_shift"),
        ("FLOAT", "flag_reach"),
    ),
    samplers=(("FLOAT_2D", "accum"), ("FLOAT_2D", "flags"), ("FLOAT_2D", "converged")),
    outputs=(("VEC4", "out_color"),),
    defines=(("WITH_SHADOW", False),),
)
SETTLE_SHADOW = replace(
    SETTLE,
    name="settle_shadow",
    samplers=SETTLE.samplers + (("FLOAT_2D", "accum_shadow"),),
    defines=(("WITH_SHADOW", True),),
)
SETTLED_COPY = Program(
    name="settled_copy",
    vertex="fullscreen.vert.glsl",
    fragment="settled_copy.frag.glsl",
    vertex_in=(("VEC2", "pos"),),
    push_constants=(("FLOAT", "scale"),),
    samplers=(("FLOAT_2D", "src_color"), ("FLOAT_2D", "converged")),
    outputs=(("VEC4", "out_color"),),
)


class SettleTargets(FilmPart):
    """Settling's target in the film: the settle test's flags (RGBA32F) over the lit pass's
    z-buffer, and the settle pass that reads them."""

    name = "settling"

    def __init__(self):
        self.size = None
        self.flags = self.fb = None

    def test_framebuffer(self, film):
        """The settle test's target, cleared to settled (1) with no change: where no surface
        is drawn, only the image decides."""
        import gpu

        if self.size != film.size or self.flags is None:
            self.release(film)
            self.size = film.size
            self.flags = new_texture(film.pool, film.size, "RGBA32F")
            self.fb = gpu.types.GPUFrameBuffer(depth_slot=film.zbuffer, color_slots=(self.flags,))
        self.flags.clear(format="FLOAT", value=(1.0, 0.0, 0.0, 0.0))
        return self.fb

    def settle(self, film, threshold, shifts, aux=False, emission=False, reach=1):
        """After the first sample, with the pilot sample in the colour (and shadow, Emission)
        targets: settle the pixels no later sample can change by ``threshold`` (the flags and
        the pilot's image; ``shifts``: ``settle_shifts``). They join the converged pixels with
        the pilot's value in place of the first sample's (the same weight); the others keep
        their first sample. ``aux``/``emission``: the frame has the Shadow / Emission pass;
        ``reach``: how many pixels away the pixel filter still reads (its light test must hold
        that far). Returns the number of converged pixels."""
        (mx, my), (sxx, syy, sxy) = shifts
        kept = film.accumulations(aux, emission)
        samplers = {"accum": film.color, "flags": self.flags}
        if "shadow" in kept:
            samplers["accum_shadow"] = kept["shadow"][1]
        uniforms = {
            "threshold": float(threshold),
            "weight_sum": 1.0,  # the pilot alone
            "mean_shift": (float(mx), float(my)),
            "moment_shift": (float(sxx), float(syy), float(sxy)),
            "flag_reach": float(reach),
        }
        count = film.update_mask(SETTLE_SHADOW if "shadow" in kept else SETTLE, samplers, uniforms)
        if count:
            mask = film.mask
            copies = list(kept.values())
            for part in film.parts:
                copies += list(part.accumulated(film))
            for target, source in copies:
                scale = film.weight_sum  # the first sample's weight, which the pilot takes over
                film.fullscreen(
                    SETTLED_COPY, gpu_framebuffer(target), {"src_color": source, "converged": mask}, {"scale": scale}
                )
        return count

    def bytes_per_pixel(self, film):
        return 16 if self.flags is not None else 0

    def release(self, film):
        film.give([self.flags])
        self.flags = self.fb = None
        self.size = None


def settle(targets, film, settings, adaptive, sample_count, aux=False, emission=False, lens=0.0):
    """Settle the pixels of ``film`` no later sample can change by ``adaptive.settle``, once
    the settle test's variant of the lit pass has drawn its flags over the pilot's surfaces,
    maps and lights into ``targets.test_framebuffer`` (``SettleTargets``): the film's settle
    pass. ``aux``: the frame has the Shadow pass, which must not change either; ``emission``:
    and the Emission pass; ``lens``: the widest circle of confusion's radius in pixels (depth
    of field; ``flag_reach``). Returns the number of pixels settled."""
    before = film.converged
    targets.settle(
        film,
        adaptive.settle,
        settle_shifts(1, sample_count, settings.filter_size),
        aux,
        emission,
        flag_reach(settings.filter_size, lens),
    )
    return film.converged - before


class Settling(Feature):
    name = "settling"

    def __init__(self, renderer):
        super().__init__(renderer)
        self.targets = SettleTargets()

    def wanted(self, frame):
        adaptive = frame.adaptive
        return (
            frame.motion is None
            and not frame.unsettled
            and adaptive is not None
            and adaptive.settle > 0.0
            and flag_reach(frame.settings.filter_size, frame.lens_reach) is not None
        )

    def film(self, frame):
        return {"masks": True}  # it converges pixels of its own

    def film_part(self, frame):
        return self.targets

    def starts_batch(self, frame, s):
        return s == 1  # its test reads the first sample

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
            renderer.lit(frame, test, target=self.targets.test_framebuffer(film))
            frame.stats.lit_keys |= test.stats.lit_keys  # its programs are the frame's to list
            frame.stats.pixels_settled = settle(
                self.targets,
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
