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
"""

import functools

import numpy as np

from ..counts import ceil_count
from . import sampling

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


def settle(film, settings, adaptive, sample_count, aux=False, emission=False, lens=0.0):
    """Settle the pixels of ``film`` no later sample can change by ``adaptive.settle``, once
    the settle test's variant of the lit pass has drawn its flags over the pilot's surfaces,
    maps and lights into ``film.settle_framebuffer()`` (``Renderer.render``): the film's settle
    pass. ``aux``: the frame has the Shadow pass, which must not change either; ``emission``:
    and the Emission pass; ``lens``: the widest circle of confusion's radius in pixels (depth
    of field; ``flag_reach``). Returns the number of pixels settled."""
    before = film.converged
    film.settle(
        adaptive.settle,
        settle_shifts(1, sample_count, settings.filter_size),
        aux,
        emission,
        flag_reach(settings.filter_size, lens),
    )
    return film.converged - before
