"""Render samples: where each sample looks from and where each soft light shines from.

Plain numpy, no bpy and no gpu. A frame of N samples renders sample s = 0 .. N-1 and averages
them with the film filter's weights:

* **Pixels.** Sample s shifts the whole image by a sub-pixel offset: sample 0 by nothing (the
  pixel centre), sample s > 0 by the Halton (2, 3) point s, centred, uniform over the pixel,
  and the film gathers it into every pixel within the reach of the Blackman-Harris filter
  Blender calls ``filter_size`` (``filter_width``: it reaches ``filter_size`` pixels each way,
  as Cycles' Pixel Filter Width and EEVEE's Filter Size do), weighted by the filter at each
  distance (``sample_taps``), so the weighted average converges to the image convolved with
  it. A filter wider than the gather reaches draws each offset from the filter instead
  (through its inverse CDF: the plain average converges to the same image).
* **Soft lights.** A light with size (sun ``angle``, point/spot ``shadow_soft_size``, area
  ``size``/``size_y`` and shape) shines from a different point of itself in each sample, in
  an order and rotation of its own so lights do not move in step: a sun from Vogel's spiral
  of N points on its disc (even along every axis), a point or spot light from a point of the
  sphere of its radius as Cycles sees it (a ball density whose projection from any direction
  is the uniform disc), an area light from a Hammersley set of N on its surface (stratified
  for any N). Every sample's shadow map is a hard shadow from that
  point, so the average converges to the true visibility (Heckbert-Herf accumulation), and an
  area light's irradiance to the integral over its surface. Each sample stands for 1/N of
  the light, so in that sample it is shadowed by PCSS (whatever the scene's filter) with a
  light 1/sqrt(N) the size (``penumbra_scale``): a few samples already give smooth penumbrae,
  many converge to the exact one, and the penumbra is not blurred twice. One sample is
  exactly the single-sample frame.
* **Map jitter.** With ``shadow_map_jitter`` on, sample s > 0 also shifts each shadowed
  light's maps by a sub-texel offset (a stratified set over the texel, sample 0 unshifted):
  every sample rasterises the casters on another texel grid, so the average of the samples'
  lookups converges to the visibility filtered over one texel (the staircase and the
  sub-texel position of an edge average out) instead of one map's aliasing, whatever the
  light's size; its normal offset shrinks as 1/sqrt(N), and a sample whose penumbra is
  under two texels reads one bilinear lookup. Such a light's maps are redrawn every sample,
  and every light with an extent is sampled on it, however small its penumbra. Without
  jitter, a light without size (or with a penumbra below a texel) is the same in every
  sample, so its map is drawn once and reused.

Sequences depend only on (s, N, light index): the viewport's k-th redraw and a final render's
k-th sample are the same sample, so N redraws show what a final render of N samples shows.
"""

import dataclasses
import functools
import math
import time

import numpy as np

from ..counts import ceil_count
from ..shadows.vectors import cross

PIXEL_BASES = (2, 3)


def radical_inverse(index, base):
    """The van der Corput radical inverse of ``index`` in ``base`` (Halton coordinate)."""
    result, f = 0.0, 1.0 / base
    i = int(index)
    while i > 0:
        result += f * (i % base)
        i //= base
        f /= base
    return result


def blackman_harris(x, width):
    """The Blackman-Harris window of total ``width`` at offset ``x`` (1 at the centre, 0 at
    +-width/2 and beyond)."""
    if width <= 0.0:
        return 1.0 if x == 0.0 else 0.0
    t = x / width + 0.5
    if t <= 0.0 or t >= 1.0:
        return 0.0
    a = 2.0 * math.pi * t
    return 0.35875 - 0.48829 * math.cos(a) + 0.14128 * math.cos(2 * a) - 0.01168 * math.cos(3 * a)


def filter_width(filter_size):
    """The total width in pixels of the Blackman-Harris window of Blender's ``filter_size``:
    twice it. Cycles doubles the Pixel Filter Width it is given for this filter (its film's
    filter table), and EEVEE weighs samples up to Filter Size pixels away, so the same number
    gives the same image in all three engines."""
    return 2.0 * float(filter_size)


@functools.lru_cache(maxsize=8)
def _filter_cdf(filter_size, table=1024):
    width = filter_width(filter_size)
    x = (np.arange(table + 1) / table - 0.5) * width
    pdf = np.array([blackman_harris(v, width) for v in x])
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (pdf[1:] + pdf[:-1]))])
    return cdf / cdf[-1], x


def _filter_inverse_cdf(u, filter_size):
    """The offset (pixels) below which a fraction ``u`` of the Blackman-Harris filter's weight
    lies: offsets drawn this way are distributed as the filter, so samples need equal weights
    (importance sampling; far less noise than weighting uniform offsets)."""
    cdf, x = _filter_cdf(float(filter_size))
    return float(np.interp(u, cdf, x))


# The gathering film (``film.Film.accumulate`` with ``gather``, EEVEE's film): each sample is
# jittered uniformly over its pixel and shaded once, and every film pixel gathers the samples
# within the filter's reach, each weighted by the Blackman-Harris window at its distance
# (separable, as the offsets of the importance-sampled film were drawn per axis); weights are
# accumulated per pixel and divided at resolve. A film pixel reads sample pixels up to
# ``gather_reach`` each way; a filter wider than GATHER_REACH_MAX of them keeps the film that
# draws each sample's offset from the filter (importance sampling, one sample per pixel).
GATHER_REACH_MAX = 4


MAX_GATHER_REACH = 64  # a bound for any Filter Size (its property's maximum, 10, reaches 10)


def gather_reach(filter_size):
    """Sample pixels each way along an axis a film pixel gathers from: those whose shading
    point (within half a pixel of their centre) can lie inside the filter's reach (Filter
    Size pixels): |t| < Filter Size + 1/2."""
    if not filter_size > 0.0:
        return 0
    return ceil_count(float(filter_size) + 0.5, 1, MAX_GATHER_REACH + 1) - 1


def gathers(filter_size):
    """Whether a multi-sample frame of this Filter Size gathers (``GATHER_REACH_MAX``)."""
    return filter_size > 0.0 and gather_reach(filter_size) <= GATHER_REACH_MAX


def film_reach(filter_size):
    """How far, in pixels, a film pixel gathers samples (``gather_reach`` where the frame
    gathers, else 0: each pixel its own)."""
    return gather_reach(filter_size) if gathers(filter_size) else 0


def axis_weights(shift, filter_size):
    """The window's weight of each sample pixel t = -R .. R along one axis for a sample whose
    image moved by ``shift`` pixels (the pixel t away sees the point t - shift away)."""
    width = filter_width(filter_size)
    reach = gather_reach(filter_size)
    return [blackman_harris(t - shift, width) for t in range(-reach, reach + 1)]


def pixel_offset(s, filter_size):
    """(dx, dy, weight) of sample ``s``: how far its image moves, in pixels, and its weight in
    the film, sample 0 at the centre. A gathering film (``gathers``): uniform over the pixel
    (the Halton (2, 3) point s, centred), the weight the window's total over the pixels it
    reaches (what the film divides by). Otherwise distributed as the film filter (Halton
    points through the filter's inverse CDF), weight 1 (the distribution carries the filter)."""
    if filter_size <= 0.0:
        return 0.0, 0.0, 1.0
    if gathers(filter_size):
        dx = math.fmod(radical_inverse(s, PIXEL_BASES[0]) + 0.5, 1.0) - 0.5
        dy = math.fmod(radical_inverse(s, PIXEL_BASES[1]) + 0.5, 1.0) - 0.5
        return dx, dy, sum(axis_weights(dx, filter_size)) * sum(axis_weights(dy, filter_size))
    if s == 0:
        return 0.0, 0.0, 1.0
    dx = _filter_inverse_cdf(radical_inverse(s, PIXEL_BASES[0]), filter_size)
    dy = _filter_inverse_cdf(radical_inverse(s, PIXEL_BASES[1]), filter_size)
    return dx, dy, 1.0


def sample_taps(s, filter_size):
    """Where sample ``s`` is seen from a film pixel, and how much: (x, y, weight) of each
    point, in pixels from the pixel's centre, the weights summing to the sample's (``pixel_offset``)."""
    dx, dy, weight = pixel_offset(s, filter_size)
    if not gathers(filter_size):
        return [(-dx, -dy, weight)]
    reach = gather_reach(filter_size)
    wx, wy = axis_weights(dx, filter_size), axis_weights(dy, filter_size)
    return [
        (tx - dx, ty - dy, a * b)
        for ty, b in zip(range(-reach, reach + 1), wy, strict=True)
        for tx, a in zip(range(-reach, reach + 1), wx, strict=True)
        if a * b > 0.0
    ]


def gather_uniforms(dx, dy, filter_size):
    """The gather's push constants of a sample moved by (dx, dy) pixels (``lib/film_gather.glsl``):
    the window's weights of the sample pixels t = -R .. R along x and along y, each padded to
    nine (a mat3's entries, column by column; the reach R is the program's, ``film.Film.gather_reach``);
    None when the frame does not gather."""
    if not gathers(filter_size):
        return None

    def nine(weights):
        return tuple(float(w) for w in weights) + (0.0,) * (9 - len(weights))

    return {
        "gather_wx": nine(axis_weights(dx, filter_size)),
        "gather_wy": nine(axis_weights(dy, filter_size)),
    }


def jittered_projection(projection, dx, dy, width, height):
    """``projection`` shifted by (dx, dy) pixels on a ``width`` x ``height`` image (the clip
    space translation, so it is exact for perspective and orthographic cameras alike)."""
    p = np.array(projection, dtype=np.float64)
    shift = np.eye(4)
    shift[0, 3] = 2.0 * dx / width
    shift[1, 3] = 2.0 * dy / height
    return shift @ p


def widened_projection(projection, reach, width, height):
    """``projection`` seeing ``reach`` pixels more on every side of a ``width`` x ``height``
    image: every pixel offset of a frame whose filter reaches that far stays inside it, so
    what is planned from it (the visible receivers the maps cover, the visible depth range)
    holds for every sample. Returns (projection, (width, height) of the widened image)."""
    p = np.array(projection, dtype=np.float64)
    grow = np.diag([width / (width + 2.0 * reach), height / (height + 2.0 * reach), 1.0, 1.0])
    return grow @ p, (width + 2.0 * reach, height + 2.0 * reach)


@functools.lru_cache(maxsize=256)
def _light_order(light_index, count):
    """A fixed shuffled order of the ``count`` points for light ``light_index``, and a fixed
    rotation: the points do not follow the pixel offsets' sequence, nor other lights'."""
    rng = np.random.default_rng(0x9E3779B1 + 7919 * light_index)
    return rng.permutation(count), rng.random(3)


def _light_point(s, light_index, dims, count):
    """Sample ``s``'s point in [0, 1)^dims for light ``light_index`` of a frame of ``count``
    samples: a point of the Hammersley set of ``count`` points ((j + 1/2) / count, then radical
    inverses in bases 2 and 3), which is stratified for every count (four samples land in four
    quarters), visited in a shuffled order and rotated per light."""
    order, rotation = _light_order(light_index, count)
    j = int(order[s % count])
    coords = [(j + 0.5) / count, radical_inverse(j, 2), radical_inverse(j, 3)][:dims]
    return [(c + rotation[d]) % 1.0 for d, c in enumerate(coords)]


GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))


def _disc_point(s, light_index, count):
    """Sample ``s``'s point of the unit disc for light ``light_index`` of a frame of ``count``
    samples: point j of Vogel's spiral of ``count`` points (radius sqrt((j + 1/2) / count),
    angle j golden angles; equal areas), j in the light's shuffled order, the spiral turned
    by the light's own angle. Its projection on every axis is evenly spread for every count,
    so a straight shadow edge (which sees the disc through one axis) converges smoothly;
    the Hammersley set's lattice at powers of two projects into clumps along some axes."""
    order, rotation = _light_order(light_index, count)
    j = int(order[s % count])
    r = math.sqrt((j + 0.5) / count)
    phi = j * GOLDEN_ANGLE + 2.0 * math.pi * rotation[0]
    return r * math.cos(phi), r * math.sin(phi)


def sobol_2(index):
    """The second dimension of the Sobol' sequence (its generator matrix is Pascal's mod 2),
    as 32 bits: with the van der Corput sequence it forms a (0, 2)-sequence in base 2."""
    v, result, i = 1 << 31, 0, int(index)
    while i:
        if i & 1:
            result ^= v
        i >>= 1
        v ^= v >> 1
    return result


@functools.lru_cache(maxsize=256)
def _progressive_scramble(light_index):
    """Per light: XOR masks of the first two coordinates' 32 bits and a rotation of the third."""
    rng = np.random.default_rng(0x5851F42D + 104729 * light_index)
    return int(rng.integers(0, 1 << 32)), int(rng.integers(0, 1 << 32)), float(rng.random())


def _light_point_progressive(s, light_index, dims):
    """Sample ``s``'s point in [0, 1)^dims for light ``light_index`` when a frame may stop any
    pixel after any multiple of 4 samples (adaptive sampling): the (0, 2)-sequence (van der
    Corput, Sobol' 2) digitally shifted per light, whose first 2^k points are stratified for
    every k, so a pixel stopped early has sampled the whole light evenly; a third coordinate
    from the radical inverse in base 5, rotated per light (base 3 is the pixel offsets' y: a
    point or spot light's angle then turned in step with it, and a sharp spot's 128 and 256
    sample frames ended at 1.4x the error of its 64)."""
    x_mask, y_mask, rotation = _progressive_scramble(light_index)
    x = int(radical_inverse(s, 2) * (1 << 32)) ^ x_mask
    y = sobol_2(s) ^ y_mask
    coords = [x / 2.0**32, y / 2.0**32, (radical_inverse(s, 5) + rotation) % 1.0]
    return coords[:dims]


def concentric_disk(u, v):
    """Shirley-Chiu map of [0, 1)^2 to the unit disk (area-preserving, low distortion)."""
    a, b = 2.0 * u - 1.0, 2.0 * v - 1.0
    if a == 0.0 and b == 0.0:
        return 0.0, 0.0
    if abs(a) > abs(b):
        r, phi = a, (math.pi / 4.0) * (b / a)
    else:
        r, phi = b, math.pi / 2.0 - (math.pi / 4.0) * (a / b)
    return r * math.cos(phi), r * math.sin(phi)


def _basis(axis):
    """Two unit vectors perpendicular to ``axis`` and to each other."""
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    u = cross(axis, helper)
    u /= np.linalg.norm(u)
    return u, cross(axis, u)


def has_size(light):
    """Whether the light's shadow depends on the sample (a light with an extent)."""
    if light.type == "SUN":
        return light.angle > 0.0
    if light.type == "AREA":
        return max(light.size_x, light.size_y) > 0.0
    return light.radius > 0.0


def penumbra_texels(light, fit):
    """An upper bound of the width, in texels of its map ``fit``, of the penumbra ``light``
    can cast: sun 2 tan(angle/2) (far - near) / texel; local lights 2 r / (texel per unit of
    distance * near) (similar triangles with the blocker at the map's near plane)."""
    if light.type == "SUN":
        if fit.texel <= 0.0:
            return math.inf
        return 2.0 * math.tan(0.5 * min(light.angle, math.pi * 0.99)) * (fit.far - fit.near) / fit.texel
    if fit.texel_per_distance <= 0.0 or fit.near <= 0.0:
        return math.inf
    return 2.0 * light.shadow_radius / (fit.texel_per_distance * fit.near)


def sampled_lights(lights, plan, every=False):
    """Indices of the lights that move between samples: area lights (their irradiance is an
    integral over the surface), and shadowed lights with an extent whose penumbra can be a
    texel wide or more in their map; with ``every`` (maps jittered per sample, so every map
    is redrawn anyway) every shadowed light with an extent, however small its penumbra: a
    sub-texel penumbra still moves the edge's 50 % contour. Every other light is the same in
    every sample (but for its map's jitter)."""
    out = set()
    for i, light in enumerate(lights):
        if not has_size(light):
            continue
        if light.type == "AREA":
            out.add(i)
            continue
        shadow = plan.lights.get(i)
        if shadow is None:
            continue
        fits = [plan.tiles[t].fit for t in shadow.tiles if t >= 0]
        if every or any(penumbra_texels(light, fit) >= 1.0 for fit in fits):
            out.add(i)
    return out


@functools.lru_cache(maxsize=256)
def _jitter_set(light_index, count):
    """The ``count`` sub-texel offsets of light ``light_index``'s maps, one per sample: a
    Hammersley set of ``count`` points over the texel (stratified for every count), visited in
    an order of its own (not the light points' nor the pixel offsets'), rotated (toroidally)
    so that sample 0 is unshifted, then centred on [-1/2, 1/2)."""
    rng = np.random.default_rng(0x51ED2701 + 104729 * light_index)
    order = rng.permutation(count)
    j = order.astype(np.float64)
    points = np.stack([(j + 0.5) / count, [radical_inverse(int(k), 2) for k in order]], axis=1)
    shifted = (points - points[0] + 0.5) % 1.0 - 0.5
    shifted[0] = 0.0
    return shifted


def map_jitter(s, light_index, count):
    """(x, y) texels by which sample ``s`` of ``count`` shifts light ``light_index``'s shadow
    maps: (0, 0) for sample 0 and frames of one sample."""
    if count <= 1 or s % count == 0:
        return (0.0, 0.0)
    x, y = _jitter_set(light_index, count)[s % count]
    return (float(x), float(y))


def _ball_radius(u):
    """The radius (of a unit ball) below which a fraction ``u`` of the ball's points lie when
    their density in the ball is 1 / sqrt(1 - r^2): the isotropic density whose projection
    along every direction is uniform on the unit disc (the inverse Abel transform of a
    uniform disc). CDF (theta - sin theta cos theta) / (pi / 2) with r = sin theta, inverted
    by Newton's method."""
    target = 0.5 * math.pi * min(max(u, 0.0), 1.0)
    theta = math.pi / 4.0
    for _ in range(40):
        f = theta - math.sin(theta) * math.cos(theta) - target
        d = 2.0 * math.sin(theta) ** 2
        if d < 1e-12:
            theta = (1.5 * target) ** (1.0 / 3.0)  # theta^3 * 2/3 near 0
            continue
        step = f / d
        theta = min(max(theta - step, 0.0), 0.5 * math.pi)
        if abs(step) < 1e-14:
            break
    return math.sin(theta)


def light_at_sample(light, light_index, s, count, jitter=False, progressive=False):
    """``light`` as it shines in sample ``s`` of ``count``: moved to a point of itself (a
    direction inside its cone for a sun), with PCSS's light size scaled by 1/sqrt(count).
    Lights without size, and every light in a frame of one sample, keep the light's centre.
    ``jitter``: its maps are also shifted by ``map_jitter`` (a light without size then
    differs from sample to sample by that shift alone). ``progressive``: pixels may stop
    early (adaptive sampling), so the points come from a sequence whose every power-of-two
    prefix is stratified (``_light_point_progressive``) rather than from the set of ``count``
    (the sun's spiral, the shuffled Hammersley set), which only the whole set stratifies."""
    if count <= 1:
        return light
    shift = map_jitter(s, light_index, count) if jitter else (0.0, 0.0)
    # Jittered maps average the lookups of N texel grids, so the normal offset, which moves
    # every edge the same way in every sample (it shifts a sun's edges and erodes a local
    # light's shadows by a fraction of a texel), shrinks as 1/sqrt(N), as the texel noise it
    # guards against averages out. The depth biases stay: shrinking them bought nothing on
    # the analytic scenes, gave a spot's grazing far ground acne (a perspective map's depth
    # is not linear across texels) and darkened smooth low-poly terminators that Cycles
    # lights with its shadow-terminator offset.
    offset = light.offset_scale / math.sqrt(count) if jitter else light.offset_scale
    if not has_size(light):
        if not jitter:
            return light
        # Its shadow is a hard one on a moving texel grid: the sampled path (PCSS, which
        # reads a light without size with one bilinear lookup) rather than the scene's filter,
        # whose fixed kernel would blur every sample alike.
        return dataclasses.replace(light, map_jitter=shift, offset_scale=offset, sampled=True, jittered=True)
    if progressive:

        def point(dims):
            return _light_point_progressive(s, light_index, dims)

    else:

        def point(dims):
            return _light_point(s, light_index, dims, count)

    scale = 1.0 / math.sqrt(count)
    m = np.array(light.matrix, dtype=np.float64)
    if light.type == "SUN":
        x, y = concentric_disk(*point(2)) if progressive else _disc_point(s, light_index, count)
        d = light.direction
        u, v = _basis(d)
        tan_half = math.tan(0.5 * min(light.angle, math.pi * 0.99))
        nd = d + tan_half * (x * u + y * v)
        nd /= np.linalg.norm(nd)
        # Lights shine along their local -Z: rotate the matrix's Z axis onto -nd.
        z = -nd
        xa = cross(m[:3, 1], z)
        if np.linalg.norm(xa) < 1e-12:
            xa = _basis(z)[0]
        xa /= np.linalg.norm(xa)
        m[:3, 0], m[:3, 1], m[:3, 2] = xa, cross(z, xa), z
    elif light.type == "AREA":
        u, v = point(2)
        if light.shape in ("DISK", "ELLIPSE"):
            x, y = concentric_disk(u, v)
            x, y = 0.5 * x, 0.5 * y
        else:
            x, y = u - 0.5, v - 0.5
        local = np.array([x * light.size_x, y * light.size_y, 0.0, 1.0])
        m[:3, 3] = (m @ local)[:3]  # the light's own axes carry its object scale
    else:  # POINT and SPOT: spheres of their radius, as Cycles and EEVEE draw them
        # A point of the ball with density 1 / sqrt(r^2 - |p|^2): seen from any receiver,
        # its projection is uniform on the disc of the sphere's outline, which is the light
        # a sphere of uniform radiance sends (a uniform ball would crowd the disc's centre).
        u, v, w = point(3)
        z = 1.0 - 2.0 * v
        r_xy = math.sqrt(max(0.0, 1.0 - z * z))
        phi = 2.0 * math.pi * w
        direction = np.array([r_xy * math.cos(phi), r_xy * math.sin(phi), z])
        m[:3, 3] = m[:3, 3] + light.radius * _ball_radius(u) * direction
    return dataclasses.replace(
        light,
        matrix=m,
        penumbra_scale=scale,
        sampled=True,
        map_jitter=shift,
        offset_scale=offset,
        jittered=jitter,
    )


# --- adaptive sampling ------------------------------------------------------------------------


def clock():
    """Seconds on a monotonic clock: what Time Limit counts (read here only, so a test can
    drive it)."""
    return time.monotonic()


ADAPTIVE_STEP = 4  # samples between two convergence checks (Cycles' adaptive step)
MAX_AUTO_MIN_SAMPLES = 4096  # the automatic Min Samples of a Noise Threshold near 0
THRESHOLD_SCALE = 5.0  # Cycles scales the Noise Threshold by 5 before comparing the error with it


def auto_min_samples(threshold):
    """Cycles' automatic Min Samples of a Noise Threshold: 0.1 -> 32, 0.01 -> 64, 0.001 -> 128."""
    return ceil_count(16.0 / max(float(threshold), 1e-12) ** 0.3, ADAPTIVE_STEP, MAX_AUTO_MIN_SAMPLES)


@dataclasses.dataclass(frozen=True)
class Adaptive:
    """What may end a frame's sampling before its last sample. ``threshold``: Cycles' Noise
    Threshold (0: every pixel takes every sample); a pixel whose error estimate (and its
    neighbours') is below it after ``min_samples`` takes no more samples, checked every
    ``step`` samples. ``time_limit``: seconds the samples may take (0: none).
    ``settle``: the Noise Threshold a pixel settles by after the frame's pilot sample (0:
    none; ``features/settling.py``): no sample could change it by as much (no moving shadow edge,
    highlight or facet, no edge or detail under the pixel filter), so it takes no other."""

    threshold: float = 0.0
    min_samples: int = ADAPTIVE_STEP
    time_limit: float = 0.0
    step: int = ADAPTIVE_STEP
    settle: float = 0.0

    def checks_at(self, done):
        """Whether the convergence check runs after ``done`` samples (an even count, so half of
        them are the "every other sample" the estimate compares with)."""
        return self.threshold > 0.0 and done >= self.min_samples and done % self.step == 0


def adaptive_settings(use, threshold, min_samples, time_limit, sample_count):
    """The ``Adaptive`` of a frame of ``sample_count`` samples (0: without end) from its
    settings, or None when nothing can end it early: adaptive sampling off or a threshold of
    0, and no time limit. Pixels settle after a pilot sample unless Min Samples asks for
    more than one sample a pixel; the noise check starts at Min Samples (automatic: Cycles'
    rule), and is left out when it would come after the last sample."""
    threshold = float(threshold) if use else 0.0
    settle = threshold if threshold > 0.0 and int(min_samples) <= 1 and sample_count != 1 else 0.0
    if threshold > 0.0:
        first = max(ADAPTIVE_STEP, int(min_samples)) if min_samples > 0 else auto_min_samples(threshold)
        first = -(-first // ADAPTIVE_STEP) * ADAPTIVE_STEP  # checks fall on multiples of the step
        if 0 < sample_count <= first:
            threshold = 0.0  # the last sample comes before any check: the frame is the plain one
    else:
        first = ADAPTIVE_STEP
    if threshold <= 0.0 and time_limit <= 0.0 and settle <= 0.0:
        return None
    return Adaptive(
        threshold=threshold,
        min_samples=first if threshold > 0.0 else 0,
        time_limit=float(time_limit),
        settle=settle,
    )


def world_is_black(world):
    """Whether ``world`` (a ``materials.World`` with its SH light, or a constant colour) gives
    no light at all."""
    sh = getattr(world, "sh", None)
    if sh is not None:
        values = np.asarray(sh, np.float64)
    elif hasattr(world, "sh"):  # an Environment Texture's world whose light is not yet known
        values = np.asarray(world.mean, np.float64)
    else:
        values = np.asarray(world if world is not None else (0.0, 0.0, 0.0), np.float64)
    return not bool(np.any(values[np.isfinite(values)] != 0.0))
