"""Shared by the procedural texture tests (``tests/nodes``): the points the GPU and numpy
evaluate, and a Cycles scene of tiled planes, one per texture mode, whose Emission is the
texture of the Object coordinate.

A mode is ``(label, node type, node properties, input values, output socket, f)``: Blender's own
names for properties and sockets (an input value "x", "y" or "z" links that component of the
coordinate, a texture's W say), and ``f`` the numpy of (n, 3) Object coordinates giving the
(n, 3) emitted colour. ``swizzle`` (optional, one string per mode such as ``"xzy"`` or ``"xy0"``)
feeds the texture a permutation of the coordinate (Separate and Combine XYZ, exact) so planes at
z = 0 exercise every axis."""

import bpy
import numpy as np

from devkit import engines, scenes

TILE = 40  # pixels per tile side; each tile is a 2 x 2 plane, object coordinates in [-1, 1]^2


def gpu_scene():
    """Any scene with a camera: the GPU runner renders the current scene."""
    scene = scenes.empty_scene(8, 8)
    scenes.top_camera(scene)
    return scene


def points(n=2048, seed=7):
    """Random points in [-10, 10]^4, then the hard cases: lattice points (exact integers,
    negative too) in rows 0-127, 1e4-scale coordinates in rows 128-255, 1e5-scale in rows
    256-319, and non-finite and huge values in every slot in rows 320-351."""
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-10.0, 10.0, (n, 4))
    pts[:128] = np.round(pts[:128])
    pts[128:256] = rng.uniform(-1.0e4, 1.0e4, (128, 4))
    pts[256:320] *= 1.0e5  # past the noise's 100000 period and its 1e6 half-cell shift
    special = [np.nan, np.inf, -np.inf, 1.0e30, -1.0e30, 0.0, -0.0, 3.0e38]
    for i, v in enumerate(special):
        pts[320 + i * 4 : 324 + i * 4, i % 4] = v
    return pts.astype(np.float32)


NEAR = np.r_[0:128, 352:2048]  # rows of points() within [-10, 10]^4


def rounding_spread(f, pts, ulps=4, trials=6, seed=0):
    """How far ``f(pts)`` (numpy, (n, k)) moves when each input component moves by up to
    ``ulps`` float32 ulps of its own magnitude: (n, k). Two conformant GPUs may round the scaled
    coordinate, an octave's coordinate or a fused multiply-add differently by about that much,
    so an output may differ from the reference by that much too (far more at 1e4 than near 0)."""
    pts = np.asarray(pts, np.float32)
    base = f(pts).astype(np.float64)
    rng = np.random.default_rng(seed)
    spread = np.zeros_like(base)
    wide = pts.astype(np.float64)
    for t in range(trials):
        sign = rng.choice([-1.0, 1.0], pts.shape) if t >= 2 else np.full(pts.shape, 1.0 - 2.0 * t)
        with np.errstate(invalid="ignore", over="ignore"):
            moved = (wide * (1.0 + sign * ulps * 2.0**-23)).astype(np.float32)
        moved = np.where(np.isfinite(pts), moved, pts)
        with np.errstate(invalid="ignore"):
            diff = np.abs(f(moved).astype(np.float64) - base)
        spread = np.maximum(spread, np.where(np.isfinite(diff), diff, 0.0))
    return spread


def compare(out, expected, rtol, atol, what):
    """``atol`` may be per value (e.g. plus ``rounding_spread``)."""
    assert np.all(np.isfinite(out)), what
    err = np.abs(out.astype(np.float64) - expected)
    assert np.all(err <= atol + rtol * np.abs(expected)), (what, float(err.max()), int(np.argmax(err.max(1))))


def swizzle(p, s):
    """The coordinate the texture reads: component c of ``s`` is x, y, z or 0; ``s`` may be a
    pair (string, factor)."""
    s, factor = s if isinstance(s, tuple) else (s, 1.0)
    cols = {"x": p[:, 0], "y": p[:, 1], "z": p[:, 2], "0": np.zeros(len(p), np.float32)}
    return (np.stack([cols[c] for c in s], -1) * np.float32(factor)).astype(np.float32)


def _vector(nt, vector, s, node_type):
    s, factor = s if isinstance(s, tuple) else (s, 1.0)
    if s and s != "xyz":
        sep = nt.nodes.new("ShaderNodeSeparateXYZ")
        comb = nt.nodes.new("ShaderNodeCombineXYZ")
        nt.links.new(vector, sep.inputs[0])
        for i, c in enumerate(s):
            if c == "0":
                comb.inputs[i].default_value = 0.0
            else:
                nt.links.new(sep.outputs["xyz".index(c)], comb.inputs[i])
        vector = comb.outputs[0]
    if factor != 1.0:
        mul = nt.nodes.new("ShaderNodeVectorMath")
        mul.operation = "MULTIPLY"
        mul.inputs[1].default_value = (factor, factor, factor)
        nt.links.new(vector, mul.inputs[0])
        vector = mul.outputs[0]
    if node_type == "ShaderNodeTexWhiteNoise":
        # White Noise of the coordinate snapped to a 1/4 lattice (Vector Math Multiply 4,
        # Floor): the hash reads exact float bits, which a ray-plane hit does not reproduce.
        mul = nt.nodes.new("ShaderNodeVectorMath")
        mul.operation = "MULTIPLY"
        mul.inputs[1].default_value = (4.0, 4.0, 4.0)
        floor = nt.nodes.new("ShaderNodeVectorMath")
        floor.operation = "FLOOR"
        nt.links.new(vector, mul.inputs[0])
        nt.links.new(mul.outputs[0], floor.inputs[0])
        vector = floor.outputs[0]
    return vector


def build_tiles(modes, swizzles=None):
    """A Cycles scene (1 sample) of one 2 x 2 plane per mode side by side, TILE pixels each."""
    scene = scenes.empty_scene(TILE * len(modes), TILE, engine="CYCLES")
    engines.configure(scene, "CYCLES", samples=1)
    scenes.camera(scene, (len(modes) - 1.0, 0.0, 5.0), (0.0, 0.0, 0.0), ortho_scale=2.0 * len(modes), clip=(0.1, 10.0))
    for k, (label, node_type, props, inputs, output, _f) in enumerate(modes):
        mat = bpy.data.materials.new(label)
        mat.use_nodes = True
        nt = mat.node_tree
        nt.nodes.clear()
        coords = nt.nodes.new("ShaderNodeTexCoord")
        tex = nt.nodes.new(node_type)
        for name, value in props.items():
            setattr(tex, name, value)
        for name, value in inputs.items():
            if name in tex.inputs and not isinstance(value, str):
                tex.inputs[name].default_value = value
        vector = _vector(nt, coords.outputs["Object"], swizzles[k] if swizzles else None, node_type)
        for name, value in inputs.items():
            if isinstance(value, str):  # "x", "y" or "z": that component of the coordinate, linked
                sep = nt.nodes.new("ShaderNodeSeparateXYZ")
                nt.links.new(vector, sep.inputs[0])
                nt.links.new(sep.outputs["xyz".index(value)], tex.inputs[name])
        if node_type == "ShaderNodeTexWhiteNoise" and "W" in tex.inputs:
            # 4D: W is the snapped x (a socket hidden in 2D and 3D)
            sep = nt.nodes.new("ShaderNodeSeparateXYZ")
            nt.links.new(vector, sep.inputs[0])
            nt.links.new(sep.outputs[0], tex.inputs["W"])
        nt.links.new(vector, next(s for s in tex.inputs if s.identifier == "Vector"))
        emit = nt.nodes.new("ShaderNodeEmission")
        out = nt.nodes.new("ShaderNodeOutputMaterial")
        nt.links.new(tex.outputs[output], emit.inputs["Color"])
        nt.links.new(emit.outputs[0], out.inputs["Surface"])
        scenes.plane(scene, label, size=2.0, mat=mat).location = (2.0 * k, 0.0, 0.0)
    return scene


def pixel_points():
    """Object coordinates of the pixel centres of one tile, (TILE * TILE, 3), row 0 at the bottom."""
    c = -1.0 + 2.0 * (np.arange(TILE) + 0.5) / TILE
    y, x = np.meshgrid(c, c, indexing="ij")
    return np.stack([x.ravel(), y.ravel(), np.zeros(TILE * TILE)], -1).astype(np.float32)


def tile_errors(image, modes):
    """Per mode: (label, mean, median, fraction over 1e-3, max) of the per-pixel max channel
    error between the render and the mode's numpy, printed as a table."""
    pts = pixel_points()
    report = []
    for k, (label, *_rest, f) in enumerate(modes):
        got = image[:, k * TILE : (k + 1) * TILE, :3].reshape(-1, 3).astype(np.float64)
        expected = f(pts).astype(np.float64)
        err = np.abs(got - expected).max(axis=1)
        report.append((label, float(err.mean()), float(np.median(err)), float(np.mean(err > 1e-3)), float(err.max())))
    print(
        "\n".join(f"{r[0]:26s} mean {r[1]:.1e} median {r[2]:.1e} over 1e-3 {r[3]:.2%} max {r[4]:.1e}" for r in report)
    )
    return report
