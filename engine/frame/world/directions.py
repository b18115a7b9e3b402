"""The world's light with visibility: directions sampled from the world's light, each a sun
with its own shadow map (numpy only; no bpy, no gpu).

The lit pass lights every surface with the world's SH light, unshadowed (``lit.frag.glsl``
``world_light``). Each sample adds a few directions of the world as suns whose shadow maps
say what blocks them; each such sun adds to two sums per surface point and lobe (diffuse,
specular),

    N += f(w) cos(w) V(w) L(w) / (p(w) K)        D += f(w) cos(w) L(w) / (p(w) K)

where ``L`` is the world's radiance, ``V`` the visibility from the sun's map, ``p`` the
probability the direction was drawn with and ``K`` the directions per sample. The film
accumulates both over the frame's samples with the colour's weights and shadows the SH light
by their ratio at resolve: the world's light is U N / D per lobe (Heitz, Hill and McGuire
2018), U the SH light. N / D lies in [0, 1], so the light lies in [0, U]: never negative,
exact where nothing blocks (an open ground has no noise at all), and consistent: as the
samples grow it tends to U x (the lobe's light with visibility over its light without), which
is Cycles' direct light with no bounces where U is the lobe's unshadowed light. Its bias is
the SH light's error in that proportion (docs/design.md has it measured).

Directions are drawn in proportion to the world's luminance per solid angle (an Environment
Texture's image, box-filtered to at most 128 x 64 texels: ``TextureCache.world_env``), mixed
with a uniform share of the sphere so every direction where the world gives light can be
drawn (defensive importance sampling, Hesterberg 1995); a constant world is drawn uniformly.
The points are a (0, 2)-sequence (van der Corput, Sobol' 2), digitally shifted, so the
directions of any first 2^k samples are stratified and a progressive viewport frame stays so.

Cycles' light portals (``portal_cones``) gather three quarters of the directions in cones
through them; such a frame gives the directions the world's whole light, f cos V L / p (no
SH light: inside a room a ratio of a few directions to the sky's SH light says little).
"""

import math

import numpy as np

from ...counts import ceil_count
from ...scene.extract import Light
from ...scene.materials import SH_C0, sh_basis
from ...shadows.vectors import cross
from ..sampling import radical_inverse, sobol_2

# The share of directions drawn uniformly over the sphere (the rest follow the luminance).
UNIFORM_SHARE = 0.15
# With light portals, the share of directions drawn in the cones through them.
PORTAL_SHARE = 0.75
_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
_SCRAMBLE = (0x6C8E9CF5, 0x2545F491)  # digital shifts of the two coordinates


# A world that gives at least this share of the light reaching the view takes every direction
# per sample (World > Directions per Sample); below it, directions in proportion.
FULL_SHARE = 0.5


# Without adaptive sampling, the Noise Threshold a world's light is negligible by
# (``world_negligible``): a tenth of Cycles' default.
NEGLIGIBLE_ERROR = 0.001


def world_negligible(world, threshold=0.0):
    """Whether the light of ``world`` (a ``materials.World`` with its SH light, or a
    constant colour) is wholly under the noise a frame accepts, so shadowing it could move
    no pixel by as much: it then takes no directions and no ambient occlusion, and lights
    every surface unshadowed. In Cycles' error units (a difference over the square root of
    the pixel's value) a pixel lit by the world alone, occluded or not, differs by sqrt(U),
    U the world's radiance off a white surface facing its brightest axis (the SH irradiance
    over pi, luminance): negligible where sqrt(U) < ``threshold`` (the frame's Noise
    Threshold; NEGLIGIBLE_ERROR when 0). A black world is; any brighter one, however bright
    its lamps, may not be (a pixel in their shadow sees the world's light alone)."""
    threshold = threshold if threshold > 0.0 else NEGLIGIBLE_ERROR
    if getattr(world, "sh", None) is not None:
        radiance = _world_irradiance(world) / math.pi
    else:  # a constant colour (no World datablock), or an image's light not yet known: its mean
        colour = world.mean if hasattr(world, "sh") else (world if world is not None else (0.0, 0.0, 0.0))
        radiance = float(np.nan_to_num(np.asarray(colour, np.float64)[:3], posinf=1e30) @ _LUMINANCE)
    return math.sqrt(max(radiance, 0.0)) < threshold


def _world_irradiance(world):
    """The world's SH irradiance on its brightest of the six axes, in luminance."""
    axes = np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]], np.float64)
    sh = np.nan_to_num(np.asarray(world.sh, np.float64), posinf=0.0, neginf=0.0)
    return math.pi * float(np.max(np.maximum(sh_basis(axes) @ sh, 0.0) @ _LUMINANCE))


def light_share(world, lights, centre):
    """The world's share of the light reaching a surface at ``centre`` (the middle of what the
    camera sees) that faces each source: its irradiance from the SH light's brightest axis
    (pi x radiance, luminance) against each lamp's unshadowed irradiance there (Blender's
    conventions, lights.glsl: a sun's strength, P / (4 pi (d^2 + r^2)) for points and spots,
    cones ignored, P / (pi d^2) for areas). 1 without lamps; 0 for a black world."""
    world_e = _world_irradiance(world)
    lamps = 0.0
    centre = np.asarray(centre, np.float64)
    for light in lights:
        power = float(np.nan_to_num(np.asarray(light.color, np.float64) @ _LUMINANCE, posinf=1e30))
        if light.type == "SUN":
            lamps += max(power, 0.0)
            continue
        d2 = float(np.sum((np.asarray(light.position, np.float64) - centre) ** 2))
        if light.type == "AREA":
            lamps += max(power, 0.0) / (math.pi * max(d2, 1e-12))
        else:
            lamps += max(power, 0.0) / (4.0 * math.pi * max(d2 + light.radius**2, 1e-12))
    total = world_e + lamps
    return world_e / total if total > 0.0 and math.isfinite(total) else (1.0 if lamps == 0.0 else 0.0)


def directions_per_sample(share, most):
    """Directions of the world per sample for its ``share`` of the light: all ``most`` from
    FULL_SHARE on (a sky-lit scene), in proportion below, at least one (its shadows are still
    what lights the lamps' shadows)."""
    if most <= 0:
        return 0
    return ceil_count(most * share / FULL_SHARE - 1e-9, 1, most)


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

    def __init__(self, sh, env=None, cones=(), rotation=None):
        self.sh = np.nan_to_num(np.asarray(sh, np.float64), posinf=0.0, neginf=0.0)
        # world direction -> the image's (an Environment Texture's Mapping), or None
        self.rotation = None if rotation is None else np.asarray(rotation, np.float64)
        # (unit axis, cos of the half-angle) of each portal's cone (``portal_cones``), or a
        # ``guide``: a WorldDistribution of where the light gets in (``world/probe.py``).
        self.cones = [
            c if isinstance(c, WorldDistribution) else (np.asarray(c[0], np.float64), float(c[1]))
            for c in cones
            if isinstance(c, WorldDistribution) or -1.0 <= c[1] < 1.0
        ]
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
        base = self._base_pdf(d)
        if not self.cones:
            return base
        cones = np.zeros(len(d))
        for cone in self.cones:
            if isinstance(cone, WorldDistribution):
                cones += cone.image_pdf(d)
                continue
            axis, cos_max = cone
            inside = d @ axis >= cos_max
            cones += inside / (2.0 * math.pi * (1.0 - cos_max))
        return PORTAL_SHARE * cones / len(self.cones) + (1.0 - PORTAL_SHARE) * base

    def _base_pdf(self, d):
        uniform = np.full(len(d), 1.0 / (4.0 * math.pi))
        if self.env is None:
            return uniform
        return UNIFORM_SHARE * uniform + (1.0 - UNIFORM_SHARE) * self.image_pdf(d)

    def image_pdf(self, d):
        """The density (per steradian) of ``_from_image``'s directions at ``d`` (n, 3)."""
        r, c = self._texel(d)
        return self.p_texel[r, c] / self.band[r]

    def _texel(self, d):
        if self.rotation is not None:
            d = d @ self.rotation.T
        return equirect_cell(d, *self.env.shape[:2])

    def directions(self, points):
        """Unit directions (n, 3) from points ``points`` (n, 2) of [0, 1)^2."""
        points = np.asarray(points, np.float64).reshape(-1, 2)
        if not self.cones:
            return self._base_directions(points)
        a, b = points[:, 0], points[:, 1]
        out = np.empty((len(points), 3))
        in_cone = a < PORTAL_SHARE
        rest = ~in_cone
        if rest.any():
            ar = np.clip((a[rest] - PORTAL_SHARE) / (1.0 - PORTAL_SHARE), 0.0, 1.0 - 1e-12)
            out[rest] = self._base_directions(np.stack([ar, b[rest]], axis=-1))
        n = len(self.cones)
        for k in np.nonzero(in_cone)[0]:
            x = a[k] / PORTAL_SHARE * n
            i = min(int(x), n - 1)
            if isinstance(self.cones[i], WorldDistribution):
                out[k] = self.cones[i]._from_image(np.array([min(x - i, 1.0 - 1e-12)]), np.array([b[k]]))[0]
                continue
            axis, cos_max = self.cones[i]
            out[k] = _in_cone(axis, cos_max, min(x - i, 1.0 - 1e-12), b[k])
        return out

    def _base_directions(self, points):
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
        lon = (0.5 - (c + fc) / w) * 2.0 * math.pi  # atan2(y, x)
        cl = np.cos(lat)
        d = np.stack([np.cos(lon) * cl, np.sin(lon) * cl, np.sin(lat)], axis=-1)
        return d if self.rotation is None else d @ self.rotation  # the image's direction -> the world's


def equirect_cell(d, h, w):
    """(row, column) of unit directions ``d`` (n, 3) on an (h, w) equirectangular grid as
    Blender maps it (row 0 at the bottom): u = 0.5 - atan2(y, x) / 2 pi, v = atan2(z, hypot(x,
    y)) / pi + 0.5."""
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    u = 0.5 - np.arctan2(y, x) / (2.0 * math.pi)
    v = np.arctan2(z, np.hypot(x, y)) / math.pi + 0.5
    return np.clip((v * h).astype(np.int64), 0, h - 1), np.clip((u * w).astype(np.int64), 0, w - 1)


def _in_cone(axis, cos_max, a, b):
    """A uniform direction within ``cos_max`` of ``axis`` from (a, b) of [0, 1)^2."""
    z = 1.0 - a * (1.0 - cos_max)
    r = math.sqrt(max(1.0 - z * z, 0.0))
    phi = 2.0 * math.pi * b
    frame = frame_towards(axis)
    return frame @ np.array([r * math.cos(phi), r * math.sin(phi), z])


def guide(weights):
    """A distribution of directions (a ``WorldDistribution`` whose image is ``weights``, an
    (h, w) equirectangular grid in world directions, row 0 at the bottom, as the world's
    images are read) that a frame's ``cones`` can hold in place of a cone: its directions are
    drawn in proportion to each cell's weight (``world/probe.py``: where the world's light gets
    into an interior). None where the weights hold nothing."""
    weights = np.nan_to_num(np.asarray(weights, np.float64), posinf=0.0, neginf=0.0)
    h, w = weights.shape
    band = np.diff(np.sin((np.arange(h + 1) / h - 0.5) * math.pi)) * (2.0 * math.pi / w)
    per_sr = np.clip(weights, 0.0, None) / band[:, None]  # the grid's weight per solid angle
    dist = WorldDistribution(np.zeros((9, 3)), np.repeat(per_sr[..., None], 3, axis=-1) / _LUMINANCE.sum())
    return dist if dist.env is not None else None


def portal_cones(portals, lo, hi):
    """Per light portal (``Snapshot.portals``: matrix, size x, size y), the cone of directions
    that can reach the box [lo, hi] (what the camera sees) through it from the sky: around
    the direction from the box's centre to the portal, wide enough for the portal's and the
    box's extents seen from there (a hemisphere at most). Directions of the world drawn in
    these cones are the ones that light a room through its windows."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        return []
    centre = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo))
    cones = []
    for matrix, size_x, size_y in portals:
        m = np.asarray(matrix, np.float64)
        if not np.all(np.isfinite(m)):
            continue
        reach = 0.5 * math.hypot(np.linalg.norm(m[:3, 0]) * size_x, np.linalg.norm(m[:3, 1]) * size_y)
        axis = m[:3, 3] - centre
        dist = float(np.linalg.norm(axis))
        if dist > 1e-9 * max(radius, 1.0):
            axis = axis / dist
        else:  # the portal at the box's centre: the half-space it faces away from (its +Z)
            z = m[:3, 2]
            axis = z / max(float(np.linalg.norm(z)), 1e-300)
        half = min(math.atan2(reach + radius, dist), 0.5 * math.pi)
        cones.append((axis, math.cos(half)))
    return cones


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


def distribution(world, cones=()):
    """The ``WorldDistribution`` of ``world`` (a ``materials.World`` whose SH is known) with
    the portals' ``cones``, remembered on the world object for those cones (a snapshot's
    world is rebuilt when the world changes)."""
    key = tuple(
        id(c) if isinstance(c, WorldDistribution) else (tuple(np.round(c[0], 12)), round(c[1], 12)) for c in cones
    )
    cached = getattr(world, "_distribution", None)
    if cached is None or cached[0] != key:
        cached = (
            key,
            WorldDistribution(world.sh, getattr(world, "env", None), cones, getattr(world, "rotation", None)),
        )
        object.__setattr__(world, "_distribution", cached)
    return cached[1]


def world_lights(world, index, count, name="World", cones=()):
    """The ``count`` world directions of one sample, as suns (``extract.Light`` with
    ``world`` set): directions ``index`` .. ``index + count - 1`` of the frame's sequence.
    Each sun's colour is the world's radiance from it over (its probability x ``count``):
    without portals the lit pass adds f cos V L / p and f cos L / p of it to the ratio that
    shadows the SH light (lit.frag.glsl WORLD_RATIO). With light portals (``cones``) the
    directions gather in the portals' cones and carry the world's whole light: inside a room
    the ratio of a few directions to the sky's SH light says little, so such a frame lights
    surfaces with these directions alone (``build_frame_data``'s ``world_sh`` False)."""
    dist = distribution(world, cones)
    d = dist.directions(sequence_points(index, count))
    pdf = np.maximum(dist.pdf(d), 1e-30)
    scale = 1.0 / (pdf * count)
    radiance = dist.radiance(d) * scale[:, None]
    lights = []
    for k in range(count):
        matrix = np.eye(4)
        matrix[:3, :3] = frame_towards(d[k])  # the sun shines along -Z: from d[k]
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
            )
        )
    return lights


def frame_towards(d):
    """A rotation whose Z axis is ``d`` (a light's -Z is where it shines)."""
    z = d / max(np.linalg.norm(d), 1e-300)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[2]) > 0.9 else np.array([0.0, 0.0, 1.0])
    x = cross(helper, z)
    x /= max(np.linalg.norm(x), 1e-300)
    y = cross(z, x)
    return np.stack([x, y, z], axis=1)
