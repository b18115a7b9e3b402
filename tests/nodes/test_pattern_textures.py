"""Pattern textures (``shaders/nodes/texture_{wave,magic,brick,checker,gradient}.glsl``) against
their numpy twins (``devkit.texture_reference``) on the GPU, and the numpy twins against
Blender's own Cycles, pixel for pixel.

Blender 4.5 wraps the Magic texture's coordinate before applying Scale, Blender 5 after: the
render test picks the wrap of the running line."""

import bpy
import numpy as np

from devkit import texture_reference as ref
from devkit.render import render
from devkit.texture_gpu import evaluate_many
from devkit.texture_tiles import NEAR, TILE, build_tiles, gpu_scene, pixel_points, points, swizzle, tile_errors

HASH = ["texture_hash.glsl"]
NOISE = ["common.glsl", *HASH, "texture_noise.glsl"]  # texture_noise and its requires line
WAVE = NOISE + ["texture_wave.glsl"]
MAGIC = NOISE + ["texture_magic.glsl"]
BRICK = HASH + ["texture_brick.glsl"]
CHECKER = HASH + ["texture_checker.glsl"]
GRADIENT = HASH + ["texture_gradient.glsl"]
MAGIC_WRAP = ref.MAGIC_WRAP_SCALED if bpy.app.version >= (5, 0, 0) else ref.MAGIC_WRAP_UNSCALED

WAVE_CASES = [
    # (type, direction, profile, scale, distortion, detail, detail scale, detail roughness, phase)
    (ref.WAVE_BANDS, ref.WAVE_X, ref.WAVE_SINE, 1.7, 0.0, 2.0, 1.0, 0.5, 0.0),
    (ref.WAVE_BANDS, ref.WAVE_Y, ref.WAVE_SAW, 0.9, 3.0, 2.0, 1.5, 0.5, 0.3),
    (ref.WAVE_BANDS, ref.WAVE_Z, ref.WAVE_TRIANGLE, 1.3, 0.0, 0.0, 1.0, 0.5, -1.0),
    (ref.WAVE_BANDS, ref.WAVE_DIAGONAL, ref.WAVE_SINE, 0.6, 5.0, 3.5, 0.8, 0.7, 2.0),
    (ref.WAVE_RINGS, ref.WAVE_X, ref.WAVE_TRIANGLE, 1.1, 1.5, 1.0, 2.0, 0.4, 0.0),
    (ref.WAVE_RINGS, ref.WAVE_Y, ref.WAVE_SINE, 0.8, 0.0, 2.0, 1.0, 0.5, 0.7),
    (ref.WAVE_RINGS, ref.WAVE_Z, ref.WAVE_SAW, 2.0, 0.5, 6.0, 3.0, 0.6, 0.0),
    (ref.WAVE_RINGS, ref.WAVE_SPHERICAL, ref.WAVE_SINE, 0.5, 8.0, 2.3, 1.2, 0.5, 1.0),
]

MAGIC_CASES = [
    # (scale, distortion, depth)
    (1.7, 1.0, 0),
    (2.3, 1.3, 2),
    (0.7, 2.5, 5),
    (3.1, 0.0, 0),
    (5.0, 1.8, 10),
]

BRICK_CASES = [
    # (color1, color2, mortar, scale, mortar size, mortar smooth, bias, brick width, row height,
    #  offset, offset frequency, squash, squash frequency)
    ((0.8, 0.8, 0.8), (0.2, 0.2, 0.2), (0.0, 0.0, 0.0), 1.7, 0.02, 0.1, 0.0, 0.5, 0.25, 0.5, 2, 1.0, 2),
    ((0.9, 0.3, 0.1), (0.1, 0.4, 0.8), (0.5, 0.5, 0.4), 2.3, 0.05, 0.0, 0.2, 0.7, 0.3, 0.3, 3, 0.6, 2),
    ((0.2, 0.7, 0.3), (0.8, 0.1, 0.6), (1.0, 1.0, 1.0), 0.9, 0.08, 0.8, -0.3, 0.4, 0.2, 0.75, 1, 1.5, 3),
]

CHECKER_CASES = [((0.8, 0.8, 0.8), (0.2, 0.2, 0.2), 1.7), ((0.9, 0.1, 0.3), (0.0, 0.5, 1.0), 0.3)]

GRADIENTS = [
    ref.GRADIENT_LINEAR,
    ref.GRADIENT_QUADRATIC,
    ref.GRADIENT_EASING,
    ref.GRADIENT_DIAGONAL,
    ref.GRADIENT_SPHERICAL,
    ref.GRADIENT_QUADRATIC_SPHERE,
    ref.GRADIENT_RADIAL,
]


def _vec(v):
    return f"vec3({v[0]}, {v[1]}, {v[2]})"


def _glsl_jobs(pts):
    jobs = []
    for kind, direction, profile, scale, dist, detail, dscale, rough, phase in WAVE_CASES:
        args = f"{scale}, {dist}, {detail}, {dscale}, {rough}, {phase}, {kind}, {direction}, {profile}"
        jobs.append((WAVE, f"result = node_tex_wave(a0.xyz, {args});", [pts]))
    for wrap in (ref.MAGIC_WRAP_UNSCALED, ref.MAGIC_WRAP_SCALED):
        for scale, dist, depth in MAGIC_CASES:
            jobs.append((MAGIC, f"result = node_tex_magic(a0.xyz, {scale}, {dist}, {depth}, {wrap});", [pts]))
    for c1, c2, m, scale, size, smooth, bias, width, height, offset, ofreq, squash, sfreq in BRICK_CASES:
        args = f"{_vec(c1)}, {_vec(c2)}, {_vec(m)}, {scale}, {size}, {smooth}, {bias}, {width}, {height}, "
        args += f"{offset}, {ofreq}, {squash}, {sfreq}"
        jobs.append((BRICK, f"result = node_tex_brick(a0.xyz, {args});", [pts]))
    for c1, c2, scale in CHECKER_CASES:
        jobs.append((CHECKER, f"result = node_tex_checker(a0.xyz, {_vec(c1)}, {_vec(c2)}, {scale});", [pts]))
    for kind in GRADIENTS:  # at the points, and at 0.15 times them (spheres have radius 1)
        jobs.append((GRADIENT, f"result = node_tex_gradient(a0.xyz, {kind});", [pts]))
        jobs.append((GRADIENT, f"result = node_tex_gradient(a0.xyz, {kind});", [_near_origin(pts)]))
    return jobs


def _near_origin(pts):
    return (pts * np.float32(0.15)).astype(np.float32)


def _numpy(pts):
    p = pts[:, :3]
    out = []
    for kind, direction, profile, scale, dist, detail, dscale, rough, phase in WAVE_CASES:
        out.append(("wave", ref.node_tex_wave(p, scale, dist, detail, dscale, rough, phase, kind, direction, profile)))
    for wrap in (ref.MAGIC_WRAP_UNSCALED, ref.MAGIC_WRAP_SCALED):
        for scale, dist, depth in MAGIC_CASES:
            out.append(("magic", ref.node_tex_magic(p, scale, dist, depth, wrap)))
    for case in BRICK_CASES:
        out.append(("brick", ref.node_tex_brick(p, *case)))
    for c1, c2, scale in CHECKER_CASES:
        out.append(("checker", ref.node_tex_checker(p, c1, c2, scale)))
    for kind in GRADIENTS:
        out.append(("gradient", ref.node_tex_gradient(p, kind)))
        out.append(("gradient", ref.node_tex_gradient(_near_origin(pts)[:, :3], kind)))
    return out


def test_pattern_glsl_matches_numpy(penumbra, gpu_call):
    gpu_scene()
    pts = points()
    outs = evaluate_many(gpu_call, _glsl_jobs(pts))
    near = np.zeros(len(pts), bool)
    near[NEAR] = True
    depths = [depth for _wrap in range(2) for _s, _d, depth in MAGIC_CASES]
    report = []
    for i, (out, (what, expected)) in enumerate(zip(outs, _numpy(pts))):
        assert np.all(np.isfinite(out)), (what, i)
        err = np.abs(out.astype(np.float64) - expected).max(1)
        report.append(f"{what:9s} {i:2d} within [-10, 10] {err[near].max():.1e}, far {err[~near].max():.1e}")
        if what == "wave":
            # The GPU's sin differs from numpy's by float32 rounding near the origin (measured
            # 1.5e-5). Far out, float32 keeps little of the wave's phase (n's ulp is 0.03 at 3e5,
            # 1 at 1e7) and the GPU reduces sin's argument its own way: any value in [0, 1] is as
            # right as Blender's there.
            assert err[near].max() < 5e-5, (what, i, err[near].max())
            assert np.all((out >= 0.0) & (out <= 1.0)), (what, i)
        elif what == "magic":
            # The GPU's sin and cos differ from numpy's by float32 rounding, more so at 4.5's
            # large arguments (Scale after the wrap: up to 290 here); each level of the chain
            # feeds sin/cos of the last times Distortion, so the rounding compounds. Measured
            # 3.0e-5 at depth 0, 2.2e-4 at depth 5, 3.7e-3 at depth 10: bound 5e-5 * 1.6^depth.
            depth = depths[i - len(WAVE_CASES)]
            assert err.max() < 5e-5 * 1.6**depth, (what, i, depth, err.max())
        elif what == "gradient":
            assert err.max() < 2e-6, (what, i, err.max())  # atan2 and sqrt; the rest is exact
        else:
            # Brick and Checker pick cells: measured bit-exact; a GPU that fused the nudge's
            # multiply-add could move a point lying on a cell edge to the other cell.
            assert np.sum(err > 1e-6) <= 2, (what, i, int(np.sum(err > 1e-6)))
    print("\n".join(report))


# --- against Blender ------------------------------------------------------------------------

WAVE_TYPES = {ref.WAVE_BANDS: "BANDS", ref.WAVE_RINGS: "RINGS"}
BANDS = {ref.WAVE_X: "X", ref.WAVE_Y: "Y", ref.WAVE_Z: "Z", ref.WAVE_DIAGONAL: "DIAGONAL"}
RINGS = {ref.WAVE_X: "X", ref.WAVE_Y: "Y", ref.WAVE_Z: "Z", ref.WAVE_SPHERICAL: "SPHERICAL"}
PROFILES = {ref.WAVE_SINE: "SIN", ref.WAVE_SAW: "SAW", ref.WAVE_TRIANGLE: "TRI"}
GRADIENT_NAMES = ["LINEAR", "QUADRATIC", "EASING", "DIAGONAL", "SPHERICAL", "QUADRATIC_SPHERE", "RADIAL"]


def _rgba(c):
    return (*c, 1.0)


def _tile_modes(wrap=MAGIC_WRAP):
    """(mode, swizzle) pairs; a mode as devkit.texture_tiles takes it, its numpy reading the
    swizzled coordinate."""

    def mode(label, node_type, props, inputs, output, g, sw="xyz"):
        def f(p):
            e = g(swizzle(p, sw))
            return np.repeat(e[:, 3:], 3, 1) if output == "Fac" else e[:, :3]

        return (label, node_type, props, inputs, output, f), sw

    def wave(kind, direction, profile, sw="xyz", scale=1.0, dist=0.0, detail=2.0, dscale=1.0, rough=0.5, phase=0.0):
        props = {"wave_type": WAVE_TYPES[kind], "wave_profile": PROFILES[profile]}
        props["bands_direction" if kind == ref.WAVE_BANDS else "rings_direction"] = (
            BANDS if kind == ref.WAVE_BANDS else RINGS
        )[direction]
        inputs = {"Scale": scale, "Distortion": dist, "Detail": detail, "Detail Scale": dscale}
        inputs.update({"Detail Roughness": rough, "Phase Offset": phase})
        label = f"wave {props['wave_type'].lower()} {(BANDS if kind == ref.WAVE_BANDS else RINGS)[direction]}"

        def g(p):
            return ref.node_tex_wave(p, scale, dist, detail, dscale, rough, phase, kind, direction, profile)

        return mode(f"{label} {PROFILES[profile].lower()}", "ShaderNodeTexWave", props, inputs, "Color", g, sw)

    def magic(scale, dist, depth, output="Color", sw=("xyz", 8.0)):
        def g(p):
            return ref.node_tex_magic(p, scale, dist, depth, wrap)

        props = {"turbulence_depth": depth}
        inputs = {"Scale": scale, "Distortion": dist}
        return mode(f"magic depth {depth} {output}", "ShaderNodeTexMagic", props, inputs, output, g, sw)

    def brick(c1, c2, m, scale, size, smooth, bias, width, height, offset, ofreq, squash, sfreq, output="Color"):
        props = {"offset": offset, "offset_frequency": ofreq, "squash": squash, "squash_frequency": sfreq}
        inputs = {"Color1": _rgba(c1), "Color2": _rgba(c2), "Mortar": _rgba(m), "Scale": scale}
        inputs.update({"Mortar Size": size, "Mortar Smooth": smooth, "Bias": bias})
        inputs.update({"Brick Width": width, "Row Height": height})

        def g(p):
            return ref.node_tex_brick(p, c1, c2, m, scale, size, smooth, bias, width, height, offset, ofreq,
                                      squash, sfreq)  # fmt: skip

        return mode(f"brick {ofreq}/{sfreq} {output}", "ShaderNodeTexBrick", props, inputs, output, g)

    def checker(c1, c2, scale, sw="xyz"):
        def g(p):
            return ref.node_tex_checker(p, c1, c2, scale)

        inputs = {"Color1": _rgba(c1), "Color2": _rgba(c2), "Scale": scale}
        return mode(f"checker {scale}", "ShaderNodeTexChecker", {}, inputs, "Color", g, sw)

    def gradient(kind, sw="xyz"):
        def g(p):
            return ref.node_tex_gradient(p, kind)

        props = {"gradient_type": GRADIENT_NAMES[kind]}
        return mode(f"gradient {GRADIENT_NAMES[kind].lower()}", "ShaderNodeTexGradient", props, {}, "Color", g, sw)

    return [
        wave(ref.WAVE_BANDS, ref.WAVE_X, ref.WAVE_SINE, scale=1.3, phase=0.4),
        wave(ref.WAVE_BANDS, ref.WAVE_Y, ref.WAVE_SAW, scale=0.8, dist=2.0, detail=2.5, dscale=1.5),
        wave(ref.WAVE_BANDS, ref.WAVE_Z, ref.WAVE_TRIANGLE, "xzy", scale=1.1),
        wave(ref.WAVE_BANDS, ref.WAVE_DIAGONAL, ref.WAVE_SINE, "xyx", scale=0.9, dist=4.0, detail=1.0, rough=0.7),
        wave(ref.WAVE_RINGS, ref.WAVE_X, ref.WAVE_TRIANGLE, "xyx", scale=1.2, dist=1.0),
        wave(ref.WAVE_RINGS, ref.WAVE_Y, ref.WAVE_SINE, "xyx", scale=1.0, phase=1.0),
        wave(ref.WAVE_RINGS, ref.WAVE_Z, ref.WAVE_SAW, scale=1.4, dist=0.5, detail=4.0, dscale=2.0),
        wave(ref.WAVE_RINGS, ref.WAVE_SPHERICAL, ref.WAVE_SINE, "xyx", scale=0.7, dist=3.0, detail=0.0),
        magic(0.7, 1.0, 2),
        magic(0.45, 1.5, 5, "Fac"),
        magic(1.1, 0.0, 0, sw=("xyz", 1.0)),
        magic(0.35, 1.2, 10, sw=("xyz", 2.0)),
        brick(*BRICK_CASES[0][:3], 3.0, 0.03, 0.1, 0.0, 0.5, 0.25, 0.5, 2, 1.0, 2),
        brick(*BRICK_CASES[1][:3], 2.5, 0.05, 0.0, 0.2, 0.7, 0.3, 0.3, 3, 0.6, 2),
        brick(*BRICK_CASES[2][:3], 4.0, 0.06, 0.8, -0.3, 0.4, 0.2, 0.75, 1, 1.5, 3, "Fac"),
        checker((0.8, 0.8, 0.8), (0.2, 0.2, 0.2), 2.5),
        checker((0.9, 0.1, 0.3), (0.0, 0.5, 1.0), 1.5, "xzy"),
        *(gradient(k, "xyx" if k == ref.GRADIENT_SPHERICAL else "xyz") for k in GRADIENTS),
    ]


def _shift_bound(f, pts):
    """Per pixel, how far the mode's colour moves when the sample leaves the pixel centre by
    up to 0.005 pixel (the box pixel filter's half width) along x or y: the change at the four
    shifted points, x and y added."""
    h = np.float32(0.005 * 2.0 / TILE)
    base = f(pts).astype(np.float64)
    bound = np.zeros(len(pts))
    for axis in (0, 1):
        moved = []
        for sign in (-1.0, 1.0):
            q = pts.copy()
            q[:, axis] += np.float32(sign) * h
            moved.append(np.abs(f(q).astype(np.float64) - base).max(1))
        bound += np.maximum(*moved)
    return bound


def test_patterns_land_where_blender_puts_them(penumbra):
    pairs = _tile_modes()
    modes = [m for m, _sw in pairs]
    image = render(build_tiles(modes, [sw for _m, sw in pairs]))["Combined"]
    report = tile_errors(image, modes)
    pts = pixel_points()
    for k, (label, mean, median, mismatched, worst) in enumerate(report):
        # Cycles' sample lands within 0.005 pixel of the centre and its hit point carries float
        # rounding: every pixel lies within 1e-4 of the colour somewhere in that little square
        # (steep patterns - Magic at 8x coordinates, smooth mortar - move up to 3e-3 across it;
        # a saw band's, a brick's or a check's edge may flip a pixel lying on one).
        got = image[:, k * TILE : (k + 1) * TILE, :3].reshape(-1, 3).astype(np.float64)
        err = np.abs(got - modes[k][5](pts).astype(np.float64)).max(1)
        bound = _shift_bound(modes[k][5], pts)
        excess = err - (1e-4 + bound)
        assert np.all(excess <= 0.0), (label, float(excess.max()), int(np.sum(excess > 0)), worst)
        assert median < max(5e-4, float(np.median(bound))), (label, median)
    # The other line's Magic wrap is another pattern once coordinates pass 2 pi.
    other = ref.MAGIC_WRAP_UNSCALED if MAGIC_WRAP == ref.MAGIC_WRAP_SCALED else ref.MAGIC_WRAP_SCALED
    wrong = [m for m, _sw in _tile_modes(other)]
    k = next(i for i, m in enumerate(modes) if m[0].startswith("magic"))
    assert tile_errors(image, wrong)[k][3] > 0.1
