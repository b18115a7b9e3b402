"""Procedural textures (``shaders/nodes/texture_*.glsl``) against their numpy twins
(``devkit.texture_reference``) on the GPU, and the numpy twins against Blender's own Cycles: a
pattern must land where Blender puts it, pixel for pixel.

Blender 4.5 hashes Voronoi cells as floats, Blender 5 as integers (PCG): the render test picks
the hash of the running line."""

import bpy
import numpy as np
import pytest

from devkit import texture_reference as ref
from devkit.render import render
from devkit.texture_gpu import evaluate_many
from devkit.texture_tiles import NEAR, build_tiles, compare, gpu_scene, points, rounding_spread, tile_errors

HASH = ["texture_hash.glsl"]
NOISE = ["common.glsl", *HASH, "texture_noise.glsl"]  # texture_noise and its requires line
VORONOI = ["common.glsl", *HASH, "texture_voronoi.glsl"]
WHITE = HASH + ["texture_white_noise.glsl"]
SWIZZLE = {1: "a0.w", 2: "a0.xy", 3: "a0.xyz", 4: "a0"}
HASH_MODE = ref.VORONOI_HASH_INT if bpy.app.version >= (5, 0, 0) else ref.VORONOI_HASH_FLOAT


def test_hashes_are_bit_exact_on_the_gpu(penumbra, gpu_call):
    gpu_scene()
    rng = np.random.default_rng(3)
    keys = rng.integers(0, 2**32, (4096, 4), dtype=np.uint64).astype(np.uint32)
    keys[(keys & 0x7F800000) == 0x7F800000] &= 0xBFFFFFFF  # no NaN/inf bit patterns in the upload
    keys[:16] = [[0, 0, 0, 0], [1, 2, 3, 4], [0xFFFFFFFF] * 4, [0x80000000] * 4] * 4
    halves = "result = vec4(float(h0 >> 16u), float(h0 & 0xffffu), float(h1 >> 16u), float(h1 & 0xffffu));"
    bodies = {
        (1, 2): "uvec4 k = floatBitsToUint(a0); uint h0 = hash_uint(k.x); uint h1 = hash_uint2(k.x, k.y);",
        (3, 4): "uvec4 k = floatBitsToUint(a0); uint h0 = hash_uint3(k.x, k.y, k.z); "
        "uint h1 = hash_uint4(k.x, k.y, k.z, k.w);",
        "pcg2": "ivec4 k = floatBitsToInt(a0); ivec2 a = hash_pcg2d_i(k.xy); uint h0 = uint(a.x); uint h1 = uint(a.y);",
        "pcg3": "ivec4 k = floatBitsToInt(a0); ivec3 a = hash_pcg3d_i(k.xyz); uint h0 = uint(a.x); "
        "uint h1 = uint(a.z);",
        "pcg4": "ivec4 k = floatBitsToInt(a0); ivec4 a = hash_pcg4d_i(k); uint h0 = uint(a.y); uint h1 = uint(a.w);",
    }
    outs = evaluate_many(gpu_call, [(HASH, body + halves, [keys.view(np.float32)]) for body in bodies.values()])
    k = keys.T
    signed = keys.view(np.int32)
    expected = [
        (ref.hash_uint(k[0]), ref.hash_uint(k[0], k[1])),
        (ref.hash_uint(k[0], k[1], k[2]), ref.hash_uint(*k)),
        tuple(ref.hash_pcg(signed[:, :2]).T.view(np.uint32)),
        tuple(ref.hash_pcg(signed[:, :3])[:, [0, 2]].T.view(np.uint32)),
        tuple(ref.hash_pcg(signed)[:, [1, 3]].T.view(np.uint32)),
    ]
    for out, (e0, e1) in zip(outs, expected):
        got = out.astype(np.uint32)
        np.testing.assert_array_equal((got[:, 0] << 16) | got[:, 1], e0)
        np.testing.assert_array_equal((got[:, 2] << 16) | got[:, 3], e1)


NOISE_CASES = [
    # (dimensions, detail, roughness, lacunarity, offset, gain, distortion, type, normalize)
    (1, 2.0, 0.5, 2.0, 0.0, 1.0, 0.0, ref.NOISE_FBM, True),
    (2, 3.5, 0.6, 2.1, 0.0, 1.0, 0.4, ref.NOISE_FBM, True),
    (3, 2.0, 0.5, 2.0, 0.0, 1.0, 0.0, ref.NOISE_FBM, False),
    (4, 1.3, 0.7, 1.9, 0.0, 1.0, 1.5, ref.NOISE_FBM, True),
    (3, 0.0, 0.5, 2.0, 0.0, 1.0, 0.0, ref.NOISE_FBM, True),
    (3, 3.7, 0.5, 2.0, 0.0, 1.0, 0.0, ref.NOISE_MULTIFRACTAL, True),
    (2, 3.7, 0.5, 2.0, 0.8, 1.0, 0.0, ref.NOISE_HETERO_TERRAIN, True),
    (3, 4.5, 0.6, 2.0, 0.7, 1.3, 0.0, ref.NOISE_HYBRID_MULTIFRACTAL, True),
    (4, 3.0, 0.5, 2.0, 1.0, 2.0, 0.0, ref.NOISE_RIDGED_MULTIFRACTAL, True),
]


def test_noise_glsl_matches_numpy(penumbra, gpu_call):
    gpu_scene()
    pts = points()
    scale = 1.7
    jobs = []
    for d, detail, rough, lac, offset, gain, dist, kind, norm in NOISE_CASES:
        args = f"{detail}, {rough}, {lac}, {offset}, {gain}, {dist}, {kind}, {'true' if norm else 'false'}"
        body = f"result = node_tex_noise_at(texture_finite({SWIZZLE[d]}) * {scale}, {args});"
        jobs.append((NOISE, body, [pts]))
    jobs.append(
        (
            NOISE,
            "result = vec4(noise_snoise(a0.x), noise_snoise(a0.xy), noise_snoise(a0.xyz), noise_snoise(a0));",
            [pts],
        )
    )
    outs = evaluate_many(gpu_call, jobs)
    for out, (d, *params) in zip(outs, NOISE_CASES):

        def noise(p, d=d, params=params):
            return ref.node_tex_noise(d, p[:, :3], p[:, 3], scale, *params)

        expected = noise(pts)
        # float32 evaluation order (the GPU may fuse multiply-adds): measured up to 1.3e-5 on
        # the 4D colour, whose octaves and distortion compound the rounding. Far from the
        # origin (rows outside NEAR) an ulp of the coordinate is a visible step of the noise
        # (0.002 at 1.7e4): a GPU that rounds a scaled, octave or distorted coordinate
        # otherwise lands anywhere the reference reaches within 4 ulps of the point, so there
        # that spread is added; within [-10, 10]^4 the bound stays as it was.
        far = far_allowance(rounding_spread(noise, pts))
        compare(out, expected, 1e-4, 5e-5 + far, ("noise", d, params))
    signed = np.stack([ref.snoise(pts[:, :k]) for k in (1, 2, 3, 4)], -1)
    # The same for the signed noise (no scale, no fractal: exact near the origin).
    far = far_allowance(rounding_spread(lambda p: np.stack([ref.snoise(p[:, :k]) for k in (1, 2, 3, 4)], -1), pts))
    compare(outs[-1], signed, 0.0, 2e-6 + far, "snoise")
    # The reduction keeps far coordinates in range: noise at 1e5-scale points is not constant.
    assert np.std(signed[256:320]) > 0.05


def far_allowance(spread):
    """``spread`` (``rounding_spread``) on the rows outside [-10, 10]^4, 0 on the others."""
    far = np.ones(len(spread), bool)
    far[NEAR] = False
    return np.where(far[:, None], spread, 0.0)


VORONOI_CASES = [
    # (dimensions, feature, metric, detail, smoothness, exponent, randomness, normalize)
    (1, ref.VORONOI_F1, ref.VORONOI_EUCLIDEAN, 0.0, 1.0, 0.5, 1.0, False),
    (1, ref.VORONOI_SMOOTH_F1, ref.VORONOI_EUCLIDEAN, 0.0, 0.6, 0.5, 1.0, False),
    (2, ref.VORONOI_F1, ref.VORONOI_EUCLIDEAN, 0.0, 1.0, 0.5, 1.0, False),
    (2, ref.VORONOI_F2, ref.VORONOI_MANHATTAN, 0.0, 1.0, 0.5, 0.8, True),
    (2, ref.VORONOI_DISTANCE_TO_EDGE, ref.VORONOI_EUCLIDEAN, 2.5, 1.0, 0.5, 1.0, True),
    (3, ref.VORONOI_F1, ref.VORONOI_CHEBYCHEV, 0.0, 1.0, 0.5, 1.0, False),
    (3, ref.VORONOI_SMOOTH_F1, ref.VORONOI_EUCLIDEAN, 0.0, 0.8, 0.5, 0.9, False),
    (3, ref.VORONOI_F1, ref.VORONOI_MINKOWSKI, 2.0, 1.0, 1.5, 0.7, True),
    (3, ref.VORONOI_N_SPHERE_RADIUS, ref.VORONOI_EUCLIDEAN, 0.0, 1.0, 0.5, 1.0, False),
    (4, ref.VORONOI_F2, ref.VORONOI_EUCLIDEAN, 0.0, 1.0, 0.5, 1.0, False),
    (4, ref.VORONOI_DISTANCE_TO_EDGE, ref.VORONOI_EUCLIDEAN, 0.0, 1.0, 0.5, 1.0, False),
]


@pytest.mark.parametrize("hash_mode", [ref.VORONOI_HASH_FLOAT, ref.VORONOI_HASH_INT])
def test_voronoi_glsl_matches_numpy(penumbra, gpu_call, hash_mode):
    gpu_scene()
    pts = points(1024)
    scale = 2.3
    jobs = []
    for d, feature, metric, detail, smooth, exponent, rnd, norm in VORONOI_CASES:
        call = (
            f"node_tex_voronoi_at(texture_finite(texture_finite({SWIZZLE[d]}) * {scale}), "
            f"{feature}, {metric}, {scale}, "
            f"{detail}, 0.5, 2.0, {smooth}, {exponent}, {rnd}, {'true' if norm else 'false'}, {hash_mode}, "
            "dist, col, pos, rad);"
        )
        jobs.append(
            (VORONOI, f"float dist, rad; vec3 col; vec4 pos; {call} result = vec4(dist + rad, col.rg, 0.0);", [pts])
        )
        jobs.append(
            (
                VORONOI,
                f"float dist, rad; vec3 col; vec4 pos; {call} result = vec4(col.b, pos.xy, pos.z + pos.w);",
                [pts],
            )
        )
    outs = evaluate_many(gpu_call, jobs)
    for i, (d, feature, metric, detail, smooth, exponent, rnd, norm) in enumerate(VORONOI_CASES):

        def voronoi(p, d=d, feature=feature, metric=metric, detail=detail, smooth=smooth, exponent=exponent,
                    rnd=rnd, norm=norm):  # fmt: skip
            e = ref.node_tex_voronoi(
                d, p[:, :3], p[:, 3], feature, metric, scale, detail, 0.5, 2.0, smooth, exponent, rnd, norm, hash_mode
            )
            return np.concatenate(
                [
                    np.stack([e[:, 0], e[:, 1], e[:, 2], 0 * e[:, 0]], -1),
                    np.stack([e[:, 3], e[:, 4], e[:, 5], e[:, 6] + e[:, 7]], -1),
                ],
                1,
            )

        expected = voronoi(pts)
        out = np.concatenate([outs[2 * i], outs[2 * i + 1]], 1)
        assert np.all(np.isfinite(out))
        # Positions carry the cell coordinate (up to 1e30 / scale here): relative tolerance.
        tol = 1e-5 + 2e-6 * np.abs(expected)
        err = np.abs(out.astype(np.float64) - expected)
        bad = np.any(err > tol, axis=1)
        # A point equidistant from two feature points to float32 rounding may pick either (a
        # fused multiply-add in a distance is enough): a point may differ only where the
        # reference itself picks another cell within 4 ulps of it, and at most 1 % of them do.
        tie = np.any(rounding_spread(voronoi, pts) > tol, axis=1)
        assert not np.any(bad & ~tie), (d, feature, metric, np.flatnonzero(bad & ~tie)[:8], float(err.max()))
        assert bad.sum() <= 0.01 * len(pts), (d, feature, metric, int(bad.sum()), int(tie.sum()))


def test_white_noise_glsl_matches_numpy_bit_for_bit(penumbra, gpu_call):
    gpu_scene()
    pts = points()
    pts = np.where(np.isnan(pts), 1.0, pts).astype(np.float32)  # NaN payloads do not survive the upload
    outs = evaluate_many(
        gpu_call, [(WHITE, f"result = node_tex_white_noise({d}, a0.xyz, a0.w);", [pts]) for d in (1, 2, 3, 4)]
    )
    for d, out in zip((1, 2, 3, 4), outs):
        np.testing.assert_array_equal(out, ref.node_tex_white_noise(d, pts[:, :3], pts[:, 3]))


# --- against Blender ------------------------------------------------------------------------


def _tile_modes():
    """(label, node type, node properties, input values, output socket, numpy of (n, 3) points
    giving the (n, 3) emitted colour). Blender's own names: property values and sockets."""
    v = HASH_MODE

    def noise(d, scale, detail, rough, lac, dist, kind, norm, w=0.0):
        kinds = {
            ref.NOISE_FBM: "FBM",
            ref.NOISE_MULTIFRACTAL: "MULTIFRACTAL",
            ref.NOISE_HETERO_TERRAIN: "HETERO_TERRAIN",
        }
        props = {"noise_dimensions": f"{d}D", "noise_type": kinds[kind], "normalize": norm}
        inputs = {"Scale": scale, "Detail": detail, "Roughness": rough, "Lacunarity": lac, "Distortion": dist, "W": w}

        def f(p):
            return ref.node_tex_noise(
                d, p, np.full(len(p), w, np.float32), scale, detail, rough, lac, 0.0, 1.0, dist, kind, norm
            )[:, :3]

        return "ShaderNodeTexNoise", props, inputs, "Color", f

    def voronoi(
        d, feature, metric, output, scale=5.0, rnd=1.0, smooth=1.0, exponent=0.5, detail=0.0, norm=False, w=0.0
    ):
        names = ["F1", "F2", "SMOOTH_F1", "DISTANCE_TO_EDGE", "N_SPHERE_RADIUS"]
        metrics = ["EUCLIDEAN", "MANHATTAN", "CHEBYCHEV", "MINKOWSKI"]
        props = {
            "voronoi_dimensions": f"{d}D",
            "feature": names[feature],
            "distance": metrics[metric],
            "normalize": norm,
        }
        inputs = {
            "Scale": scale,
            "Randomness": rnd,
            "Smoothness": smooth,
            "Exponent": exponent,
            "Detail": detail,
            "W": w,
        }

        def f(p):
            e = ref.node_tex_voronoi(d, p, np.full(len(p), w, np.float32), feature, metric, scale, detail, 0.5, 2.0,
                                     smooth, exponent, rnd, norm, v)  # fmt: skip
            return e[:, 1:4] if output == "Color" else np.repeat(e[:, :1], 3, 1)

        return "ShaderNodeTexVoronoi", props, inputs, output, f

    return [
        ("noise 3D fBM", *noise(3, 5.0, 2.0, 0.5, 2.0, 0.0, ref.NOISE_FBM, True)),
        ("noise 2D fBM distorted", *noise(2, 3.0, 3.5, 0.6, 2.1, 0.4, ref.NOISE_FBM, True)),
        ("noise 4D fBM", *noise(4, 4.0, 1.5, 0.5, 2.0, 0.0, ref.NOISE_FBM, True, w=0.3)),
        ("noise 3D multifractal", *noise(3, 4.0, 2.0, 0.5, 2.0, 0.0, ref.NOISE_MULTIFRACTAL, True)),
        ("voronoi 3D F1", *voronoi(3, ref.VORONOI_F1, ref.VORONOI_EUCLIDEAN, "Distance")),
        ("voronoi 3D F1 colour", *voronoi(3, ref.VORONOI_F1, ref.VORONOI_EUCLIDEAN, "Color")),
        ("voronoi 2D F2 Manhattan", *voronoi(2, ref.VORONOI_F2, ref.VORONOI_MANHATTAN, "Color", rnd=0.8)),
        ("voronoi 3D smooth F1", *voronoi(3, ref.VORONOI_SMOOTH_F1, ref.VORONOI_EUCLIDEAN, "Distance", smooth=0.7)),
        ("voronoi 2D edge", *voronoi(2, ref.VORONOI_DISTANCE_TO_EDGE, ref.VORONOI_EUCLIDEAN, "Distance", scale=3.0)),
        ("voronoi 3D Minkowski", *voronoi(3, ref.VORONOI_F1, ref.VORONOI_MINKOWSKI, "Distance", exponent=1.5, rnd=0.7)),
        (
            "voronoi 4D F1 fractal",
            *voronoi(4, ref.VORONOI_F1, ref.VORONOI_EUCLIDEAN, "Distance", detail=2.0, norm=True, w=0.4),
        ),
        ("voronoi 2D Chebychev", *voronoi(2, ref.VORONOI_F1, ref.VORONOI_CHEBYCHEV, "Color", scale=4.0)),
    ]


def _white_noise_mode(d):
    """White Noise of the object coordinate snapped to a 1/4 lattice (Vector Math Multiply 4,
    Floor): the hash reads exact float bits, which a ray-plane hit does not reproduce."""

    def f(p):
        q = np.floor(p * np.float32(4.0)).astype(np.float32)
        return ref.node_tex_white_noise(d, q, q[:, 0])[:, :3]

    return (f"white noise {d}D", "ShaderNodeTexWhiteNoise", {"noise_dimensions": f"{d}D"}, {}, "Color", f)


def test_textures_land_where_blender_puts_them(penumbra):
    modes = _tile_modes() + [_white_noise_mode(d) for d in (2, 3, 4)]
    scene = build_tiles(modes)
    report = tile_errors(render(scene)["Combined"], modes)
    for label, mean, median, mismatched, worst in report:
        # Cycles' samples land within 0.005 pixel of the centre (pixel filter 0.01) and the hit
        # point carries float rounding: continuous patterns differ by that little shift only.
        # Voronoi may pick the other cell for pixels on a cell border (at most 1 % of them).
        limit = 0.0 if label.startswith(("noise", "white")) else 0.01
        assert mismatched <= limit, (label, mismatched, worst)
        assert median < 5e-4, (label, median)


def test_noise_and_voronoi_detail_beyond_its_range_is_bounded(penumbra, gpu_call):
    """Detail is a count of octaves: NaN, 1e30 and -1e30 (a linked input can hold any float)
    end their loops as Blender's clamp to [0, 15] does: 1e30 gives Detail 15, NaN and -1e30
    Detail 0 (nodes/common.glsl node_detail; each loop also stops at NODE_MAX_OCTAVE)."""
    gpu_scene()
    pts = points()[:64]
    jobs = []
    for detail in ("uintBitsToFloat(0x7fc00000u)", "1e30", "-1e30", "15.0", "0.0"):
        args = f"{detail}, 0.5, 2.0, 0.0, 1.0, 0.0, {ref.NOISE_FBM}, true"
        jobs.append((NOISE, f"result = node_tex_noise_at(texture_finite(a0.xyz) * 1.7, {args});", [pts]))
        voronoi = (
            "float d, r; vec3 c; vec4 q; node_tex_voronoi_at(texture_finite(a0.xyz) * 1.7, VORONOI_F1, "
            f"VORONOI_EUCLIDEAN, 1.0, {detail}, 0.5, 2.0, 1.0, 0.5, 1.0, true, {HASH_MODE}, d, c, q, r); "
            "result = vec4(d, c);"
        )
        jobs.append((VORONOI, voronoi, [pts]))
    outs = evaluate_many(gpu_call, jobs)
    for kind in (0, 1):  # noise, voronoi
        nan, huge, negative, fifteen, zero = outs[kind::2]
        np.testing.assert_array_equal(huge, fifteen)
        np.testing.assert_array_equal(nan, zero)
        np.testing.assert_array_equal(negative, zero)
        assert np.all(np.isfinite(fifteen)) and not np.array_equal(fifteen, zero)
