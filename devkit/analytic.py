"""Analytic references: camera rays, plane hits and box shadows computed in numpy."""

import math

import numpy as np


def camera_matrices(scene, depsgraph=None):
    """(view, projection) of the scene camera as numpy arrays, as Penumbra computes them."""
    import bpy

    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    cam = scene.camera.evaluated_get(depsgraph)
    r = scene.render
    w = int(r.resolution_x * r.resolution_percentage / 100)
    h = int(r.resolution_y * r.resolution_percentage / 100)
    proj = np.array(cam.calc_matrix_camera(depsgraph, x=w, y=h, scale_x=r.pixel_aspect_x, scale_y=r.pixel_aspect_y))
    # The depth rows exactly, from the clip distances (float32 loses the far plane at a
    # near/far ratio beyond ~1e7); the view ignores the camera's scale, as Blender's does.
    n, f = float(cam.data.clip_start), float(cam.data.clip_end)
    if cam.data.type == "ORTHO":
        proj[2, 2], proj[2, 3] = -2.0 / (f - n), -(f + n) / (f - n)
    else:
        proj[2, 2], proj[2, 3] = -(f + n) / (f - n), -2.0 * f * n / (f - n)
    view = np.array(cam.matrix_world.normalized().inverted())
    return view, proj, w, h


def plane_hits(view, proj, w, h, z=0.0, axis=2):
    """World point where each pixel centre's ray meets the plane {p[axis] = z}, and its view
    depth. Arrays are (h, w[, 3]) with row 0 at the bottom of the image."""
    # A pixel's ray does not depend on the clip distances: unproject through a well-conditioned
    # depth row (near 1, far 2), not one whose near/far ratio is 1e8.
    proj = np.array(proj, dtype=np.float64)
    proj[2, 2], proj[2, 3] = (-3.0, -4.0) if proj[3, 3] == 0.0 else (-2.0, -3.0)
    inv = np.linalg.inv(proj @ view)
    xs = (np.arange(w) + 0.5) / w * 2 - 1
    ys = (np.arange(h) + 0.5) / h * 2 - 1
    X, Y = np.meshgrid(xs, ys)

    def unproject(zn):
        p = np.stack([X, Y, np.full_like(X, zn), np.ones_like(X)], axis=-1) @ inv.T
        return p[..., :3] / p[..., 3:4]

    o = unproject(-1.0)
    d = unproject(1.0) - o
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (z - o[..., axis]) / d[..., axis]
    p = o + t[..., None] * d
    depth = -(p @ view[:3, :3].T + view[:3, 3])[..., 2]
    return p, depth


def ray_hits_box(origins, direction, lo, hi):
    """Whether rays ``origins + s * direction`` (s > 0) hit the box [lo, hi] (slab test)."""
    o = np.asarray(origins, float)
    d = np.asarray(direction, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t1 = (np.asarray(lo) - o) * inv
        t2 = (np.asarray(hi) - o) * inv
    tmin = np.nanmax(np.minimum(t1, t2), axis=-1)
    tmax = np.nanmin(np.maximum(t1, t2), axis=-1)
    return (tmax >= np.maximum(tmin, 0.0)) & (tmax > 0)


def iou(a, b):
    a = np.asarray(a, bool)
    b = np.asarray(b, bool)
    union = (a | b).sum()
    return float((a & b).sum() / union) if union else 1.0


# Blender's Principled BSDF (Cycles), dielectric: GGX with height-correlated Smith masking-
# shadowing, the exact dielectric Fresnel, multiple scattering as microfacet_ggx_preserve_energy
# adds it and the diffuse weighted by 1 - the specular's albedo (closure_layering_weight).


def fresnel_dielectric(c, eta=1.5):
    c = np.abs(c)
    g = np.sqrt(np.maximum(eta * eta - 1.0 + c * c, 0.0))
    a = (g - c) / (g + c)
    b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
    return 0.5 * a * a * (1.0 + b * b)


def fresnel_shape(c, eta=1.5):
    """s: the real Fresnel remapped from F0 to 1 (0 at normal incidence, 1 at grazing)."""
    f0 = ((eta - 1.0) / (eta + 1.0)) ** 2
    return (fresnel_dielectric(c, eta) - f0) / (1.0 - f0)


def smith_lambda(a2, mu):
    return 0.5 * (np.sqrt(1.0 + a2 * np.maximum(1.0 / (mu * mu) - 1.0, 0.0)) - 1.0)


def ggx_albedo(rough, mu, fresnel, n_theta=1024, n_phi=256):
    """int f(v, l) cos(l) dl of the GGX lobe with Fresnel ``fresnel(h.v)`` at N.V = ``mu``."""
    a = max(rough * rough, 1e-3)
    a2 = a * a
    u1 = (np.arange(n_theta) + 0.5) / n_theta
    u2 = (np.arange(n_phi) + 0.5) / n_phi
    U1, U2 = np.meshgrid(u1, u2, indexing="ij")
    theta = np.arctan(a * np.sqrt(U1 / (1.0 - U1)))
    phi = 2.0 * np.pi * U2
    h = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    v = np.array([np.sqrt(1.0 - mu * mu), 0.0, mu])
    hv = h @ v
    mul = (2.0 * hv[..., None] * h - v)[..., 2]
    ok = (mul > 0.0) & (hv > 0.0)
    g2 = 1.0 / (1.0 + smith_lambda(a2, mu) + smith_lambda(a2, np.maximum(mul, 1e-9)))
    # f cos(l) dl = F D G2 (h.v) / mu dh; the samples' density is D cos(h).
    return float(np.where(ok, fresnel(hv) * g2 * hv / (mu * h[..., 2]), 0.0).mean())


def principled_dielectric(base, rough, v, to_light, ior=1.5):
    """(diffuse, specular) reflectance f cos(theta_l) of Blender's Principled BSDF (metallic 0,
    Specular IOR Level 0.5, so F0 = F0(ior)) for unit view ``v`` and light ``to_light`` directions about
    the normal +z, as Cycles evaluates it."""
    v, w = np.asarray(v, float), np.asarray(to_light, float)
    mu_v, mu_l = v[2], w[2]
    if mu_l <= 0.0:
        return 0.0, 0.0
    a2 = max(rough * rough, 1e-3) ** 2
    ms = _multiple_scattering(rough, mu_v, ior)
    albedo = ggx_albedo(rough, mu_v, lambda c: fresnel_dielectric(c, ior)) * ms
    h = (v + w) / np.linalg.norm(v + w)
    d = a2 / (np.pi * (h[2] ** 2 * (a2 - 1.0) + 1.0) ** 2)
    g2 = 1.0 / (1.0 + smith_lambda(a2, mu_v) + smith_lambda(a2, mu_l))
    spec = fresnel_dielectric(np.dot(h, w), ior) * d * g2 / (4.0 * mu_v * mu_l) * ms
    return float((1.0 - albedo) * base / np.pi * mu_l), float(spec * mu_l)


def principled_dielectric_albedo(base, rough, mu_v, ior=1.5):
    """What the Principled dielectric reflects of a uniform world of radiance 1 seen at N.V =
    ``mu_v``: its diffuse (1 - A) base plus its specular's albedo A (multiple scattering in)."""
    albedo = ggx_albedo(rough, mu_v, lambda c: fresnel_dielectric(c, ior)) * _multiple_scattering(rough, mu_v, ior)
    return float((1.0 - albedo) * base + albedo)


def coat_albedo(rough, mu_v, ior=1.5):
    """What a Principled coat (a dielectric GGX of ``rough`` and ``ior``) reflects of a uniform
    world at N.V = ``mu_v``, multiple scattering in (as Cycles' coat closure)."""
    return ggx_albedo(rough, mu_v, lambda c: fresnel_dielectric(c, ior)) * _multiple_scattering(rough, mu_v, ior)


def coat_below(weight, rough, mu_v, ior=1.5, tint=(1.0, 1.0, 1.0)):
    """What reaches the layers under a Principled coat and back, per channel: 1 - weight x its
    albedo towards the viewer (closure_layering_weight), times mix(1, tint^(1 / cos_t), weight)
    with cos_t the view refracted into the coat (Cycles' coat tint)."""
    cos_t = math.sqrt(max(1.0 - (1.0 - mu_v * mu_v) / (ior * ior), 1e-8))
    through = np.power(np.clip(np.asarray(tint, float), 1e-6, 1.0), 1.0 / cos_t)
    return (1.0 - weight * coat_albedo(rough, mu_v, ior)) * ((1.0 - weight) + weight * through)


def coat_reflectance(weight, rough, v, to_light, ior=1.5):
    """f cos(theta_l) of a Principled coat alone for unit ``v`` and ``to_light`` about +z: GGX,
    height-correlated Smith, the exact dielectric Fresnel of ``ior``, times ``weight``."""
    return float(weight * ggx_reflectance(lambda c: fresnel_dielectric(c, ior), rough, v, to_light))


# Rec. 709 (Blender's scene linear) from CIE XYZ.
XYZ_TO_REC709 = np.array(
    [[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560], [0.0556434, -0.2040259, 1.0572252]]
)
FILM_WAVELENGTHS = np.linspace(360.0, 830.0, 1881)  # nm, every 0.25 nm


def _lobe(x, mu, s1, s2):
    return np.exp(-0.5 * ((x - mu) / np.where(x < mu, s1, s2)) ** 2)


def cie_cmf(lam):
    """The CIE 1931 2-degree colour matching functions at wavelengths ``lam`` (nm), as Wyman,
    Sloan and Shirley's multi-lobe fit ("Simple Analytic Approximations to the CIE XYZ Color
    Matching Functions", JCGT 2013): (n, 3) XYZ."""
    lam = np.asarray(lam, float)
    x = (
        1.056 * _lobe(lam, 599.8, 37.9, 31.0)
        + 0.362 * _lobe(lam, 442.0, 16.0, 26.7)
        - 0.065 * _lobe(lam, 501.1, 20.4, 26.2)
    )
    y = 0.821 * _lobe(lam, 568.8, 46.9, 40.5) + 0.286 * _lobe(lam, 530.9, 16.3, 31.1)
    z = 1.217 * _lobe(lam, 437.0, 11.8, 36.0) + 0.681 * _lobe(lam, 459.0, 26.0, 13.8)
    return np.stack([x, y, z], axis=-1)


def film_rgb_weights():
    """(wavelengths, (n, 3) Rec. 709 weights per wavelength whose columns each sum to 1): what
    a spectral reflectance is integrated against to give linear RGB, white-balanced so a flat
    spectrum is white (the equal-energy white)."""
    rgb = cie_cmf(FILM_WAVELENGTHS) @ XYZ_TO_REC709.T
    return FILM_WAVELENGTHS, rgb / rgb.sum(axis=0)


def _amplitudes(c, n1, n2):
    """The s- and p-polarised reflection amplitudes (complex) from index n1 to n2 (n2 may be
    complex: a conductor n + i k) at cosine ``c``, and the cosine in n2."""
    s2 = 1.0 - c * c
    c2 = np.sqrt(complex(1.0 - (n1 / n2) ** 2 * s2))
    rs = (n1 * c - n2 * c2) / (n1 * c + n2 * c2)
    rp = (n2 * c - n1 * c2) / (n2 * c + n1 * c2)
    return rs, rp, c2


def _film_spectral(c, thickness, film_ior, r23_of):
    """The film's reflectance in linear Rec. 709: the exact Airy reflectance at each wavelength
    (both polarisations averaged) integrated against the colour matching functions.
    ``r23_of(c2, eta2)`` gives the film-to-base amplitudes (s, p) at the film's cosine."""
    c = min(max(c, 1e-4), 1.0)
    d = max(thickness, 0.0)
    t = min(max(d, 0.0), 1.0)
    eta2 = 1.0 + (max(film_ior, 1.0) - 1.0) * t * t * (3.0 - 2.0 * t)  # below 1 nm, no film
    rs12, rp12, c2 = _amplitudes(c, 1.0, eta2)
    c2 = float(np.real(c2))
    lam, weights = film_rgb_weights()
    phase = np.exp(1j * 4.0 * math.pi * eta2 * d * c2 / lam)
    reflectance = 0.0
    for r12, r23 in zip((rs12, rp12), r23_of(c2, eta2), strict=True):
        r = (r12 + r23 * phase) / (1.0 + r12 * r23 * phase)
        reflectance = reflectance + 0.5 * np.abs(r) ** 2
    return np.clip(reflectance @ weights, 0.0, 1.0)


def thin_film_fresnel(c, thickness, film_ior, base_ior):
    """The reflectance (linear Rec. 709) of a thin dielectric film of ``thickness`` nm and
    ``film_ior`` on a dielectric of ``base_ior``, from air at cosine ``c``: the Airy reflectance
    integrated over the spectrum (what Belcour and Barla's Fourier-space sum approximates)."""

    def r23(c2, eta2):
        rs, rp, _ = _amplitudes(c2, eta2, max(base_ior, 1.0))
        return rs, rp

    return _film_spectral(c, thickness, film_ior, r23)


def ggx_reflectance(fresnel, rough, v, to_light):
    """f cos(theta_l) of a GGX lobe (height-correlated Smith) whose Fresnel at the half vector
    is ``fresnel(cos)`` (a scalar or RGB), for unit ``v`` and ``to_light`` about +z."""
    v, w = np.asarray(v, float), np.asarray(to_light, float)
    mu_v, mu_l = v[2], w[2]
    if mu_l <= 0.0:
        return 0.0
    a2 = max(rough * rough, 1e-3) ** 2
    h = (v + w) / np.linalg.norm(v + w)
    d = a2 / (np.pi * (h[2] ** 2 * (a2 - 1.0) + 1.0) ** 2)
    g2 = 1.0 / (1.0 + smith_lambda(a2, mu_v) + smith_lambda(a2, mu_l))
    return np.asarray(fresnel(float(np.dot(h, w)))) * d * g2 / (4.0 * mu_v)


_SHEEN_TABLE = []


def sheen_table():
    """The sheen's LTC table as the lit pass reads it (shaders/lib/sheen_ltc.glsl, written by
    tools/make_sheen_table.py): (N, N, 3) of (a, b, R) by [roughness, N.V] nodes."""
    if not _SHEEN_TABLE:
        import re
        from pathlib import Path

        text = (Path(__file__).resolve().parent.parent / "shaders" / "lib" / "sheen_ltc.glsl").read_text()
        body = text[text.index("SHEEN_LTC[") :]
        values = np.array(re.findall(r"vec3\(([-\d.e]+), ([-\d.e]+), ([-\d.e]+)\)", body), float)
        n = math.isqrt(len(values))
        _SHEEN_TABLE.append(values.reshape(n, n, 3))
    return _SHEEN_TABLE[0]


def sheen_ltc(rough, mu):
    """(a, b, R) at Sheen Roughness ``rough`` and N.V ``mu``, bilinear between the nodes (with
    the lobe left empty where the transform or R vanish), as lib/sheen.glsl reads them."""
    table = sheen_table()
    n = table.shape[0]
    p = np.array([min(max(rough, 1e-3), 1.0), min(max(mu, 0.0), 1.0)]) * (n - 1)
    i = np.minimum(p.astype(int), n - 2)
    f = p - i
    lo = table[i[0], i[1]] * (1 - f[1]) + table[i[0], i[1] + 1] * f[1]
    hi = table[i[0] + 1, i[1]] * (1 - f[1]) + table[i[0] + 1, i[1] + 1] * f[1]
    out = lo * (1 - f[0]) + hi * f[0]
    return np.zeros(3) if abs(out[0]) < 1e-5 or out[2] < 1e-5 else out


def sheen_lobe(a, b, local):
    """D(w) of the sheen's transformed cosine at local directions ``local`` (..., 3), x the view
    projected on the surface, z the normal: it integrates to 1 over the hemisphere."""
    x, y, z = local[..., 0], local[..., 1], local[..., 2]
    len2 = (a * x + b * z) ** 2 + (a * y) ** 2 + z * z
    return np.where(z > 0.0, z / np.pi * (a / np.maximum(len2, 1e-300)) ** 2, 0.0)


def sheen_reflectance(rough, v, to_light):
    """f cos(theta_l) of Blender's microfiber sheen (weight 1, white) for unit ``v`` and
    ``to_light`` about +z: R D in the frame whose x axis is v on the surface."""
    v, w = np.asarray(v, float), np.asarray(to_light, float)
    a, b, r = sheen_ltc(rough, v[2])
    t = v - np.array([0.0, 0.0, v[2]])
    t = t / np.linalg.norm(t) if np.linalg.norm(t) > 1e-9 else np.array([1.0, 0.0, 0.0])
    bt = np.cross([0.0, 0.0, 1.0], t)
    return r * float(sheen_lobe(a, b, np.array([w @ t, w @ bt, w[2]])))


def ggx_aniso_reflectance(fresnel, ax, ay, v, to_light):
    """f cos(theta_l) of an anisotropic GGX lobe (height-correlated Smith) of roughness ``ax``
    along +x and ``ay`` along +y, whose Fresnel at the half vector is ``fresnel(cos)``, for unit
    ``v`` and ``to_light`` about +z."""
    v, w = np.asarray(v, float), np.asarray(to_light, float)
    if w[2] <= 0.0:
        return 0.0
    h = (v + w) / np.linalg.norm(v + w)
    d = 1.0 / (np.pi * ax * ay * ((h[0] / ax) ** 2 + (h[1] / ay) ** 2 + h[2] ** 2) ** 2)

    def lam(u):
        return 0.5 * (math.sqrt(1.0 + ((ax * u[0]) ** 2 + (ay * u[1]) ** 2) / u[2] ** 2) - 1.0)

    g2 = 1.0 / (1.0 + lam(v) + lam(w))
    return np.asarray(fresnel(float(np.dot(h, w)))) * d * g2 / (4.0 * v[2])


def ggx_aniso_albedo(ax, ay, v, n=512):
    """The directional albedo (Fresnel 1, single scattering) of an anisotropic GGX lobe of
    roughness ``ax`` along +x and ``ay`` along +y seen from unit ``v`` about +z: half vectors
    drawn from D(h) (n.h) on an n x n midpoint grid, each reflection weighted by f cos / pdf =
    G2 (v.h) / (n.v n.h) (0 below the surface)."""
    v = np.asarray(v, float)
    u1, u2 = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n, indexing="ij")
    phi = np.arctan(ay / ax * np.tan(2.0 * np.pi * u2))
    phi = np.where((u2 > 0.25) & (u2 <= 0.75), phi + np.pi, phi)
    phi = np.where(u2 > 0.75, phi + 2.0 * np.pi, phi)
    a2 = 1.0 / ((np.cos(phi) / ax) ** 2 + (np.sin(phi) / ay) ** 2)
    tan2 = a2 * u1 / (1.0 - u1)
    cos_t = 1.0 / np.sqrt(1.0 + tan2)
    sin_t = np.sqrt(np.maximum(1.0 - cos_t**2, 0.0))
    h = np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], -1)
    vh = h @ v
    w = 2.0 * vh[..., None] * h - v
    ok = (w[..., 2] > 0.0) & (vh > 0.0)

    def lam(d):
        z = np.maximum(d[..., 2], 1e-9)
        return 0.5 * (np.sqrt(1.0 + ((ax * d[..., 0]) ** 2 + (ay * d[..., 1]) ** 2) / z**2) - 1.0)

    g2 = 1.0 / (1.0 + lam(v[None, None]) + lam(w))
    return float(np.where(ok, g2 * vh / (v[2] * h[..., 2]), 0.0).mean())


def ggx_ms_gain(f, f90, rough, mu_v):
    """The lit pass's multiple-scattering gain of a GGX lobe of mean reflectance ``f`` and rim
    ``f90`` (lib/lit_bsdf.glsl ggx_ms_gain): 1 + F_ms (1 - E) / E, F_ss from the IOR-1.5 Fresnel
    curve's cosine-weighted mean, as Cycles' microfacet_ggx_preserve_energy."""
    one = np.ones_like
    e = ggx_albedo(rough, mu_v, one)
    mus = (np.arange(64) + 0.5) / 64
    e_avg = 2.0 * np.mean([ggx_albedo(rough, m, one, 256, 64) * m for m in mus])
    s_avg = 2.0 * np.mean(fresnel_shape(mus) * mus)
    f_ss = min(max(f + (1.0 - f) * s_avg * f90, 0.0), 1.0)
    f_ms = f_ss * e_avg / (1.0 - f_ss * (1.0 - e_avg))
    return 1.0 + f_ms * (1.0 - e) / e


def _multiple_scattering(rough, mu_v, ior):
    """Cycles' energy gain of the GGX lobe for light bouncing between microfacets at N.V =
    ``mu_v``: 1 + F_ms (1 - E) / E (Kulla and Conty 2017; microfacet_ggx_preserve_energy)."""
    one = np.ones_like
    e = ggx_albedo(rough, mu_v, one)
    mus = (np.arange(64) + 0.5) / 64
    e_avg = 2.0 * np.mean([ggx_albedo(rough, m, one, 256, 64) * m for m in mus])
    f_ss = 2.0 * np.mean(fresnel_dielectric(mus, ior) * mus)
    f_ms = f_ss * e_avg / (1.0 - f_ss * (1.0 - e_avg))
    return 1.0 + f_ms * (1.0 - e) / e


def erode(mask, n=1):
    """``mask`` (a boolean image) shrunk by ``n`` pixels: a pixel stays where it and its four
    neighbours do (the inside of an outline, away from its edge pixels)."""
    out = mask.copy()
    for _ in range(n):
        inner = out.copy()
        inner[1:] &= out[:-1]
        inner[:-1] &= out[1:]
        inner[:, 1:] &= out[:, :-1]
        inner[:, :-1] &= out[:, 1:]
        out = inner
    return out


# Burley's normalized diffusion (Christensen and Burley 2015), as Cycles draws it and
# shaders/lib/burley.glsl evaluates it: d per channel, truncated at BURLEY_TRUNCATE d.
BURLEY_TRUNCATE = 16.0
BURLEY_TRUNCATE_CDF = 0.9963790093708328


def burley_distance(radius, scale):
    """Burley's d of a subsurface Radius x Scale (Cycles' r / 4 pi: node_sss_distance)."""
    return np.maximum(np.asarray(radius, np.float64), 0.0) * max(float(scale), 0.0) * 0.25 / math.pi


def burley_radial(d, r):
    """R(r) 2 pi r: the density of the radius ``r`` (burley_radial in lib/burley.glsl)."""
    r = np.asarray(r, np.float64)
    e3 = np.exp(-r / (3.0 * d))
    return np.where(r < BURLEY_TRUNCATE * d, (e3**3 + e3) / (4.0 * d), 0.0)


def burley_cdf(d, r):
    """The share of the profile within ``r``: 1 - exp(-r/d) / 4 - 3 exp(-r/3d) / 4."""
    x = np.asarray(r, np.float64) / d
    return 1.0 - 0.25 * np.exp(-x) - 0.75 * np.exp(-x / 3.0)


def burley_through(d, s):
    """The share leaving a slab ``s`` thick on its far face: R over the plane at that depth
    (burley_through in lib/burley.glsl)."""
    e3 = np.exp(-np.asarray(s, np.float64) / (3.0 * d))
    return 0.25 * (e3**3 + 3.0 * e3)


def burley_edge(d, x, n=4096):
    """The light a point ``x`` from the edge of a lit half-plane receives of it (x > 0 on the
    dark side, < 0 on the lit side) over Burley's truncated, renormalised profile: the profile's
    share beyond the line at distance |x| (by the radial density and the arc beyond it)."""
    x = np.atleast_1d(np.asarray(x, np.float64))
    rm = BURLEY_TRUNCATE * d
    r = (np.arange(n) + 0.5) / n * rm
    w = burley_radial(d, r) * (rm / n) / BURLEY_TRUNCATE_CDF
    a = np.abs(x)[:, None]
    beyond = np.where(r[None, :] > a, np.arccos(np.clip(a / r[None, :], -1.0, 1.0)) / math.pi, 0.0)
    share = (w[None, :] * beyond).sum(axis=1)
    return np.where(x > 0.0, share, 1.0 - share)


def f82_tint_b(f0, tint):
    """Cycles' F82-tint metal: the b of F = Schlick(f0) - b cos (1 - cos)^6 that makes the value
    at cos 1/7 (82 degrees) Schlick's times ``tint`` (Kutz et al., Adobe Standard Material)."""
    f = 6.0 / 7.0
    schlick = np.asarray(f0) + (1.0 - np.asarray(f0)) * f**5
    return schlick * (7.0 / f**6) * (1.0 - np.asarray(tint))


def f82_b(f0, f82):
    """The b of the F82 model whose value at cos 1/7 is ``f82``."""
    f = 6.0 / 7.0
    schlick = np.asarray(f0) + (1.0 - np.asarray(f0)) * f**5
    return (7.0 / f**6) * (schlick - np.asarray(f82))


def f82_fresnel(c, f0, b):
    """The F82 model's reflectance at cosine ``c``."""
    s = min(max(1.0 - c, 0.0), 1.0)
    return np.clip(np.asarray(f0) + (1.0 - np.asarray(f0)) * s**5 - np.asarray(b) * c * s**6, 0.0, 1.0)


def gulbrandsen_ior(f0, f82):
    """A metal's complex index (n, k) per channel from its reflectance at normal incidence
    ``f0`` and at 82 degrees ``f82`` read as Gulbrandsen's reflectivity and edge tint
    ("Artist Friendly Metallic Fresnel", JCGT 2014), as Cycles films its metals."""
    r = np.minimum(np.asarray(f0, float), 0.999)
    sr = np.sqrt(r)
    g = np.asarray(f82, float)
    n = (1.0 + sr) / (1.0 - sr) * (1.0 - g) + (1.0 - r) / (1.0 + r) * g
    k = np.sqrt(np.maximum((r * (n + 1.0) ** 2 - (n - 1.0) ** 2) / (1.0 - r), 0.0))
    return n, k


def thin_film_conductor(c, thickness, film_ior, f0, tint=(1.0, 1.0, 1.0)):
    """The reflectance (linear Rec. 709) of a thin dielectric film on a metal of F82-tint
    ``f0`` and ``tint``, as Cycles films its Principled metal: the metal's n and k from F0 and
    its value at 82 degrees (gulbrandsen_ior); under the film its reflectance is the F82 model's
    at the film's index and its phase the complex Fresnel's; the Airy reflectance per channel,
    integrated over the spectrum."""
    f0 = np.clip(np.asarray(f0, float), 0.0, 1.0)
    g = f82_fresnel(1.0 / 7.0, f0, f82_tint_b(f0, tint))
    n, k = gulbrandsen_ior(f0, g)
    out = np.zeros(3)
    for ch in range(3):

        def r23(c2, eta2, ch=ch):
            nc = complex(n[ch], k[ch])
            rs, rp, _ = _amplitudes(c2, eta2, nc)
            rel = nc / eta2
            film_f0 = abs((rel - 1.0) / (rel + 1.0)) ** 2
            size = math.sqrt(float(f82_fresnel(c2, film_f0, f82_b(film_f0, g[ch]))))
            return size * rs / abs(rs), size * rp / abs(rp)

        out[ch] = _film_spectral(c, thickness, film_ior, r23)[ch]
    return out
