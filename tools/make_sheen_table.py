"""Writes shaders/lib/sheen_ltc.glsl: the Principled BSDF's sheen lobe as a table of linearly
transformed cosines, measured from Blender's Cycles.

    .venv/blender-5.2/bin/python -m tools.make_sheen_table [--quick]

Blender's sheen (the Principled BSDF's Sheen, the Sheen BSDF's Microfiber) is Zeltner, Burley
and Chiang's "Practical Multiple-Scattering Sheen Using Linearly Transformed Cosines" (2022): for
a view at cos(theta) = mu from the normal and Sheen Roughness r, the lobe times the cosine is

    f cos = R(mu, r) D(w),   D(w) = z / pi (a / |(a x + b z, a y, z)|^2)^2

in the frame whose x axis is the view projected on the surface (w = (x, y, z), z along the
normal): a clamped cosine linearly transformed by the inverse of [[a, 0, b], [0, a, 0], [0, 0, 1]]
(Heitz et al. 2016), which keeps z's sign, so D integrates to 1 over the hemisphere and R is the
lobe's directional albedo. The paper fits a, b and R to a volumetric layer of fiber-like
microflakes per (mu, r) on a 32 x 32 grid (mu and r each from 0 to 1), read bilinearly.

Those values are measured here from Cycles itself rather than copied: a row of spheres, one per
roughness of the grid, each a white Sheen BSDF, seen from above by an orthographic camera (the
view +z everywhere) and lit by a sun of irradiance 1 from several directions in the xz plane. A
pixel's Combined is then R D(w) at its normal (the Normal pass), one exact evaluation of the lobe
(a sun is sampled exactly; direct light only; spheres that cast no shadow). For each roughness
and each node mu_j of the grid, the pixels with mu within a fifth of a cell of it give a, b (a search
on a grid in log a and b, refined twice) and R (least squares at each a, b, within [0, 1]). The
nodes at mu 0, which no pixel sees, take the next node's values; where R is below 1e-2 the
shape (a, b) is the nearest well-measured node's; where R (or a) is below 1e-5 the lobe is
empty, as in Cycles.

The renders are cached under out/reference_cache by Blender's version; ``--quick`` renders 64
pixels a sphere (a check of the tool), the table 192.
"""

import argparse
import math
import os
import sys
import tempfile
from pathlib import Path

import bpy
import numpy as np

from devkit import scenes
from devkit.engines import configure
from devkit.imageio import read_exr, set_format
from devkit.render import cached_image

N = 32  # the grid: mu_j = j / (N - 1), r_k = k / (N - 1)
COLS = 8
SPACING = 2.2
BIN = 0.2  # the pixels within 0.2 of a cell of a node fit it (the lobe changes within a cell)
SUN_DEGREES = (0.0, 25.0, 50.0, 75.0, 100.0, 125.0, 150.0, 170.0)
OUT = Path(__file__).resolve().parent.parent / "shaders" / "lib" / "sheen_ltc.glsl"


def roughness(k):
    return k / (N - 1)


def _scene(pixels, sun_degrees):
    rows = N // COLS
    width, height = COLS * pixels, rows * pixels
    scene = scenes.empty_scene(int(width * SPACING / 2.0), int(height * SPACING / 2.0), engine="CYCLES")
    configure(scene, "CYCLES", samples=1)
    scene.view_layers[0].use_pass_normal = True
    scene.render.film_transparent = True
    for k in range(N):
        mat = bpy.data.materials.new(f"Sheen {k}")
        mat.use_nodes = True
        tree = mat.node_tree
        tree.nodes.clear()
        sheen = tree.nodes.new("ShaderNodeBsdfSheen")
        sheen.distribution = "MICROFIBER"
        sheen.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        sheen.inputs["Roughness"].default_value = roughness(k)
        out = tree.nodes.new("ShaderNodeOutputMaterial")
        tree.links.new(sheen.outputs[0], out.inputs["Surface"])
        col, row = k % COLS, k // COLS
        centre = ((col - (COLS - 1) / 2.0) * SPACING, (row - (rows - 1) / 2.0) * SPACING, 0.0)
        ob = scenes.uv_sphere(scene, f"Sphere {k}", center=centre, segments=192, rings=96, mat=mat)
        ob.visible_shadow = False
    scenes.camera(scene, (0.0, 0.0, 10.0), (0.0, 0.0, 0.0), ortho_scale=COLS * SPACING, clip=(0.1, 20.0))
    t = math.radians(sun_degrees)
    # A sun shines along its local -z: rotated about y by theta, it comes from (sin t, 0, cos t).
    scenes.light(scene, "Sun", "SUN", 1.0, rotation=(0.0, t, 0.0), angle=0.0)
    return scene


def _render(pixels, sun_degrees):
    """(value, normal x, normal y, normal z, alpha) per pixel for the sun at ``sun_degrees``."""

    def make():
        scene = _scene(pixels, sun_degrees)
        set_format(scene.render.image_settings, "OPEN_EXR_MULTILAYER", color_depth="32", exr_codec="ZIP")
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "frame.exr")
            scene.render.filepath = path
            scene.render.use_file_extension = False
            bpy.ops.render.render(write_still=True)
            data = read_exr(path)
        combined, normal = data["Combined"], data["Normal"]
        return np.concatenate([combined[..., :1], normal[..., :3], combined[..., 3:4]], axis=-1).astype(np.float32)

    return cached_image("sheen", __file__, f"{pixels}-{sun_degrees}", make)


def ltc(a, b, local):
    """D(w) for LTC coefficients a, b (broadcast) at local directions ``local`` (..., 3)."""
    x, y, z = local[..., 0], local[..., 1], local[..., 2]
    len2 = (a * x + b * z) ** 2 + (a * y) ** 2 + z * z
    return np.where(z > 0.0, z / np.pi * (a / len2) ** 2, 0.0)


def local_frame(normal, view, light):
    """``light`` in the frame (T, B, N) of each normal, T the view projected on its plane."""
    mu = normal @ view
    t = view[None, :] - normal * mu[:, None]
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12)
    b = np.cross(normal, t)
    return mu, np.stack([t @ light, b @ light, normal @ light], axis=1)


def samples(pixels):
    """Every roughness's (mu, local light direction, value) over all suns."""
    view = np.array([0.0, 0.0, 1.0])
    out = {k: [] for k in range(N)}
    rows = N // COLS
    for deg in SUN_DEGREES:
        image = _render(pixels, deg)
        h, w = image.shape[:2]
        t = math.radians(deg)
        light = np.array([math.sin(t), 0.0, math.cos(t)])
        for k in range(N):
            col, row = k % COLS, k // COLS
            # Image rows run from the top of the frame: sphere row ``row`` (y up) is rows - 1 - row.
            cy, cx = (rows - 1 - row + 0.5) * h / rows, (col + 0.5) * w / COLS
            half = pixels // 2 + 2
            tile = image[int(cy) - half : int(cy) + half, int(cx) - half : int(cx) + half].reshape(-1, 5)
            keep = tile[:, 4] > 0.999
            n = tile[keep, 1:4].astype(np.float64)
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
            mu, local = local_frame(n, view, light)
            # Away from the terminator, where a smooth mesh's shading and geometric normals part.
            ok = (local[:, 2] > 0.05) & (mu > 0.0)
            out[k].append(np.concatenate([mu[ok, None], local[ok], tile[keep][ok, :1].astype(np.float64)], axis=1))
    return {k: np.concatenate(v) for k, v in out.items()}


def fit(data):
    """(a, b, R) of the LTC closest to ``data`` rows (mu, x, y, z, value) in least squares."""
    local, value = data[:, 1:4], data[:, 4]

    def best(log_a, bs):
        la, bb = np.meshgrid(log_a, bs, indexing="ij")
        a = np.exp(la)[..., None]
        d = ltc(a, bb[..., None], local[None, None])
        # R is an albedo: within [0, 1].
        scale = np.clip((d * value).sum(-1) / np.maximum((d * d).sum(-1), 1e-30), 0.0, 1.0)
        err = ((scale[..., None] * d - value) ** 2).sum(-1)
        i, j = np.unravel_index(np.argmin(err), err.shape)
        return la[i, j], bb[i, j], scale[i, j], err[i, j]

    la, b, r, err = best(np.linspace(np.log(1e-3), np.log(20.0), 48), np.linspace(-4.0, 4.0, 49))
    for width in (0.3, 0.03):
        la, b, r, err = best(
            np.linspace(la - width * 3, la + width * 3, 25), np.linspace(b - width * 2, b + width * 2, 25)
        )
    residual = math.sqrt(err / max((value * value).sum(), 1e-30))  # relative RMS
    return (float(np.exp(la)), float(b), float(r)), residual


def table(pixels):
    data = samples(pixels)
    out = np.zeros((N, N, 3))  # [r, mu] -> (a, b, R)
    residual = np.zeros((N, N))
    for k in range(N):
        rows = data[k]
        for j in range(N):
            mu = j / (N - 1)
            near = rows[np.abs(rows[:, 0] - mu) <= BIN / (N - 1)]
            if len(near) < 32:
                continue
            if len(near) > 4000:  # an even subset: the fit's cost, not its accuracy
                near = near[:: len(near) // 4000 + 1]
            out[k, j], residual[k, j] = fit(near)
        filled = np.flatnonzero(out[k, :, 2] > 0.0)
        for j in range(N):  # a node no pixel sees (mu 0): the nearest one's
            if out[k, j, 2] == 0.0 and len(filled):
                out[k, j] = out[k, filled[np.argmin(np.abs(filled - j))]]
        worst = residual[k].max()
        print(f"make_sheen_table: r {roughness(k):.3f}: worst relative RMS {worst:.4f}", file=sys.stderr, flush=True)
    out[(out[..., 2] < 1e-5) | (np.abs(out[..., 0]) < 1e-5)] = 0.0
    return out


def tidy(values, floor=1e-2):
    """Where a node's R is below ``floor`` the lobe reflects too little for its shape to be
    measured: its a and b are the nearest well-measured node's of the same roughness (so the
    bilinear read between nodes never blends a measured shape with noise)."""
    out = values.copy()
    for k in range(N):
        good = np.flatnonzero(values[k, :, 2] >= floor)
        if len(good) == 0:
            continue
        for j in range(N):
            if values[k, j, 2] < floor:
                out[k, j, :2] = values[k, good[np.argmin(np.abs(good - j))], :2]
    return out


def glsl(values):
    rows = ",\n".join("  " + ", ".join(f"vec3({a:.5f}, {b:.5f}, {r:.5f})" for a, b, r in values[k]) for k in range(N))
    return f"""// requires:
#ifndef PENUMBRA_LIB_SHEEN_LTC
#define PENUMBRA_LIB_SHEEN_LTC

/* The Principled BSDF's sheen as linearly transformed cosines (Zeltner, Burley and Chiang 2022),
 * measured from Cycles (generated by tools/make_sheen_table.py; do not edit):
 * SHEEN_LTC[r * {N} + m] = (a, b, R) at Sheen Roughness r / {N - 1} and N.V = m / {N - 1}. The
 * lobe times the cosine is R z / pi (a / |(a x + b z, a y, z)|^2)^2 in the frame whose x axis
 * is the view projected on the surface; R is its directional albedo. */

#ifndef NODE_SHEEN
#  define NODE_SHEEN 0 /* a Principled sheen is drawn (engine/frame/programs.py material_defines) */
#endif

#if NODE_SHEEN /* only variants that draw a sheen carry the table */

const vec3 SHEEN_LTC[{N * N}] = vec3[{N * N}](
{rows});

/* (a, b, R) at Sheen Roughness ``rough`` and ``NdotV``, bilinear in both. */
vec3 sheen_ltc(float rough, float NdotV)
{{
  vec2 p = vec2(clamp(rough, 1e-3, 1.0), clamp(NdotV, 0.0, 1.0)) * {N - 1}.0;
  ivec2 i = min(ivec2(p), ivec2({N - 2}));
  vec2 f = p - vec2(i);
  int k = i.x * {N} + i.y;
  vec3 lo = mix(SHEEN_LTC[k], SHEEN_LTC[k + 1], f.y);
  vec3 hi = mix(SHEEN_LTC[k + {N}], SHEEN_LTC[k + {N + 1}], f.y);
  return mix(lo, hi, f.x);
}}

#endif

#endif /* PENUMBRA_LIB_SHEEN_LTC */
"""


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="64 pixels a sphere (a check), not 192")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args(argv)
    values = tidy(table(64 if args.quick else 192))
    Path("out").mkdir(exist_ok=True)
    np.save(Path("out") / "sheen_ltc.npy", values)
    args.out.write_text(glsl(values))
    print(f"make_sheen_table: wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
