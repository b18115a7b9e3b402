"""The world's sun: an Environment Texture's light above a threshold as a shadowed sun, as
EEVEE's World > Settings > Sun does (Blender 4.2 and later).

Order-2 spherical harmonics spread a small bright source (the sun in an HDRI) over the whole
sky, so the world's SH light keeps the sky's proportions but not the sun's: its shading and,
through the ratio that shadows the SH light (``lit_world.glsl`` WORLD_RATIO), its shadow come
out soft and wrong. Taken out, the radiance above ``WorldSun.threshold`` becomes a sun light
with the frame's other lights (its irradiance, its direction the extracted light's mean, its
angle the World's Sun angle, shadowed when Sun > Shadow is on), and the SH light and the
world's directions are of what is left, min(L, threshold) per channel: both are >= 0, and
they add up to the image's light.

Read from the image box-filtered to at most 128 x 64 texels (``TextureCache.world_env``): the
filter keeps each texel's light, so the sun's power is whole, but a sun smaller than a texel
is read as that texel's mean, and a threshold above it extracts less than EEVEE does from the
full image.
"""

import dataclasses
import hashlib
import math

import numpy as np

from ...scene.extract import Light
from ...scene.materials import equirect_sh
from ...scene.textures import world_background
from .directions import frame_towards

_LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def _directions(h, w):
    """Unit directions (h, w, 3) of an equirectangular image's texel centres and their solid
    angles (h, w), in the image's frame (Blender's mapping, ``materials.equirect_sh``)."""
    lat = ((np.arange(h) + 0.5) / h - 0.5) * math.pi
    lon = (0.5 - (np.arange(w) + 0.5) / w) * 2.0 * math.pi
    cl = np.cos(lat)[:, None]
    d = np.stack(
        [np.cos(lon)[None, :] * cl, np.sin(lon)[None, :] * cl, np.broadcast_to(np.sin(lat)[:, None], (h, w))],
        axis=-1,
    )
    return d, (2.0 * math.pi / w) * (math.pi / h) * np.broadcast_to(cl, (h, w))


# The last few extractions by content (the image's light, the rotation, the Sun settings):
# a frame whose world did not change takes its sun again instead of projecting anew (1-2 ms).
_KEPT = {}
_KEPT_MAX = 4


def with_sun(world):
    """(``world`` with its SH light and ``env`` of what the sun leaves, the sun as an
    ``extract.Light`` or None): None where the world has no Sun threshold, no image light or
    no texel above it."""
    sun = getattr(world, "sun", None)
    env = getattr(world, "env", None)
    if sun is None or env is None or world.sh is None:
        return world, None
    rotation = None if world.rotation is None else np.asarray(world.rotation, np.float64).tobytes()
    key = (hashlib.sha256(np.ascontiguousarray(env).data).digest(), rotation, sun)
    kept = _KEPT.get(key)
    if kept is None:
        kept = _extract(world, sun, env)
        if len(_KEPT) >= _KEPT_MAX:
            _KEPT.pop(next(iter(_KEPT)))
        _KEPT[key] = kept
    if kept is None:
        return world, None
    sh, left, light = kept
    out = dataclasses.replace(world, sh=sh, background=world_background(sh), env=left, sun_clamp=sun.threshold)
    return out, dataclasses.replace(light, matrix=light.matrix.copy(), color=light.color.copy())


def _extract(world, sun, env):
    """(the rest's SH light, the rest, the sun) of ``env``, or None where no texel is above the
    threshold."""
    rgb = np.nan_to_num(np.asarray(env, np.float64)[..., :3], posinf=0.0, neginf=0.0)
    excess = np.maximum(rgb - sun.threshold, 0.0)
    if not np.any(excess > 0.0):
        return None
    d, omega = _directions(*rgb.shape[:2])
    if world.rotation is not None:
        d = d @ np.asarray(world.rotation, np.float64)  # the image's direction -> the world's
    flux = excess * omega[..., None]  # radiance x solid angle: irradiance at normal incidence
    weight = flux @ _LUMINANCE
    axis = np.einsum("hw,hwc->c", weight, d)
    length = float(np.linalg.norm(axis))
    if not (length > 0.0 and math.isfinite(length)):
        return None
    irradiance = flux.sum(axis=(0, 1))
    left = np.minimum(rgb, sun.threshold)
    sh = equirect_sh(left, world.rotation)
    matrix = np.eye(4)
    matrix[:3, :3] = frame_towards(axis / length)
    light = Light(
        type="SUN",
        color=irradiance,
        matrix=matrix,
        radius=0.0,
        angle=max(float(sun.angle), 0.0),
        use_shadow=bool(sun.shadow),
        name="World Sun",
        lightgroup=getattr(world, "lightgroup", ""),
    )
    return sh, left, light
