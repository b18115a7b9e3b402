"""Object › Shading › Shadow Terminator, as Blender's engines define it (numpy only).

- *Geometry Offset* (Cycles): a smooth-shaded triangle's shadow point is lifted from the flat
  triangle towards the smooth surface its vertex normals imply (Hanika, "Hacking the Shadow
  Terminator", Ray Tracing Gems II, 2021, in Cycles' form): a parabolic estimate of that
  surface, bounded by a local linear envelope of the three vertices' tangent planes, along the
  interpolated normal, blended in where the smooth normal and the light make a grazing angle
  (the blend reaches from 0 to 1 over ``geometry_offset`` of the cosine). Flat faces get no
  offset: their corner normals are the face normal and every term below is 0.
- *Shading Offset* (Cycles): the cosine term becomes max(cos(f * theta), 0) with
  f = 1 / (1 - offset / 2), pushing the terminator towards the light.
- *Normal Offset* (EEVEE): the shadow point moves along the normal by
  ``normal_offset`` (object units) x saturate(1 - N.L / geometry_offset).

The lit pass evaluates the geometry offset per fragment from per-corner data that is linear
over each triangle (``corner_data``), so the rasteriser's interpolation gives the exact
per-point values without a geometry shader; ``smooth_offset`` is the same offset evaluated
directly from the triangle, the reference the per-corner form is tested against.
"""

import math
from dataclasses import dataclass

import numpy as np

from ..store import Kind
from .geometry import content_key

# Names of the per-corner vertex attributes of ``corner_data`` (and the shader's inputs).
ATTRIBUTES = ("tbary", "tabc", "tfront", "tback")


@dataclass(frozen=True)
class Terminator:
    """An object's Shadow Terminator settings, as Blender stores them."""

    geometry_offset: float = 0.1  # Cycles' default
    shading_offset: float = 0.0
    normal_offset: float = 0.0  # EEVEE's, object units

    @classmethod
    def of(cls, ob):
        def value(name, default):
            v = float(getattr(ob, name, default))
            return v if math.isfinite(v) else default

        return cls(
            geometry_offset=min(max(value("shadow_terminator_geometry_offset", 0.1), 0.0), 1.0),
            shading_offset=min(max(value("shadow_terminator_shading_offset", 0.0), 0.0), 1.0),
            normal_offset=max(value("shadow_terminator_normal_offset", 0.0), 0.0),
        )

    @property
    def frequency(self):
        """Cycles' cosine frequency multiplier of the Shading Offset (1: no change)."""
        return 1.0 / (1.0 - 0.5 * self.shading_offset)

    def world_normal_offset(self, matrix):
        """EEVEE's Normal Offset in world units: object units times the object's largest axis
        scale (0 for a degenerate matrix)."""
        if self.normal_offset <= 0.0 or self.geometry_offset <= 0.0:
            return 0.0
        scale = float(np.max(np.linalg.norm(np.asarray(matrix, np.float64)[:3, :3], axis=0)))
        value = self.normal_offset * scale
        return value if math.isfinite(value) else 0.0


# content digest of (positions, normals, indices) -> corner_data: final renders build anew
_CORNERS = Kind("corners")


def corner_data_cached(positions, normals, indices):
    """``corner_data``, remembered by the content of its inputs (as ``extract._closed_cached``
    remembers closedness): every F12 render is a new engine that builds its batches anew, and
    hashing the arrays costs a small part of computing the corners again."""
    key = content_key(positions, normals, indices)
    got = _CORNERS.get(key)
    if got is None:
        got = corner_data(positions, normals, indices)
        _CORNERS.put(key, got, sum(v.nbytes for v in got.values()))
    return got


def corner_data(positions, normals, indices):
    """Per-corner attributes (one row per corner of each triangle, in ``indices`` order) from
    which a fragment rebuilds its triangle's smooth-surface offset:

    tbary   (u, v): barycentric weights of the triangle's first and second vertex
    tabc    (a, b, c): the parabola's coefficients (the same at all three corners)
    tfront  the three vertices' tangent-plane heights over the point, each raised by its
            vertex's envelope term, for a triangle seen from its normals' side: affine over
            the triangle, so interpolation gives them exactly
    tback   the same for a triangle seen from behind

    Positions and normals are the object's (local) ones; the lit pass moves the offset to
    world space with the model matrix, as Cycles does for instanced objects."""
    tris = np.asarray(indices, np.int64).reshape(-1, 3)
    V = np.asarray(positions, np.float32)[tris].astype(np.float64)  # (t, 3 vertices, 3)
    N = np.asarray(normals, np.float32)[tris].astype(np.float64)
    V[~np.isfinite(V)] = 0.0
    N[~np.isfinite(N)] = 0.0
    t = len(tris)
    # d[t, k, i] = dot(V_k - V_i, N_i): k a corner, i a vertex.
    vn = np.einsum("tkx,tix->tki", V, N)  # dot(V_k, N_i)
    d = vn - np.diagonal(vn, axis1=1, axis2=2)[:, None, :]
    a = np.einsum("ij,ij->i", N[:, 2] - N[:, 0], V[:, 0] - V[:, 2])
    b = np.einsum("ij,ij->i", N[:, 2] - N[:, 1], V[:, 1] - V[:, 2])
    c = np.einsum("ij,ij->i", N[:, 1] - N[:, 0], V[:, 1] - V[:, 0])
    # Envelope terms: max over j != i of dot(V_j - V_i, N_i) (front) and of its negative (back).
    # d[:, i, i] = 0, so the off-diagonal maxima come from the other two corners.
    k1, k2 = np.array([1, 0, 0]), np.array([2, 2, 1])
    i3 = np.arange(3)
    dj, dk = d[:, k1, i3], d[:, k2, i3]  # (t, i): the two other corners of vertex i
    front_env = np.maximum(np.maximum(dj, dk), 0.0)
    back_env = np.maximum(np.maximum(-dj, -dk), 0.0)
    # At corner k: dot(V_i - V_k, N_i) + front_env_i and dot(V_k - V_i, N_i) + back_env_i.
    front = front_env[:, None, :] - d
    back = d + back_env[:, None, :]
    bary = np.zeros((t, 3, 2))
    bary[:, 0, 0] = 1.0
    bary[:, 1, 1] = 1.0
    abc = np.repeat(np.stack([a, b, c], axis=1)[:, None, :], 3, axis=1)
    out = {"tbary": bary, "tabc": abc, "tfront": front, "tback": back}
    return {k: _finite32(v.reshape(-1, v.shape[-1])) for k, v in out.items()}


def _finite32(a):
    a = np.asarray(a, np.float64)
    a[~np.isfinite(a)] = 0.0
    big = float(np.finfo(np.float32).max) / 4.0
    np.clip(a, -big, big, out=a)
    return np.ascontiguousarray(a, np.float32)


def smooth_offset(V, N, bary, toward_viewer):
    """The smooth-surface offset vector (object space) at barycentric ``bary`` = (u, v, w) of
    triangle ``V`` (3, 3) with vertex normals ``N`` (3, 3): the interpolated normal times the
    height h of the parabolic estimate, bounded by the vertices' tangent planes. ``toward_viewer``
    is the triangle's plane normal turned towards the side it is seen from: seen from the normals'
    side h >= 0, from behind h <= 0. The reference for the shader's per-corner form."""
    V = np.asarray(V, np.float64)
    N = np.asarray(N, np.float64)
    u, v, w = bary
    P = u * V[0] + v * V[1] + w * V[2]
    n = u * N[0] + v * N[1] + w * N[2]
    a = np.dot(N[2] - N[0], V[0] - V[2])
    b = np.dot(N[2] - N[1], V[1] - V[2])
    c = np.dot(N[1] - N[0], V[1] - V[0])
    h = a * u * (u - 1) + (a + b + c) * u * v + b * v * (v - 1)
    idx = ((0, 1, 2), (1, 0, 2), (2, 0, 1))
    if np.dot(n, toward_viewer) > 0:
        env = [max(np.dot(V[j] - V[i], N[i]), np.dot(V[k] - V[i], N[i]), 0.0) for i, j, k in idx]
        hs = [max(np.dot(V[i] - P, N[i]) + env[i], 0.0) for i in range(3)]
        h = max(min(hs), 0.5 * h)
    else:
        env = [max(np.dot(V[i] - V[j], N[i]), np.dot(V[i] - V[k], N[i]), 0.0) for i, j, k in idx]
        hs = [max(np.dot(P - V[i], N[i]) + env[i], 0.0) for i in range(3)]
        h = min(-min(hs), 0.5 * h)
    return n * h


def offset_amount(cutoff, NL, NgL):
    """How much of the offset a light direction gets: 1 where the smooth normal (``NL``, its
    cosine with the light) and the flat triangle (``NgL``) are grazing, fading to 0 over
    ``cutoff`` (the Geometry Offset)."""
    if cutoff <= 0.0:
        return 0.0
    if NL < cutoff:
        return float(np.clip(2.0 - (NgL + NL) / cutoff, 0.0, 1.0))
    return float(np.clip(1.0 - NgL / cutoff, 0.0, 1.0))
