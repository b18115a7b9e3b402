"""The world's light with visibility: directions sampled from the world's light, each a sun
with its own shadow map (numpy only; no bpy, no gpu).

The lit pass lights every surface with the world's SH light, unshadowed (``lights.glsl``
``world_light``). Each sample adds a few directions of the world as suns whose shadow maps
say what blocks them; each such sun adds, per surface point,

    f(w) cos(w) (V(w) L(w) - L_sh(w)) / (p(w) K)

where ``L`` is the world's radiance, ``L_sh`` its order-2 SH radiance (the light the lit pass
already gave, unshadowed), ``V`` the visibility from the sun's map, ``p`` the probability the
direction was drawn with and ``K`` the directions per sample. Its mean over the frame's
samples is the world's direct light with visibility minus the SH light's unshadowed
irradiance: with the SH term it sums to the world's direct light with visibility, which is
what Cycles renders with no bounces (a control variate: where nothing blocks a uniform world,
the two cancel exactly and the open ground has no noise at all). The SH diffuse term is
exactly the integral of ``L_sh`` against the clamped cosine (Funk-Hecke), so the estimate is
unbiased for diffuse surfaces whatever the world's image holds.

Directions are drawn in proportion to the world's luminance per solid angle (an Environment
Texture's image, box-filtered to at most 128 x 64 texels: ``TextureCache.world_env``), mixed
with a uniform share of the sphere so every direction where ``L_sh`` is not zero can be
drawn (defensive importance sampling, Hesterberg 1995); a constant world is drawn uniformly.
The points are a (0, 2)-sequence (van der Corput, Sobol' 2), digitally shifted, so the
directions of any first 2^k samples are stratified and a progressive viewport frame stays so.
"""

import math

import numpy as np

from ..scene.extract import Light
from ..scene.materials import SH_C0, sh_basis
from .sampling import radical_inverse, sobol_2

# The share of directions drawn uniformly over the sphere (the rest follow the luminance).
UNIFORM_SHARE = 0.15
_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
_SCRAMBLE = (0x6C8E9CF5, 0x2545F491)  # digital shifts of the two coordinates


def world_radiance(world):
    """The world's mean radiance (rgb), 0 for no world."""
    if world is None:
        return np.zeros(3)
    return np.nan_to_num(np.asarray(world.mean, np.float64), posinf=0.0, neginf=0.0)


def needs_directions(world, settings):
    """Whether the world's light is sampled with shadow maps this frame: World > Shadows on,
    and a world that gives any light (a black world costs nothing)."""
    if world is None or not bool(getattr(settings, "world_shadows", False)):
        return False
    sh = getattr(world, "sh", None)
    return sh is not None and bool(np.any(np.abs(np.nan_to_num(sh)) > 0.0))


class WorldDistribution:
    """How directions of ``world`` (a ``materials.World`` with its SH light) are drawn: in
    proportion to luminance per solid angle of its environment image ``env`` (h, w, 3), row 0
    at the bottom, or uniformly for a constant world (``env`` None)."""

    def __init__(self, sh, env=None):
        self.sh = np.nan_to_num(np.asarray(sh, np.float64), posinf=0.0, neginf=0.0)
        self.env = None
        if env is not None:
            env = np.nan_to_num(np.asarray(env, np.float64)[..., :3], posinf=0.0, neginf=0.0)
            env = np.clip(env, 0.0, 1e30)
            h, w = env.shape[:2]
            lat_edges = (np.arange(h + 1) / h - 0.5) * math.pi
            # A texel's solid angle: its longitude span times the difference of the sines of
            # its latitude edges (exact for the equirectangular grid).
            band = np.diff(np.sin(lat_edges)) * (2.0 * math.pi / w)  # (h,)
            weight = (env @ _LUMINANCE) * band[:, None]
            total = float(weight.sum())
            if total > 0.0 and np.isfinite(total):
                self.env = env
                self.band = band
                self.sin_edges = np.sin(lat_edges)
                p = weight / total  # each texel's probability
                self.p_texel = p
                rows = p.sum(axis=1)
                self.row_cdf = np.concatenate([[0.0], np.cumsum(rows)])
                self.row_cdf[-1] = 1.0
                with np.errstate(invalid="ignore", divide="ignore"):
                    cond = np.cumsum(p, axis=1) / rows[:, None]
                cond = np.where(np.isfinite(cond), cond, (np.arange(1, w + 1) / w)[None, :])
                cond[:, -1] = 1.0
                self.col_cdf = np.concatenate([np.zeros((h, 1)), cond], axis=1)

    @property
    def uniform_share(self):
        return 1.0 if self.env is None else UNIFORM_SHARE

    def radiance(self, d):
        """The world's radiance (n, 3) towards unit directions ``d`` (n, 3)."""
        if self.env is None:
            return np.broadcast_to(self.sh[0] * SH_C0, d.shape).copy()
        r, c = self._texel(d)
        return self.env[r, c]

    def sh_radiance(self, d):
        """The world's order-2 SH radiance (n, 3) towards ``d``: what the lit pass's SH light
        integrates against the cosine."""
        return sh_basis(d) @ self.sh

    def pdf(self, d):
        """The probability density (per steradian) of drawing unit directions ``d`` (n, 3)."""
        uniform = np.full(len(d), 1.0 / (4.0 * math.pi))
        if self.env is None:
            return uniform
        r, c = self._texel(d)
        lum = self.p_texel[r, c] / self.band[r]
        return UNIFORM_SHARE * uniform + (1.0 - UNIFORM_SHARE) * lum

    def _texel(self, d):
        h, w = self.env.shape[:2]
        x, y, z = d[:, 0], d[:, 1], d[:, 2]
        u = np.arctan2(y, -x) / (2.0 * math.pi) + 0.5
        v = np.arctan2(z, np.hypot(x, y)) / math.pi + 0.5
        return np.clip((v * h).astype(np.int64), 0, h - 1), np.clip((u * w).astype(np.int64), 0, w - 1)

    def directions(self, points):
        """Unit directions (n, 3) from points ``points`` (n, 2) of [0, 1)^2."""
        points = np.asarray(points, np.float64).reshape(-1, 2)
        a, b = points[:, 0], points[:, 1]
        share = self.uniform_share
        uniform = a < share
        out = np.empty((len(points), 3))
        au = np.clip(a / share, 0.0, 1.0)
        out[:] = _sphere(au, b)
        if self.env is not None and not np.all(uniform):
            k = ~uniform
            al = np.clip((a[k] - share) / (1.0 - share), 0.0, 1.0 - 1e-12)
            out[k] = self._from_image(al, b[k])
        return out

    def _from_image(self, a, b):
        """Directions drawn in proportion to each texel's probability: the row by ``a``, the
        texel in it by ``b``, and the point within the texel uniform in solid angle from what
        is left of each."""
        h, w = self.env.shape[:2]
        r = np.clip(np.searchsorted(self.row_cdf, a, side="right") - 1, 0, h - 1)
        lo, hi = self.row_cdf[r], self.row_cdf[r + 1]
        fr = np.clip((a - lo) / np.maximum(hi - lo, 1e-300), 0.0, 1.0)
        cdf = self.col_cdf[r]
        c = np.clip(np.array([np.searchsorted(cdf[i], b[i], side="right") - 1 for i in range(len(b))]), 0, w - 1)
        clo, chi = cdf[np.arange(len(b)), c], cdf[np.arange(len(b)), c + 1]
        fc = np.clip((b - clo) / np.maximum(chi - clo, 1e-300), 0.0, 1.0)
        sin_lat = self.sin_edges[r] + fr * (self.sin_edges[r + 1] - self.sin_edges[r])
        lat = np.arcsin(np.clip(sin_lat, -1.0, 1.0))
        lon = ((c + fc) / w - 0.5) * 2.0 * math.pi
        cl = np.cos(lat)
        return np.stack([-np.cos(lon) * cl, np.sin(lon) * cl, np.sin(lat)], axis=-1)


def _sphere(a, b):
    """Uniform directions on the sphere from [0, 1)^2 (equal areas: z = 1 - 2a)."""
    z = 1.0 - 2.0 * a
    r = np.sqrt(np.clip(1.0 - z * z, 0.0, 1.0))
    phi = 2.0 * math.pi * b
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def sequence_points(first, count):
    """Points ``first`` .. ``first + count - 1`` of the digitally shifted (0, 2)-sequence."""
    out = np.empty((count, 2))
    for n in range(count):
        j = first + n
        out[n, 0] = (int(radical_inverse(j, 2) * (1 << 32)) ^ _SCRAMBLE[0]) / 2.0**32
        out[n, 1] = (sobol_2(j) ^ _SCRAMBLE[1]) / 2.0**32
    return out


def distribution(world):
    """The ``WorldDistribution`` of ``world`` (a ``materials.World`` whose SH is known),
    remembered on the world object (a snapshot's world is rebuilt when the world changes)."""
    dist = getattr(world, "_distribution", None)
    if dist is None:
        dist = WorldDistribution(world.sh, getattr(world, "env", None))
        object.__setattr__(world, "_distribution", dist)
    return dist


def world_lights(world, index, count, name="World"):
    """The ``count`` world directions of one sample, as suns (``extract.Light`` with
    ``world`` set): directions ``index`` .. ``index + count - 1`` of the frame's sequence.
    Each sun's colour is the world's radiance from it over (its probability x ``count``),
    its ``world_baseline`` the same of the SH radiance."""
    dist = distribution(world)
    d = dist.directions(sequence_points(index, count))
    pdf = np.maximum(dist.pdf(d), 1e-30)
    scale = 1.0 / (pdf * count)
    radiance = dist.radiance(d) * scale[:, None]
    baseline = dist.sh_radiance(d) * scale[:, None]
    lights = []
    for k in range(count):
        matrix = np.eye(4)
        matrix[:3, :3] = _frame_towards(d[k])  # the sun shines along -Z: from d[k]
        lights.append(
            Light(
                type="SUN",
                color=radiance[k],
                matrix=matrix,
                radius=0.0,
                angle=0.0,
                use_shadow=True,
                name=f"{name} {k + 1}",
                world=True,
                world_baseline=baseline[k],
            )
        )
    return lights


def _frame_towards(d):
    """A rotation whose Z axis is ``d`` (a light's -Z is where it shines)."""
    z = d / max(np.linalg.norm(d), 1e-300)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[2]) > 0.9 else np.array([0.0, 0.0, 1.0])
    x = np.cross(helper, z)
    x /= max(np.linalg.norm(x), 1e-300)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)
