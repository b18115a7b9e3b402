"""The hashed and pattern textures as the node-tree compiler draws them (engine/scene/nodetree.py):
tiled planes (devkit/texture_tiles.py, 40 x 40 pixels each, Object coordinates in [-1, 1]^2) whose
Emission is a texture node's output, rendered by Penumbra (one sample: each pixel its centre,
Standard view, black world) and compared per pixel with the numpy twin (devkit.texture_reference)
at the pixel centres' coordinates. The compiler picks the Voronoi hash and the Magic wrap of the
running Blender line; so does the reference here."""

import bpy
import numpy as np
import pytest

from devkit import engines
from devkit import texture_reference as ref
from devkit.render import render
from devkit.texture_tiles import TILE, build_tiles, pixel_points, swizzle, tile_errors

BLENDER_5 = bpy.app.version >= (5, 0, 0)
HASH_MODE = ref.VORONOI_HASH_INT if BLENDER_5 else ref.VORONOI_HASH_FLOAT
MAGIC_WRAP = ref.MAGIC_WRAP_SCALED if BLENDER_5 else ref.MAGIC_WRAP_UNSCALED
NOISE_TYPES = ["FBM", "MULTIFRACTAL", "HYBRID_MULTIFRACTAL", "RIDGED_MULTIFRACTAL", "HETERO_TERRAIN"]
FEATURES = ["F1", "F2", "SMOOTH_F1", "DISTANCE_TO_EDGE", "N_SPHERE_RADIUS"]
METRICS = ["EUCLIDEAN", "MANHATTAN", "CHEBYCHEV", "MINKOWSKI"]


def _grey(x):
    return np.repeat(np.asarray(x, np.float32).reshape(-1, 1), 3, 1)


def _w(d, p):
    """W as the tiles link it: the coordinate's x in 1D and 4D, else unused."""
    return p[:, 0] if d in (1, 4) else np.zeros(len(p), np.float32)


def _noise(d, kind, output="Fac", scale=3.0, detail=2.0, rough=0.5, lac=2.0, offset=0.0, gain=1.0, dist=0.0, norm=True):
    props = {"noise_dimensions": f"{d}D", "noise_type": NOISE_TYPES[kind], "normalize": norm}
    inputs = {"Scale": scale, "Detail": detail, "Roughness": rough, "Lacunarity": lac, "Offset": offset}
    inputs.update({"Gain": gain, "Distortion": dist})
    if d in (1, 4):
        inputs["W"] = "x"

    def f(p):
        e = ref.node_tex_noise(d, p, _w(d, p), scale, detail, rough, lac, offset, gain, dist, kind, norm)
        return e[:, :3] if output == "Color" else _grey(e[:, 3])

    label = f"noise {d}D {NOISE_TYPES[kind].lower()} {output}"
    return (label, "ShaderNodeTexNoise", props, inputs, output, f)


def _voronoi(d, feature, metric, output, scale=4.0, detail=0.0, rough=0.5, lac=2.0, smooth=1.0, exponent=0.5,
             rnd=1.0, norm=False):  # fmt: skip
    props = {"voronoi_dimensions": f"{d}D", "feature": FEATURES[feature], "distance": METRICS[metric]}
    props["normalize"] = norm
    inputs = {"Scale": scale, "Detail": detail, "Roughness": rough, "Lacunarity": lac, "Smoothness": smooth}
    inputs.update({"Exponent": exponent, "Randomness": rnd})
    if d in (1, 4):
        inputs["W"] = "x"

    def f(p):
        e = ref.node_tex_voronoi(d, p, _w(d, p), feature, metric, scale, detail, rough, lac, smooth, exponent, rnd,
                                 norm, HASH_MODE)  # fmt: skip
        if output == "Color":
            return e[:, 1:4]
        if output == "Position":
            return e[:, 4:7]
        return _grey(e[:, {"Distance": 0, "Radius": 0, "W": 7}[output]])

    label = f"voronoi {d}D {FEATURES[feature].lower()} {METRICS[metric].lower()} {output}"
    return (label, "ShaderNodeTexVoronoi", props, inputs, output, f)


def _white(d, output):
    def f(p):
        q = np.floor(p * np.float32(4.0)).astype(np.float32)
        e = ref.node_tex_white_noise(d, q, q[:, 0])
        return e[:, :3] if output == "Color" else _grey(e[:, 3])

    return (f"white noise {d}D {output}", "ShaderNodeTexWhiteNoise", {"noise_dimensions": f"{d}D"}, {}, output, f)


def _pattern(label, node_type, props, inputs, output, g, sw="xyz"):
    def f(p):
        e = g(swizzle(p, sw))
        return _grey(e[:, 3]) if output == "Fac" else e[:, :3]

    return (label, node_type, props, inputs, output, f), sw


def _patterns():
    wave = [
        ("BANDS", "X", "SIN", ref.WAVE_BANDS, ref.WAVE_X, ref.WAVE_SINE, 1.3, 0.0, 0.4, "xyz"),
        ("BANDS", "DIAGONAL", "SAW", ref.WAVE_BANDS, ref.WAVE_DIAGONAL, ref.WAVE_SAW, 0.8, 2.0, 0.0, "xyz"),
        ("RINGS", "SPHERICAL", "TRI", ref.WAVE_RINGS, ref.WAVE_SPHERICAL, ref.WAVE_TRIANGLE, 0.7, 3.0, 1.0, "xyx"),
        ("RINGS", "Z", "SIN", ref.WAVE_RINGS, ref.WAVE_Z, ref.WAVE_SINE, 1.1, 0.5, 0.0, "xyz"),
    ]
    out = []
    for kind, direction, profile, k, dk, pk, scale, dist, phase, sw in wave:
        props = {"wave_type": kind, "wave_profile": profile}
        props["bands_direction" if kind == "BANDS" else "rings_direction"] = direction
        inputs = {"Scale": scale, "Distortion": dist, "Detail": 2.5, "Detail Scale": 1.5, "Detail Roughness": 0.6}
        inputs["Phase Offset"] = phase

        def g(p, k=k, dk=dk, pk=pk, scale=scale, dist=dist, phase=phase):
            return ref.node_tex_wave(p, scale, dist, 2.5, 1.5, 0.6, phase, k, dk, pk)

        output = "Fac" if kind == "RINGS" else "Color"
        out.append(_pattern(f"wave {kind} {direction} {profile}", "ShaderNodeTexWave", props, inputs, output, g, sw))
    for scale, dist, depth, output in ((0.7, 1.0, 2, "Color"), (0.45, 1.5, 5, "Fac")):

        def g(p, scale=scale, dist=dist, depth=depth):
            return ref.node_tex_magic(p, scale, dist, depth, MAGIC_WRAP)

        props, inputs = {"turbulence_depth": depth}, {"Scale": scale, "Distortion": dist}
        out.append(_pattern(f"magic {depth} {output}", "ShaderNodeTexMagic", props, inputs, output, g, ("xyz", 8.0)))
    bricks = [
        ((0.9, 0.3, 0.1), (0.1, 0.4, 0.8), (0.5, 0.5, 0.4), 2.5, 0.05, 0.0, 0.2, 0.7, 0.3, 0.3, 3, 0.6, 2, "Color"),
        ((0.2, 0.7, 0.3), (0.8, 0.1, 0.6), (1.0, 1.0, 1.0), 4.0, 0.06, 0.8, -0.3, 0.4, 0.2, 0.75, 1, 1.5, 3, "Fac"),
    ]
    for c1, c2, m, scale, size, smooth, bias, width, height, offset, ofreq, squash, sfreq, output in bricks:
        props = {"offset": offset, "offset_frequency": ofreq, "squash": squash, "squash_frequency": sfreq}
        inputs = {"Color1": (*c1, 1.0), "Color2": (*c2, 1.0), "Mortar": (*m, 1.0), "Scale": scale}
        inputs.update({"Mortar Size": size, "Mortar Smooth": smooth, "Bias": bias})
        inputs.update({"Brick Width": width, "Row Height": height})

        def g(p, a=(c1, c2, m, scale, size, smooth, bias, width, height, offset, ofreq, squash, sfreq)):
            return ref.node_tex_brick(p, *a)

        out.append(_pattern(f"brick {ofreq}/{sfreq} {output}", "ShaderNodeTexBrick", props, inputs, output, g))
    return out


def _modes():
    """(mode, swizzle, kind): kind says how its pixels are compared (see the test)."""
    modes = [(m, "xyz", "continuous") for m in (
        _noise(1, ref.NOISE_FBM, "Color", detail=3.0),
        _noise(2, ref.NOISE_MULTIFRACTAL, norm=False, dist=0.6),
        _noise(3, ref.NOISE_HYBRID_MULTIFRACTAL, "Color", offset=0.7, gain=1.3, detail=4.5, rough=0.6),
        _noise(4, ref.NOISE_RIDGED_MULTIFRACTAL, offset=1.0, gain=2.0),
        _noise(3, ref.NOISE_HETERO_TERRAIN, offset=0.8, detail=3.7),
        _noise(3, ref.NOISE_FBM, "Color", norm=False, dist=1.5, lac=2.3),
    )]  # fmt: skip
    voronoi = [
        _voronoi(1, ref.VORONOI_F1, ref.VORONOI_EUCLIDEAN, "Color"),
        _voronoi(1, ref.VORONOI_SMOOTH_F1, ref.VORONOI_EUCLIDEAN, "W", smooth=0.6),
        _voronoi(2, ref.VORONOI_F1, ref.VORONOI_MANHATTAN, "Color", rnd=0.8),
        _voronoi(2, ref.VORONOI_F2, ref.VORONOI_CHEBYCHEV, "Position"),
        _voronoi(2, ref.VORONOI_DISTANCE_TO_EDGE, ref.VORONOI_EUCLIDEAN, "Distance", detail=2.5, norm=True),
        _voronoi(3, ref.VORONOI_F1, ref.VORONOI_MINKOWSKI, "Distance", exponent=1.5, rnd=0.7),
        _voronoi(3, ref.VORONOI_SMOOTH_F1, ref.VORONOI_EUCLIDEAN, "Color", smooth=0.8, rnd=0.9),
        _voronoi(3, ref.VORONOI_N_SPHERE_RADIUS, ref.VORONOI_EUCLIDEAN, "Radius"),
        _voronoi(3, ref.VORONOI_F1, ref.VORONOI_EUCLIDEAN, "Distance", detail=2.0, rough=0.6, lac=2.2, norm=True),
        _voronoi(4, ref.VORONOI_F2, ref.VORONOI_EUCLIDEAN, "Color"),
        _voronoi(4, ref.VORONOI_F1, ref.VORONOI_EUCLIDEAN, "W"),
    ]
    cell = [m[4] in ("Color", "Position") and "smooth" not in m[0] for m in voronoi]  # Smooth F1 blends cells
    modes += [(m, "xyz", "cell colour" if c else "edges") for m, c in zip(voronoi, cell, strict=True)]
    modes += [
        (_white(d, output), "xyz", "exact") for d, output in ((1, "Color"), (2, "Value"), (3, "Color"), (4, "Color"))
    ]
    modes += [(m, sw, "edges") for m, sw in _patterns()]
    return modes


@pytest.mark.negative_inputs  # texture outputs below zero on purpose (Musgrave-like noise, Wave, ...)
def test_compiled_textures_match_numpy_per_pixel(penumbra):
    """Noise (every type, 1-4D, Normalize, Distortion, Fac and Color), Voronoi (every feature
    and metric, 1-4D, fractal, each output), White Noise (1-4D, Value and Color), Wave, Magic and
    Brick through the compiler, against numpy at the pixel centres (Object coordinates)."""
    from penumbra.engine.scene.materials import material_from_blender

    modes = _modes()
    scene = build_tiles([m for m, _sw, _kind in modes], [sw for _m, sw, _kind in modes])
    engines.configure(scene, "PENUMBRA")
    scene.penumbra.render_samples = 1
    scene.render.filter_size = 0.0
    for m, _sw, _kind in modes:
        read = material_from_blender(bpy.data.materials[m[0]])
        assert read.tree is not None and read.tree.fallbacks == 0, (m[0], read.messages)
    image = render(scene)["Combined"]
    report = tile_errors(image, [m for m, _sw, _kind in modes])
    pts = pixel_points()
    for k, ((label, *_rest, f), _sw, kind) in enumerate(modes):
        got = image[:, k * TILE : (k + 1) * TILE, :3].reshape(-1, 3).astype(np.float64)
        err = np.abs(got - f(pts).astype(np.float64)).max(1)
        assert np.all(np.isfinite(got)), label
        # Measured on 5.2 and 4.5 (tile_errors prints the table): White Noise and Voronoi's
        # cell colours and positions equal numpy bit for bit; the continuous outputs differ by
        # float32 evaluation order and the interpolated coordinate's rounding (noise up to 1.3e-4,
        # median 3e-6); distances, bands, mortar and Magic's steep waves up to 2.2e-4, and a
        # pixel on a discontinuity (a cell border, an edge) may take the other side.
        if kind == "exact":
            assert err.max() == 0.0, (label, report[k])
        elif kind == "cell colour":
            assert np.mean(err > 0.0) <= 0.01, (label, report[k])
        elif kind == "continuous":
            assert err.max() < 5e-4 and np.median(err) < 2e-5, (label, report[k])
        else:
            assert np.mean(err > 1e-3) <= 0.01 and np.median(err) < 5e-5, (label, report[k])
