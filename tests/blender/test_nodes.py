"""Compiled shader node trees (engine/scene/nodetree.py): each node family drives an Emission
shader on a grid of planes (devkit/node_scenes.py, one plane per mode, 8x8 pixels each, one
Penumbra sample at pixel centres), compared with its numpy twin (devkit/node_reference.py)
evaluated at each pixel's analytic UV; tolerances are stated at each assertion."""

import math

import bpy
import numpy as np
import pytest

from devkit import engines, node_reference, node_scenes, texture_reference
from devkit.render import render


def _penumbra(scene, samples=1):
    engines.configure(scene, "PENUMBRA")
    scene.penumbra.render_samples = samples
    return render(scene)["Combined"]


def _in(node, key):
    """A socket of ``node`` by identifier (stable across Blender lines; names are not)."""
    return next(s for s in node.inputs if s.identifier == key)


def _out(node, key):
    return next(s for s in node.outputs if s.identifier == key)


def _per_plane(grid, fn):
    """The reference image: ``fn(i, u, v)`` -> (n,) or (n, 3) values at plane i's pixels."""
    u, v, index = grid.uv()
    out = np.zeros(u.shape + (3,))
    for i in range(len(grid.cells)):
        mask = index == i
        value = np.asarray(fn(i, u[mask], v[mask]), np.float64)
        out[mask] = value[..., :3] if value.ndim == 2 else value[:, None]
    return out


def _assert_close(image, expected, grid, names, atol=2e-3, rtol=2e-3):
    _u, _v, index = grid.uv()
    got = image[..., :3].astype(np.float64)
    bad = ~np.isclose(got, expected, atol=atol, rtol=rtol)
    failed = sorted({names[i] for i in np.unique(index[bad.any(axis=-1)]) if i < len(names)})
    assert not failed, f"modes off: {failed}; worst {np.abs(got - expected).max():.4g}"


@pytest.mark.negative_inputs  # node outputs below zero on purpose (Subtract, Sine, curves, ...)
def test_math_every_operation(penumbra):
    """Math with A = 4u - 2, B = 4v - 1.9, C = 0.5 (pixel centres avoid whole numbers and
    ties between A and B): every
    operation equals the numpy reference within 2e-3 (absolute or relative)."""
    from penumbra.engine.scene.nodetree import MATH_OPS

    grid = node_scenes.grid(len(MATH_OPS))
    for cell, op in zip(grid.cells, MATH_OPS, strict=False):
        m = cell.nodes.new("ShaderNodeMath")
        m.operation = op
        cell.links.new(node_scenes.uv_input(cell, 0, 4.0, -2.0), m.inputs[0])
        cell.links.new(node_scenes.uv_input(cell, 1, 4.0, -1.9), m.inputs[1])
        m.inputs[2].default_value = 0.5
        cell.links.new(m.outputs[0], _in(cell.emission, "Color"))
    image = _penumbra(grid.scene)
    expected = _per_plane(grid, lambda i, u, v: node_reference.math(MATH_OPS[i], 4 * u - 2, 4 * v - 1.9, 0.5))
    _assert_close(image, expected, grid, MATH_OPS)


def _combine(cell, x, y, z, color=False):
    """A Combine XYZ (or Combine Color, RGB) of three sockets or constants: its output."""
    node = cell.nodes.new("ShaderNodeCombineColor" if color else "ShaderNodeCombineXYZ")
    for i, src in enumerate((x, y, z)):
        if isinstance(src, float | int):
            node.inputs[i].default_value = float(src)
        else:
            cell.links.new(src, node.inputs[i])
    return node.outputs[0]


def _uv_vector(cell, su=4.0, ou=-2.0, sv=4.0, ov=-1.9, z=0.7):
    return _combine(cell, node_scenes.uv_input(cell, 0, su, ou), node_scenes.uv_input(cell, 1, sv, ov), z)


@pytest.mark.negative_inputs  # node outputs below zero on purpose (Subtract, Sine, curves, ...)
def test_vector_math_every_operation(penumbra):
    """Vector Math with A = (4u - 2, 4v - 1.9, 0.7), B = (0.5, -1.3, 2), C = (0.3, 1, -1),
    Scale 1.5 (Refract's eta 0.6): every operation's Vector (or Value, for Dot Product,
    Distance, Length) equals the numpy reference within 2e-3."""
    from penumbra.engine.scene.nodetree import VECTOR_MATH_OPS, VECTOR_MATH_VALUE

    grid = node_scenes.grid(len(VECTOR_MATH_OPS))
    b, c = (0.5, -1.3, 2.0), (0.3, 1.0, -1.0)
    for cell, op in zip(grid.cells, VECTOR_MATH_OPS, strict=False):
        m = cell.nodes.new("ShaderNodeVectorMath")
        m.operation = op
        cell.links.new(_uv_vector(cell), m.inputs[0])
        m.inputs[1].default_value = b
        m.inputs[2].default_value = c
        _in(m, "Scale").default_value = 0.6 if op == "REFRACT" else 1.5
        out = _out(m, "Value" if op in VECTOR_MATH_VALUE else "Vector")
        cell.links.new(out, _in(cell.emission, "Color"))
    image = _penumbra(grid.scene)

    def ref(i, u, v):
        op = VECTOR_MATH_OPS[i]
        a = np.stack([4 * u - 2, 4 * v - 1.9, np.full_like(u, 0.7)], -1)
        vec, val = node_reference.vector_math(op, a, b, c, 0.6 if op == "REFRACT" else 1.5)
        return val if op in VECTOR_MATH_VALUE else vec

    _assert_close(image, _per_plane(grid, ref), grid, VECTOR_MATH_OPS)


@pytest.mark.negative_inputs  # node outputs below zero on purpose (Subtract, Sine, curves, ...)
def test_mix_color_every_blend_mode(penumbra):
    """Mix (Color) of A = (u, v, 0.3) and B = (0.6, 0.2 + 0.6 v, 0.9 u) at factor 0.7, every
    blend mode, the result clamped in every other mode: the numpy reference within 2e-3."""
    from penumbra.engine.scene.nodetree import BLEND_MODES

    grid = node_scenes.grid(len(BLEND_MODES))
    for k, (cell, mode) in enumerate(zip(grid.cells, BLEND_MODES, strict=False)):
        m = cell.nodes.new("ShaderNodeMix")
        m.data_type = "RGBA"
        m.blend_type = mode
        m.clamp_result = k % 2 == 1
        _in(m, "Factor_Float").default_value = 0.7
        a = _combine(cell, node_scenes.uv_input(cell, 0), node_scenes.uv_input(cell, 1), 0.3, color=True)
        bb = _combine(
            cell, 0.6, node_scenes.uv_input(cell, 1, 0.6, 0.2), node_scenes.uv_input(cell, 0, 0.9, 0.0), color=True
        )
        cell.links.new(a, _in(m, "A_Color"))
        cell.links.new(bb, _in(m, "B_Color"))
        cell.links.new(_out(m, "Result_Color"), cell.emission.inputs[0])
    image = _penumbra(grid.scene)

    def ref(i, u, v):
        a = np.stack([u, v, np.full_like(u, 0.3), np.ones_like(u)], -1)
        b = np.stack([np.full_like(u, 0.6), 0.2 + 0.6 * v, 0.9 * u, np.ones_like(u)], -1)
        return node_reference.mix_color(BLEND_MODES[i], 0.7, a, b, clamp_result=i % 2 == 1)

    _assert_close(image, _per_plane(grid, ref), grid, BLEND_MODES)


@pytest.mark.negative_inputs  # node outputs below zero on purpose (Subtract, Sine, curves, ...)
def test_map_range_clamp_and_float_mix(penumbra):
    """Map Range (each interpolation, clamped and not, from [0.2, 0.8] to [-1, 2], 3 steps), and
    the reversed source range; Clamp (Min Max and Range with min > max); Mix (Float) and Mix
    (Vector, non-uniform factor); Map Range (Vector, each interpolation, clamped): the numpy
    reference within 2e-3, value = 1.4u - 0.2."""
    from penumbra.engine.scene.nodetree import MAP_RANGE_TYPES

    cases = [(t, c, False) for t in MAP_RANGE_TYPES for c in (False, True)] + [(t, True, True) for t in MAP_RANGE_TYPES]
    cases += [("CLAMP", "MINMAX", False), ("CLAMP", "RANGE", False), ("MIX", "FLOAT", False), ("MIX", "VECTOR", False)]
    cases += [("VECTOR_RANGE", t, False) for t in MAP_RANGE_TYPES]
    grid = node_scenes.grid(len(cases))
    for cell, (kind, option, reverse) in zip(grid.cells, cases, strict=False):
        value = node_scenes.uv_input(cell, 0, 1.4, -0.2)
        if kind == "CLAMP":
            node = cell.nodes.new("ShaderNodeClamp")
            node.clamp_type = option
            _in(node, "Min").default_value = 0.7
            _in(node, "Max").default_value = 0.3
            cell.links.new(value, _in(node, "Value"))
            out = node.outputs[0]
        elif kind == "VECTOR_RANGE":
            node = cell.nodes.new("ShaderNodeMapRange")
            node.data_type = "FLOAT_VECTOR"
            node.interpolation_type = option
            node.clamp = True
            _in(node, "From_Min_FLOAT3").default_value = (0.2, 0.8, 0.0)
            _in(node, "From_Max_FLOAT3").default_value = (0.8, 0.2, 1.0)
            _in(node, "To_Min_FLOAT3").default_value = (-1.0, 0.0, 2.0)
            _in(node, "To_Max_FLOAT3").default_value = (2.0, 1.0, 1.0)
            _in(node, "Steps_FLOAT3").default_value = (3.0, 2.0, 4.0)
            cell.links.new(_combine(cell, value, value, value), _in(node, "Vector"))
            out = _out(node, "Vector")
        elif kind == "MIX":
            node = cell.nodes.new("ShaderNodeMix")
            node.data_type = option
            if option == "VECTOR":
                node.factor_mode = "NON_UNIFORM"
                node.clamp_factor = False
                cell.links.new(_combine(cell, value, 0.25, 0.9), _in(node, "Factor_Vector"))
                _in(node, "A_Vector").default_value = (0.1, 0.2, 0.3)
                _in(node, "B_Vector").default_value = (0.9, 0.6, -0.3)
                out = _out(node, "Result_Vector")
            else:
                cell.links.new(value, _in(node, "Factor_Float"))
                node.clamp_factor = False
                _in(node, "A_Float").default_value = 0.2
                _in(node, "B_Float").default_value = 0.9
                out = _out(node, "Result_Float")
        else:
            node = cell.nodes.new("ShaderNodeMapRange")
            node.interpolation_type = kind
            node.clamp = option
            lo, hi = (0.8, 0.2) if reverse else (0.2, 0.8)
            for i, x in enumerate((None, lo, hi, -1.0, 2.0, 3.0)):
                if x is not None:
                    node.inputs[i].default_value = x
            cell.links.new(value, node.inputs[0])
            out = node.outputs[0]
        cell.links.new(out, cell.emission.inputs[0])
    image = _penumbra(grid.scene)

    def ref(i, u, v):
        kind, option, reverse = cases[i]
        x = 1.4 * u - 0.2
        if kind == "CLAMP":
            return node_reference.clamp(option, x, 0.7, 0.3)
        if kind == "VECTOR_RANGE":
            rows = ((0.2, 0.8, -1.0, 2.0, 3.0), (0.8, 0.2, 0.0, 1.0, 2.0), (0.0, 1.0, 2.0, 1.0, 4.0))
            return np.stack([node_reference.map_range(option, x, *row, True) for row in rows], -1)
        if kind == "MIX":
            if option == "FLOAT":
                return 0.2 + x * (0.9 - 0.2)
            f = np.stack([x, np.full_like(x, 0.25), np.full_like(x, 0.9)], -1)
            return np.array([0.1, 0.2, 0.3]) + f * (np.array([0.9, 0.6, -0.3]) - np.array([0.1, 0.2, 0.3]))
        lo, hi = (0.8, 0.2) if reverse else (0.2, 0.8)
        return node_reference.map_range(kind, x, lo, hi, -1.0, 2.0, 3.0, option)

    _assert_close(image, _per_plane(grid, ref), grid, [str(c) for c in cases])


RAMP_STOPS = (
    (0.1, (0.9, 0.1, 0.1, 1.0)),
    (0.35, (0.1, 0.8, 0.2, 0.5)),
    (0.6, (0.2, 0.3, 0.9, 1.0)),
    (0.9, (1.0, 0.9, 0.2, 1.0)),
)


def test_color_ramp_every_interpolation_and_colour_mode(penumbra):
    """Color Ramp of four stops on Fac = 1.2u - 0.1 (before the first stop and past the last
    one): every interpolation in RGB, and HSV / HSL with each hue interpolation, equal the
    numpy reference within 2e-3."""
    from penumbra.engine.scene.nodetree import RAMP_HUE, RAMP_INTERPOLATIONS

    cases = [("RGB", i, "NEAR") for i in RAMP_INTERPOLATIONS] + [
        (m, "LINEAR", h) for m in ("HSV", "HSL") for h in RAMP_HUE
    ]
    grid = node_scenes.grid(len(cases))
    for cell, (mode, interp, hue) in zip(grid.cells, cases, strict=False):
        ramp = cell.nodes.new("ShaderNodeValToRGB")
        els = ramp.color_ramp.elements
        els[0].position, els[1].position = RAMP_STOPS[0][0], RAMP_STOPS[-1][0]
        els[0].color, els[1].color = RAMP_STOPS[0][1], RAMP_STOPS[-1][1]
        for pos, col in RAMP_STOPS[1:-1]:
            els.new(pos).color = col
        ramp.color_ramp.color_mode = mode
        ramp.color_ramp.interpolation = interp
        ramp.color_ramp.hue_interpolation = hue
        cell.links.new(node_scenes.uv_input(cell, 0, 1.2, -0.1), ramp.inputs[0])
        cell.links.new(ramp.outputs[0], cell.emission.inputs[0])
    image = _penumbra(grid.scene)

    def ref(i, u, v):
        mode, interp, hue = cases[i]
        pos = [p for p, _c in RAMP_STOPS]
        cols = [c for _p, c in RAMP_STOPS]
        return node_reference.color_ramp(1.2 * u - 0.1, pos, cols, interp, mode, hue)

    _assert_close(image, _per_plane(grid, ref), grid, [str(c) for c in cases])


def test_colour_adjustments_and_separate_combine(penumbra):
    """Hue/Saturation/Value, Invert, Gamma, Bright/Contrast on C = (u, v, 0.4); Separate Color
    and Combine Color in RGB, HSV and HSL (a round trip through each model, and the separated
    components themselves): the numpy reference within 2e-3."""
    cases = ["HSV", "INVERT", "GAMMA", "BRIGHT"] + [f"SEP_{m}" for m in ("RGB", "HSV", "HSL")]
    cases += [f"TRIP_{m}" for m in ("RGB", "HSV", "HSL")]
    grid = node_scenes.grid(len(cases))
    for cell, case in zip(grid.cells, cases, strict=False):
        col = _combine(cell, node_scenes.uv_input(cell, 0), node_scenes.uv_input(cell, 1), 0.4, color=True)
        if case == "HSV":
            node = cell.nodes.new("ShaderNodeHueSaturation")
            _in(node, "Hue").default_value = 0.3
            _in(node, "Saturation").default_value = 1.5
            _in(node, "Value").default_value = 0.8
            _in(node, "Fac").default_value = 0.9
        elif case == "INVERT":
            node = cell.nodes.new("ShaderNodeInvert")
            _in(node, "Fac").default_value = 0.75
        elif case == "GAMMA":
            node = cell.nodes.new("ShaderNodeGamma")
            _in(node, "Gamma").default_value = 2.2
        elif case == "BRIGHT":
            node = cell.nodes.new("ShaderNodeBrightContrast")
            _in(node, "Bright").default_value = 0.1
            _in(node, "Contrast").default_value = 0.5
        if case in {"HSV", "INVERT", "GAMMA", "BRIGHT"}:
            cell.links.new(col, _in(node, "Color"))
            cell.links.new(node.outputs[0], cell.emission.inputs[0])
            continue
        sep = cell.nodes.new("ShaderNodeSeparateColor")
        sep.mode = case[-3:]
        cell.links.new(col, sep.inputs[0])
        if case.startswith("SEP"):
            out = _combine(cell, sep.outputs[0], sep.outputs[1], sep.outputs[2])
        else:
            comb = cell.nodes.new("ShaderNodeCombineColor")
            comb.mode = case[-3:]
            for k in range(3):
                cell.links.new(sep.outputs[k], comb.inputs[k])
            out = comb.outputs[0]
        cell.links.new(out, cell.emission.inputs[0])
    image = _penumbra(grid.scene)
    r = node_reference

    def ref(i, u, v):
        c = np.stack([u, v, np.full_like(u, 0.4), np.ones_like(u)], -1)
        case = cases[i]
        table = {
            "HSV": lambda: r.hue_saturation(0.3, 1.5, 0.8, 0.9, c),
            "INVERT": lambda: r.invert(0.75, c),
            "GAMMA": lambda: r.gamma(c, 2.2),
            "BRIGHT": lambda: r.bright_contrast(c, 0.1, 0.5),
            "SEP_RGB": lambda: c,
            "SEP_HSV": lambda: r.rgb_to_hsv(c),
            "SEP_HSL": lambda: r.rgb_to_hsl(c),
        }
        return table[case]() if case in table else c

    _assert_close(image, _per_plane(grid, ref), grid, cases)


def _planes_xy(grid):
    """World (x, y) of every plane's centre."""
    return [tuple(cell.ob.location[:2]) for cell in grid.cells]


@pytest.mark.negative_inputs  # node outputs below zero on purpose (Subtract, Sine, curves, ...)
def test_coordinates_and_geometry(penumbra):
    """Texture Coordinate (every output), Geometry, Object Info Location, UV Map and Mapping
    (each type, rotated and scaled) on planes facing the camera: the analytic value at each
    pixel within 2e-3 (Window: the pixel's place in the frame; Camera: camera space with +z
    ahead, as Blender's)."""
    coords = ["Generated", "Normal", "UV", "Object", "Camera", "Window", "Reflection"]
    geometry = ["Position", "Normal", "True Normal", "Incoming", "Backfacing"]
    cases = [("COORD", c) for c in coords] + [("GEOM", g) for g in geometry] + [("INFO", "Location"), ("UVMAP", "UV")]
    cases += [("MAPPING", t) for t in ("POINT", "TEXTURE", "VECTOR", "NORMAL")]
    grid = node_scenes.grid(len(cases))
    loc, rot, scale = (0.1, -0.2, 0.3), (0.3, 0.5, 0.7), (1.5, 0.8, 2.0)
    for cell, (kind, name) in zip(grid.cells, cases, strict=False):
        if kind == "COORD":
            out = _out(cell.nodes.new("ShaderNodeTexCoord"), name)
        elif kind == "GEOM":
            out = _out(cell.nodes.new("ShaderNodeNewGeometry"), name)
        elif kind == "INFO":
            out = _out(cell.nodes.new("ShaderNodeObjectInfo"), name)
        elif kind == "UVMAP":
            node = cell.nodes.new("ShaderNodeUVMap")
            node.uv_map = "UVMap"
            out = node.outputs[0]
        else:
            node = cell.nodes.new("ShaderNodeMapping")
            node.vector_type = name
            _in(node, "Location").default_value = loc
            _in(node, "Rotation").default_value = rot
            _in(node, "Scale").default_value = scale
            cell.links.new(_out(cell.nodes.new("ShaderNodeTexCoord"), "UV"), _in(node, "Vector"))
            out = node.outputs[0]
        cell.links.new(out, _in(cell.emission, "Color"))
    image = _penumbra(grid.scene)
    centres = _planes_xy(grid)
    width = float(max(grid.cols, grid.rows))
    height = width * grid.rows / grid.cols

    def ref(i, u, v):
        kind, name = cases[i]
        x, y = centres[i][0] + u - 0.5, centres[i][1] + v - 0.5
        zero, one = np.zeros_like(u), np.ones_like(u)
        up = np.stack([zero, zero, one], -1)
        uv = np.stack([u, v, zero], -1)
        if kind == "MAPPING":
            return node_reference.mapping(name, uv, loc, rot, scale)
        table = {
            "Generated": np.stack([u, v, one * 0.5], -1),
            "Normal": up,
            "UV": uv,
            "Object": np.stack([u - 0.5, v - 0.5, zero], -1),
            "Camera": np.stack([x, y, one * 10.0], -1),
            "Window": np.stack([x / width + 0.5, y / height + 0.5, zero], -1),
            "Reflection": up,
            "Position": np.stack([x, y, zero], -1),
            "True Normal": up,
            "Incoming": up,
            "Backfacing": zero,
            "Location": np.stack([one * centres[i][0], one * centres[i][1], zero], -1),
        }
        return table[name]

    _assert_close(image, _per_plane(grid, ref), grid, [str(c) for c in cases])


def test_checker_gradient_and_input_nodes(penumbra):
    """Checker (Scale 3 on UV, and on Generated when its Vector is unlinked; Fac and Color) and
    Gradient (every type, on 2 UV - 1); Fresnel and Layer Weight on a plane the camera faces
    (N.V = 1): the numpy reference within 2e-3."""
    from penumbra.engine.scene.nodetree import GRADIENT_TYPES

    cases = [("CHECKER", "UV"), ("CHECKER", "GENERATED"), ("CHECKER", "COLOR")]
    cases += [("GRADIENT", t) for t in GRADIENT_TYPES] + [("FRESNEL", 1.45), ("FRESNEL", 2.5)]
    cases += [("LAYER", "Fresnel"), ("LAYER", "Facing")]
    grid = node_scenes.grid(len(cases))
    colours = ((0.9, 0.2, 0.1, 1.0), (0.1, 0.3, 0.8, 1.0))
    for cell, (kind, option) in zip(grid.cells, cases, strict=False):
        if kind == "CHECKER":
            node = cell.nodes.new("ShaderNodeTexChecker")
            _in(node, "Scale").default_value = 3.0
            _in(node, "Color1").default_value = colours[0]
            _in(node, "Color2").default_value = colours[1]
            if option != "GENERATED":
                cell.links.new(_out(cell.nodes.new("ShaderNodeTexCoord"), "UV"), _in(node, "Vector"))
            out = _out(node, "Color" if option == "COLOR" else "Fac")
        elif kind == "GRADIENT":
            node = cell.nodes.new("ShaderNodeTexGradient")
            node.gradient_type = option
            cell.links.new(_uv_vector(cell, 2.0, -1.0, 2.0, -1.0, 0.0), _in(node, "Vector"))
            out = _out(node, "Fac")
        elif kind == "FRESNEL":
            node = cell.nodes.new("ShaderNodeFresnel")
            _in(node, "IOR").default_value = option
            out = node.outputs[0]
        else:
            node = cell.nodes.new("ShaderNodeLayerWeight")
            _in(node, "Blend").default_value = 0.3
            out = _out(node, option)
        cell.links.new(out, _in(cell.emission, "Color"))
    image = _penumbra(grid.scene)

    def ref(i, u, v):
        kind, option = cases[i]
        zero = np.zeros_like(u)
        if kind == "CHECKER":
            z = zero + (0.5 if option == "GENERATED" else 0.0)
            t = texture_reference.node_tex_checker(np.stack([u, v, z], -1), colours[0][:3], colours[1][:3], 3.0)
            return t[:, :3] if option == "COLOR" else t[:, 3]
        if kind == "GRADIENT":
            p = np.stack([2 * u - 1, 2 * v - 1, zero], -1)
            return texture_reference.node_tex_gradient(p, GRADIENT_TYPES.index(option))[:, 3]
        if kind == "FRESNEL":
            return node_reference.fresnel_dielectric(1.0, option) + zero
        fresnel, facing = node_reference.layer_weight(0.3, 1.0)
        return (fresnel if option == "Fresnel" else facing) + zero

    _assert_close(image, _per_plane(grid, ref), grid, [str(c) for c in cases])


def _group(name, build):
    """A shader node group: ``build(tree, group_input, group_output)`` fills it."""
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    gin, gout = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    build(tree, gin, gout)
    return tree


def _socket(tree, name, in_out, kind="NodeSocketFloat", default=None):
    item = tree.interface.new_socket(name, in_out=in_out, socket_type=kind)
    if default is not None:
        item.default_value = default
    return item


def test_groups_reroutes_and_muted_nodes(penumbra):
    """Nested node groups (an inner group's input left unlinked reads the value on its group
    node), reroutes, a muted node (its first input passed through), a muted link (the socket's
    own value): what Blender computes, within 2e-3."""

    def inner(tree, gin, gout):
        _socket(tree, "A", "INPUT")
        _socket(tree, "B", "INPUT", default=0.5)
        _socket(tree, "Out", "OUTPUT")
        m = tree.nodes.new("ShaderNodeMath")
        m.operation = "MULTIPLY"
        tree.links.new(gin.outputs[0], m.inputs[0])
        tree.links.new(gin.outputs[1], m.inputs[1])
        tree.links.new(m.outputs[0], gout.inputs[0])

    cases = ["GROUPS", "REROUTE", "MUTED_NODE", "MUTED_LINK"]
    grid = node_scenes.grid(len(cases))  # a fresh file: the groups come after it
    inner_tree = _group("Inner", inner)

    def outer(tree, gin, gout):
        _socket(tree, "X", "INPUT")
        _socket(tree, "Y", "OUTPUT")
        g = tree.nodes.new("ShaderNodeGroup")
        g.node_tree = inner_tree
        g.inputs[1].default_value = 0.25
        add = tree.nodes.new("ShaderNodeMath")
        add.inputs[1].default_value = 0.1
        tree.links.new(gin.outputs[0], g.inputs[0])
        tree.links.new(g.outputs[0], add.inputs[0])
        tree.links.new(add.outputs[0], gout.inputs[0])

    outer_tree = _group("Outer", outer)
    for cell, case in zip(grid.cells, cases, strict=False):
        u = node_scenes.uv_input(cell, 0)
        target = _in(cell.emission, "Color")
        if case == "GROUPS":
            g = cell.nodes.new("ShaderNodeGroup")
            g.node_tree = outer_tree
            cell.links.new(u, g.inputs[0])
            cell.links.new(g.outputs[0], target)
        elif case == "REROUTE":
            r1, r2 = cell.nodes.new("NodeReroute"), cell.nodes.new("NodeReroute")
            cell.links.new(u, r1.inputs[0])
            cell.links.new(r1.outputs[0], r2.inputs[0])
            cell.links.new(r2.outputs[0], target)
        elif case == "MUTED_NODE":
            m = cell.nodes.new("ShaderNodeMath")
            m.operation = "POWER"
            cell.links.new(u, m.inputs[0])
            m.mute = True
            cell.links.new(m.outputs[0], target)
        else:
            target.default_value = (0.3, 0.6, 0.9, 1.0)
            link = cell.links.new(u, target)
            link.is_muted = True
    image = _penumbra(grid.scene)

    def ref(i, u, v):
        return {
            "GROUPS": u * 0.25 + 0.1,
            "REROUTE": u,
            "MUTED_NODE": u,
            "MUTED_LINK": np.tile([0.3, 0.6, 0.9], (len(u), 1)),
        }[cases[i]]

    _assert_close(image, _per_plane(grid, ref), grid, cases)


def _messages(mat):
    from penumbra.engine.scene.materials import material_from_blender

    return material_from_blender(mat)


def test_bad_trees_fall_back_by_input_with_one_message(penumbra, capfd):
    """An unknown node (Light Path) into a Mix Shader's factor falls back for that factor only;
    a group node whose group is gone, a group that contains itself (a broken file) and a
    2000-node chain each give one clear message and a finite frame."""
    grid = node_scenes.grid(4)
    light_path, missing, recursive, huge = (cell.mat for cell in grid.cells)

    # 1: Light Path -> Mix Shader factor (default 0.5 used); the mixed sides still compile.
    cell = grid.cells[0]
    mix = cell.nodes.new("ShaderNodeMixShader")
    _in(mix, "Fac").default_value = 0.5
    red = cell.nodes.new("ShaderNodeEmission")
    _in(red, "Color").default_value = (1.0, 0.0, 0.0, 1.0)
    cell.links.new(_out(cell.nodes.new("ShaderNodeLightPath"), "Is Camera Ray"), _in(mix, "Fac"))
    cell.links.new(red.outputs[0], mix.inputs[1])
    cell.links.new(cell.emission.outputs[0], mix.inputs[2])
    cell.links.new(node_scenes.uv_input(cell, 0), _in(cell.emission, "Color"))
    cell.links.new(mix.outputs[0], _in(cell.output, "Surface"))
    read = _messages(light_path)
    assert read.tree is not None and read.tree.fallbacks == 1
    assert len(read.messages) == 1 and "Light Path" in read.messages[0] and "'Node000'" in read.messages[0]

    # 2: a group node without its group.
    cell = grid.cells[1]
    gone = _group("Gone", lambda t, i, o: _socket(t, "V", "OUTPUT"))
    g = cell.nodes.new("ShaderNodeGroup")
    g.node_tree = gone
    cell.links.new(g.outputs[0], _in(cell.emission, "Color"))
    cell.links.new(node_scenes.uv_input(cell, 1), _in(cell.emission, "Strength"))
    bpy.data.node_groups.remove(gone)
    read = _messages(missing)
    if g.outputs and g.outputs[0].is_linked:  # Blender drops the sockets (and links) with the group
        assert any("without its node group" in m for m in read.messages), read.messages

    # 3: a group containing itself. Blender's own API refuses to build one, as a broken file
    # may hold it: where it refuses, a group of a group of itself is tried the same way.
    cell = grid.cells[2]
    loop = _group("Loop", lambda t, i, o: _socket(t, "V", "OUTPUT"))
    inside = loop.nodes.new("ShaderNodeGroup")
    try:
        inside.node_tree = loop
        built = inside.node_tree == loop
    except (TypeError, RuntimeError, ValueError):
        built = False
    if built:
        loop.links.new(inside.outputs[0], loop.nodes["Group Output"].inputs[0])
    g = cell.nodes.new("ShaderNodeGroup")
    g.node_tree = loop
    cell.links.new(g.outputs[0], _in(cell.emission, "Color"))
    cell.links.new(node_scenes.uv_input(cell, 1), _in(cell.emission, "Strength"))
    read = _messages(recursive)
    if built:
        assert any("contains itself" in m for m in read.messages), read.messages

    # 4: 2000 Math nodes in a row: 50 group nodes in a chain, each a group of 40 (Blender
    # itself takes half a minute to build 2000 nodes in one tree).
    cell = grid.cells[3]

    def forty(tree, gin, gout):
        _socket(tree, "V", "INPUT")
        _socket(tree, "V", "OUTPUT")
        src = gin.outputs[0]
        for _ in range(40):
            m = tree.nodes.new("ShaderNodeMath")
            m.inputs[1].default_value = 0.0001
            tree.links.new(src, m.inputs[0])
            src = m.outputs[0]
        tree.links.new(src, gout.inputs[0])

    block = _group("Forty", forty)
    src = node_scenes.uv_input(cell, 0)
    for _ in range(50):
        g = cell.nodes.new("ShaderNodeGroup")
        g.node_tree = block
        cell.links.new(src, g.inputs[0])
        src = g.outputs[0]
    cell.links.new(src, _in(cell.emission, "Color"))
    read = _messages(huge)
    assert any("too large to compile" in m for m in read.messages), read.messages

    image = _penumbra(grid.scene)
    assert np.isfinite(image).all()
    out = capfd.readouterr().out
    assert out.count("Light Path") == 1, out


@pytest.mark.negative_inputs  # node outputs below zero on purpose (Subtract, Sine, curves, ...)
def test_extreme_inputs_draw_finite(penumbra):
    """NaN, +-1e30 and zero or negative scales through Math, Vector Math, Mapping, Color Ramp
    and Map Range: every pixel finite."""
    cases = ["DIV0", "HUGE", "NEGHUGE", "NAN", "MAPZERO", "MAPNEG", "RAMP", "RANGE"]
    grid = node_scenes.grid(len(cases))
    for cell, case in zip(grid.cells, cases, strict=False):
        target = _in(cell.emission, "Color")
        if case in {"DIV0", "HUGE", "NEGHUGE", "NAN"}:
            m = cell.nodes.new("ShaderNodeMath")
            m.operation = {"DIV0": "DIVIDE", "HUGE": "POWER", "NEGHUGE": "MULTIPLY", "NAN": "SQRT"}[case]
            m.inputs[0].default_value = {"DIV0": 1.0, "HUGE": 1e30, "NEGHUGE": -1e30, "NAN": -1.0}[case]
            m.inputs[1].default_value = {"DIV0": 0.0, "HUGE": 1e30, "NEGHUGE": 1e30, "NAN": 0.0}[case]
            out = m.outputs[0]
        elif case.startswith("MAP"):
            node = cell.nodes.new("ShaderNodeMapping")
            node.vector_type = "TEXTURE" if case == "MAPZERO" else "NORMAL"
            _in(node, "Scale").default_value = (0.0, 0.0, 0.0) if case == "MAPZERO" else (-1e30, -2.0, 0.0)
            cell.links.new(_out(cell.nodes.new("ShaderNodeTexCoord"), "UV"), _in(node, "Vector"))
            out = node.outputs[0]
        elif case == "RAMP":
            node = cell.nodes.new("ShaderNodeValToRGB")
            node.inputs[0].default_value = float("nan")
            out = node.outputs[0]
        else:
            node = cell.nodes.new("ShaderNodeMapRange")
            node.inputs[1].default_value = 1e30
            node.inputs[2].default_value = -1e30
            cell.links.new(node_scenes.uv_input(cell, 0), node.inputs[0])
            out = node.outputs[0]
        cell.links.new(out, target)
    image = _penumbra(grid.scene)
    assert np.isfinite(image).all()


def test_trees_differing_in_values_share_one_program(penumbra, gpu_call):
    """1000 materials of one structure and different values compile to one key (a Math node's
    value; a Noise texture's Scale); drawn, a second scene of other values compiles no program,
    while another operation compiles one."""
    from penumbra.engine.scene.nodetree import compile_material

    mats = []
    for k in range(1000):
        mat, nodes, links, emission, _output = node_scenes.emission_material(f"Same{k:04d}")
        m = nodes.new("ShaderNodeMath")
        m.operation = "MULTIPLY"
        m.inputs[1].default_value = k / 1000.0
        links.new(_out(nodes.new("ShaderNodeTexCoord"), "UV"), m.inputs[0])
        links.new(m.outputs[0], _in(emission, "Color"))
        mats.append(mat)
    trees = [compile_material(m)[0] for m in mats]
    assert len({t.key for t in trees}) == 1
    assert len({float(t.constants[0, 0]) for t in trees}) == 1000  # the values differ, as constants
    noise = []
    for k in range(1000):  # a Noise texture (4D, so Vector and W) differing only in Scale
        mat, nodes, links, emission, _output = node_scenes.emission_material(f"Noise{k:04d}")
        n = nodes.new("ShaderNodeTexNoise")
        n.noise_dimensions = "4D"
        _in(n, "Scale").default_value = 1.0 + k / 100.0
        links.new(_out(n, "Color"), _in(emission, "Color"))
        noise.append(compile_material(mat)[0])
    assert len({t.key for t in noise}) == 1 and noise[0].key != trees[0].key
    assert len({t.constants.tobytes() for t in noise}) == 1000

    from devkit.render import engine_frame

    def scene_of(values, ops=("MULTIPLY",)):
        grid = node_scenes.grid(len(values))
        for k, (cell, value) in enumerate(zip(grid.cells, values, strict=False)):
            m = cell.nodes.new("ShaderNodeMath")
            m.operation = ops[k % len(ops)]
            m.inputs[1].default_value = value
            cell.links.new(node_scenes.uv_input(cell, 0), m.inputs[0])
            cell.links.new(m.outputs[0], _in(cell.emission, "Color"))
        engines.configure(grid.scene, "PENUMBRA")
        return grid.scene

    one, _ = engine_frame(gpu_call, scene_of([0.5]), 16, 16)
    many, image = engine_frame(gpu_call, scene_of([0.1 * k for k in range(16)]), 32, 32)
    assert many.shaders_compiled == one.shaders_compiled, (one.shaders_compiled, many.shaders_compiled)
    assert len(np.unique(np.round(image[..., 0], 3))) > 16  # the values did reach the planes
    two, _ = engine_frame(gpu_call, scene_of([0.5, 0.5], ("MULTIPLY", "ADD")), 16, 16)
    assert two.shaders_compiled == one.shaders_compiled + 1
    # (FrameStats.compile_seconds, the time those programs took, is the benchmark's to report.)


# --- asset-like trees against EEVEE -------------------------------------------------------


def _principled_in_group(mat, nodes, links, bsdf, output):
    """A Principled BSDF inside a node group (inside another group), its Base Color and
    Roughness group inputs: one linked from an RGB node, one left at the group node's value."""

    def inner(tree, gin, gout):
        p = tree.nodes.new("ShaderNodeBsdfPrincipled")
        tree.links.new(gin.outputs[0], _in(p, "Base Color"))
        tree.links.new(gin.outputs[1], _in(p, "Roughness"))
        _in(p, "Specular IOR Level").default_value = 0.5
        tree.links.new(p.outputs[0], gout.inputs[0])

    inner_tree = node_scenes.shader_group(
        "PBR", [("Color", "NodeSocketColor", (0.8, 0.8, 0.8, 1.0)), ("Rough", "NodeSocketFloat", 0.5)], inner
    )

    def outer(tree, gin, gout):
        g = tree.nodes.new("ShaderNodeGroup")
        g.node_tree = inner_tree
        g.inputs[1].default_value = 0.35
        tree.links.new(gin.outputs[0], g.inputs[0])
        tree.links.new(g.outputs[0], gout.inputs[0])

    outer_tree = node_scenes.shader_group("Wrapper", [("Color", "NodeSocketColor", None)], outer)
    g = nodes.new("ShaderNodeGroup")
    g.node_tree = outer_tree
    rgb = nodes.new("ShaderNodeRGB")
    rgb.outputs[0].default_value = (0.7, 0.25, 0.1, 1.0)
    links.new(rgb.outputs[0], g.inputs[0])
    links.new(g.outputs[0], _in(output, "Surface"))


def _ramp_on_gradient_into_roughness(mat, nodes, links, bsdf, output):
    """Gradient (Generated, linear along x) -> Color Ramp -> Roughness, and a second ramp
    (Ease) of the same gradient -> Base Color; Metallic 0.6 so roughness shows."""
    grad = nodes.new("ShaderNodeTexGradient")
    rough = nodes.new("ShaderNodeValToRGB")
    rough.color_ramp.elements[0].color = (0.05, 0.05, 0.05, 1.0)
    rough.color_ramp.elements[1].color = (0.9, 0.9, 0.9, 1.0)
    color = nodes.new("ShaderNodeValToRGB")
    color.color_ramp.interpolation = "EASE"
    color.color_ramp.elements[0].color = (0.8, 0.1, 0.1, 1.0)
    color.color_ramp.elements[1].color = (0.1, 0.3, 0.9, 1.0)
    links.new(_out(grad, "Fac"), rough.inputs[0])
    links.new(_out(grad, "Fac"), color.inputs[0])
    links.new(rough.outputs[0], _in(bsdf, "Roughness"))
    links.new(color.outputs[0], _in(bsdf, "Base Color"))
    _in(bsdf, "Metallic").default_value = 0.6


def _mix_shader_by_checker(mat, nodes, links, bsdf, output):
    """Mix Shader whose factor is a Checker (Generated, scale 4): a red Principled and a blue
    Diffuse BSDF."""
    _in(bsdf, "Base Color").default_value = (0.8, 0.15, 0.1, 1.0)
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    _in(diffuse, "Color").default_value = (0.1, 0.3, 0.8, 1.0)
    checker = nodes.new("ShaderNodeTexChecker")
    _in(checker, "Scale").default_value = 4.0
    mix = nodes.new("ShaderNodeMixShader")
    links.new(_out(checker, "Fac"), mix.inputs[0])
    links.new(bsdf.outputs[0], mix.inputs[1])
    links.new(diffuse.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], _in(output, "Surface"))


def _add_shader_rim(mat, nodes, links, bsdf, output):
    """Add Shader of a Principled BSDF and an Emission whose strength is Layer Weight's
    Facing: a glowing rim."""
    _in(bsdf, "Base Color").default_value = (0.3, 0.5, 0.3, 1.0)
    emission = nodes.new("ShaderNodeEmission")
    _in(emission, "Color").default_value = (1.0, 0.6, 0.2, 1.0)
    weight = nodes.new("ShaderNodeLayerWeight")
    _in(weight, "Blend").default_value = 0.4
    links.new(_out(weight, "Facing"), _in(emission, "Strength"))
    add = nodes.new("ShaderNodeAddShader")
    links.new(bsdf.outputs[0], add.inputs[0])
    links.new(emission.outputs[0], add.inputs[1])
    links.new(add.outputs[0], _in(output, "Surface"))


def _ramp_on_noise(mat, nodes, links, bsdf, output):
    """Noise (Generated, Scale 4, Detail 3) -> Color Ramp -> Roughness, and a second ramp of
    the same noise -> Base Color; Metallic 0.5 so roughness shows."""
    noise = nodes.new("ShaderNodeTexNoise")
    _in(noise, "Scale").default_value = 4.0
    _in(noise, "Detail").default_value = 3.0
    rough, color = nodes.new("ShaderNodeValToRGB"), nodes.new("ShaderNodeValToRGB")
    rough.color_ramp.elements[0].position = 0.35
    rough.color_ramp.elements[1].position = 0.65
    rough.color_ramp.elements[0].color = (0.1, 0.1, 0.1, 1.0)
    color.color_ramp.elements[0].position = 0.3
    color.color_ramp.elements[1].position = 0.7
    color.color_ramp.elements[0].color = (0.8, 0.25, 0.05, 1.0)
    color.color_ramp.elements[1].color = (0.1, 0.5, 0.3, 1.0)
    links.new(_out(noise, "Fac"), rough.inputs[0])
    links.new(_out(noise, "Fac"), color.inputs[0])
    links.new(rough.outputs[0], _in(bsdf, "Roughness"))
    links.new(color.outputs[0], _in(bsdf, "Base Color"))
    _in(bsdf, "Metallic").default_value = 0.5


def _bump_from_voronoi(mat, nodes, links, bsdf, output):
    """Voronoi (Generated, Scale 6, F1 Distance) -> Bump (Strength 0.6, Distance 0.05) -> the
    Principled Normal; Base Color its Color."""
    voronoi = nodes.new("ShaderNodeTexVoronoi")
    _in(voronoi, "Scale").default_value = 6.0
    bump = nodes.new("ShaderNodeBump")
    _in(bump, "Strength").default_value = 0.6
    _in(bump, "Distance").default_value = 0.05
    links.new(_out(voronoi, "Distance"), _in(bump, "Height"))
    links.new(_out(bump, "Normal"), _in(bsdf, "Normal"))
    links.new(_out(voronoi, "Color"), _in(bsdf, "Base Color"))


# name -> (builder, bound on the mean |difference| from EEVEE); measured on 5.2 and 4.5:
# 0.0017, 0.0035, 0.0080, 0.0067, 0.0063, 0.0092 (the bounds sit 2-3x above; the issue asks
# for 0.05).
ASSETS = {
    "principled_in_group": (_principled_in_group, 0.005),
    "ramp_into_roughness": (_ramp_on_gradient_into_roughness, 0.01),
    "mix_shader_by_checker": (_mix_shader_by_checker, 0.02),
    "add_shader_rim": (_add_shader_rim, 0.015),
    "ramp_on_noise": (_ramp_on_noise, 0.015),
    "bump_from_voronoi": (_bump_from_voronoi, 0.02),
}


@pytest.mark.parametrize("name", list(ASSETS))
def test_asset_like_trees_match_eevee(penumbra, name):
    """Trees as asset libraries build them, on a sphere under a sun (48x48): Penumbra at 8
    samples within the bound of ASSETS (mean |difference|) of EEVEE (16 samples), and the
    tree compiled whole."""
    from penumbra.engine.scene.materials import material_from_blender

    build, bound = ASSETS[name]
    scene = node_scenes.sphere(48, 48, build)
    from penumbra.engine.scene.materials import summary

    read = material_from_blender(bpy.data.materials["Asset"])
    assert read.tree is not None and read.tree.fallbacks == 0, read.messages
    assert summary(read)[0][0] == "NODETREE"  # the Material panel says it is compiled
    ours = _penumbra(scene, samples=8)
    engines.configure(scene, "EEVEE")
    ref = render(scene)["Combined"]
    diff = np.abs(ours[..., :3] - ref[..., :3]).mean()
    assert diff < bound, diff


def test_an_image_feeds_any_node(penumbra):
    """An Image Texture (the 4x4 sRGB checker of material_scenes, its alpha 1 / 0.25 by cell)
    through Invert, and its Alpha through Math Multiply 0.5, both into Emission; and through a
    Mapping node (scale 2) read by its Vector: each checker cell's centre is the decoded texel
    so transformed, within 1e-3."""
    from devkit import material_scenes as ms

    grid = node_scenes.grid(3, block=32)
    pixels = ms.checker(4, 4, (*ms.CHECKER_A, 1.0), (*ms.CHECKER_B, 0.25))
    img = ms.image("NodeChecker", pixels)
    for k, cell in enumerate(grid.cells):
        tex = cell.nodes.new("ShaderNodeTexImage")
        tex.image = img
        tex.interpolation = "Closest"
        if k == 0:
            inv = cell.nodes.new("ShaderNodeInvert")
            cell.links.new(_out(tex, "Color"), _in(inv, "Color"))
            cell.links.new(inv.outputs[0], _in(cell.emission, "Color"))
        elif k == 1:
            m = cell.nodes.new("ShaderNodeMath")
            m.operation = "MULTIPLY"
            m.inputs[1].default_value = 0.5
            cell.links.new(_out(tex, "Alpha"), m.inputs[0])
            cell.links.new(m.outputs[0], _in(cell.emission, "Color"))
        else:
            mapping = cell.nodes.new("ShaderNodeMapping")
            _in(mapping, "Scale").default_value = (2.0, 2.0, 1.0)
            cell.links.new(_out(cell.nodes.new("ShaderNodeTexCoord"), "UV"), _in(mapping, "Vector"))
            cell.links.new(mapping.outputs[0], _in(tex, "Vector"))
            cell.links.new(_out(tex, "Color"), _in(cell.emission, "Color"))
    image = _penumbra(grid.scene)
    # The GPU decodes the sRGB texels: exact within half a code step (``srgb_decode_tolerance``).
    a, b = ms.srgb_decoded(ms.CHECKER_A), ms.srgb_decoded(ms.CHECKER_B)
    tol_a = ms.srgb_decode_tolerance(ms.CHECKER_A) + 1e-4
    tol_b = ms.srgb_decode_tolerance(ms.CHECKER_B) + 1e-4
    for i in range(4):
        for j in range(4):
            first = (i + j) % 2 == 0
            row, col = j * 8 + 4, i * 8 + 4
            assert np.all(np.abs(image[row, col, :3] - (1.0 - (a if first else b))) <= (tol_a if first else tol_b))
            np.testing.assert_allclose(image[row, 32 + col, :3], 0.5 * (1.0 if first else 0.25), atol=1e-3)
            # Mapping scales UV by 2: this cell's centre reads cell (2i, 2j) mod 4, always the first colour
            assert np.all(np.abs(image[32 + row, col, :3] - a) <= tol_a)


def test_a_normal_map_stays_on_a_compiled_tree(penumbra):
    """material_scenes' normal_map with a Math node (Add 0) between a Value and Roughness, which
    only the compiler reads: the tree compiles and the normal map still tilts the normal as
    the reader's path draws it (within 1e-3)."""
    from devkit import material_scenes as ms
    from penumbra.engine.scene.materials import material_from_blender

    def plane(compiled):
        scene = ms.normal_map(32, 32)
        mat = next(ob for ob in scene.objects if ob.type == "MESH").material_slots[0].material
        if compiled:
            nodes, links = mat.node_tree.nodes, mat.node_tree.links
            bsdf = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
            value, add = nodes.new("ShaderNodeValue"), nodes.new("ShaderNodeMath")
            value.outputs[0].default_value = _in(bsdf, "Roughness").default_value
            add.inputs[1].default_value = 0.0
            links.new(value.outputs[0], add.inputs[0])
            links.new(add.outputs[0], _in(bsdf, "Roughness"))
            read = material_from_blender(mat)
            assert read.tree is not None and "normal" in read.textures, read.messages
        return _penumbra(scene, samples=1)

    np.testing.assert_allclose(plane(True), plane(False), atol=1e-3)


def test_a_procedural_alpha_casts_the_shadow_it_draws(penumbra):
    """material_scenes' alpha_checker_shadow with its alpha from a Checker texture (UV, Scale
    4: the same 4x4 cells, opaque where i + j is odd) instead of the image: the compiled tree
    runs in the shadow pass, so the ground is shadowed exactly under the opaque cells (pixels
    more than 1.5 pixels from a cell edge)."""
    from devkit import material_scenes as ms
    from penumbra.engine.scene.materials import material_from_blender

    size = 64
    scene = ms.alpha_checker_shadow(size, size)
    mat = scene.objects["Checker"].material_slots[0].material
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    checker = nodes.new("ShaderNodeTexChecker")
    _in(checker, "Scale").default_value = 4.0
    links.new(_out(nodes.new("ShaderNodeTexCoord"), "UV"), _in(checker, "Vector"))
    links.new(_out(checker, "Fac"), _in(bsdf, "Alpha"))
    read = material_from_blender(mat)
    assert read.tree is not None and read.tree.transparent and read.uses_alpha, read.messages
    image = _penumbra(scene, samples=1)[..., :3].mean(axis=-1)
    view, cells, side = scene["view_size"], scene["checker_cells"], scene["checker_size"]
    centres = ((np.arange(size) + 0.5) / size - 0.5) * view
    gx, gy = np.meshgrid(centres, centres)
    inside = (np.abs(gx) < side / 2) & (np.abs(gy) < side / 2)
    i = np.floor((gx + side / 2) / (side / cells)).astype(int)
    j = np.floor((gy + side / 2) / (side / cells)).astype(int)
    shadowed = inside & ((i + j) % 2 == 1)
    cell, pixel = side / cells, view / size
    fx, fy = np.mod(gx + side / 2, cell), np.mod(gy + side / 2, cell)
    near_edge = (np.minimum(fx, cell - fx) < 1.5 * pixel) | (np.minimum(fy, cell - fy) < 1.5 * pixel)
    near_edge |= (np.abs(np.abs(gx) - side / 2) < 1.5 * pixel) | (np.abs(np.abs(gy) - side / 2) < 1.5 * pixel)
    lit_level = image[~shadowed & ~near_edge].mean()
    dark = image < 0.5 * lit_level
    assert shadowed.sum() > 200 and (~shadowed & ~near_edge).sum() > 200
    assert np.array_equal(dark[~near_edge], shadowed[~near_edge])


def test_object_info_colour_alpha_and_random(penumbra):
    """Object Info's Color and Alpha are the object's viewport display colour; its Random is
    the per-object hash Cycles draws (within 1e-3; EEVEE's differs from Cycles' by up to
    0.015), on 6 planes."""
    grid = node_scenes.grid(6)
    for k, cell in enumerate(grid.cells):
        cell.ob.color = (0.1 * k, 0.5, 1.0 - 0.1 * k, 0.2 + 0.1 * k)
        info = cell.nodes.new("ShaderNodeObjectInfo")
        out = _out(info, ("Color", "Alpha", "Random")[k % 3])
        cell.links.new(out, _in(cell.emission, "Color"))
    ours = _penumbra(grid.scene)

    def ref(i, u, v):
        col = np.array([0.1 * i, 0.5, 1.0 - 0.1 * i, 0.2 + 0.1 * i])
        kind = i % 3
        return np.tile(col[:3], (len(u), 1)) if kind == 0 else (np.full_like(u, col[3]) if kind == 1 else np.nan + u)

    expected = _per_plane(grid, ref)
    engines.configure(grid.scene, "CYCLES", samples=1)
    cycles = render(grid.scene)["Combined"][..., :3]
    expected = np.where(np.isnan(expected), cycles, expected)
    _assert_close(ours, expected, grid, [f"{('Color', 'Alpha', 'Random')[i % 3]} {i}" for i in range(6)], atol=1e-3)
    u, v, index = grid.uv()
    randoms = [float(cycles[index == i].mean()) for i in (2, 5)]
    assert len({round(r, 3) for r in randoms}) == 2 and all(0.0 < r < 1.0 for r in randoms)


@pytest.mark.negative_inputs  # node outputs below zero on purpose (Subtract, Sine, curves, ...)
def test_rgb_curves_and_float_curve(penumbra):
    """Float Curve (an S-curve, Factor 0.8) and RGB Curves (a combined curve, a red curve, Fac
    1) on x = 1.6u - 0.3 (past both ends of the curves): Blender's own curve evaluation at
    each pixel within 2e-3 (combined curve first, then the channel's; past the ends along
    the end slopes, as CurveMapping.evaluate), and EEVEE within 0.005 mean (measured 0.0008, 0.0010 on 4.5)
    inside the curves' range, away from the planes' edges."""
    grid = node_scenes.grid(2, block=32)
    float_cell, rgb_cell = grid.cells
    fc = float_cell.nodes.new("ShaderNodeFloatCurve")
    points = fc.mapping.curves[0].points
    points.new(0.3, 0.1)
    points.new(0.7, 0.9)
    _in(fc, "Factor").default_value = 0.8
    float_cell.links.new(node_scenes.uv_input(float_cell, 0, 1.6, -0.3), _in(fc, "Value"))
    float_cell.links.new(fc.outputs[0], _in(float_cell.emission, "Color"))
    rc = rgb_cell.nodes.new("ShaderNodeRGBCurve")
    rc.mapping.curves[3].points.new(0.5, 0.7)
    rc.mapping.curves[0].points.new(0.4, 0.2)
    x = node_scenes.uv_input(rgb_cell, 0, 1.6, -0.3)
    rgb_cell.links.new(_combine(rgb_cell, x, x, 0.5, color=True), _in(rc, "Color"))
    rgb_cell.links.new(rc.outputs[0], _in(rgb_cell.emission, "Color"))
    ours = _penumbra(grid.scene)
    r = node_reference
    fm, rm = fc.mapping, rc.mapping

    def ref(i, u, v):
        x = 1.6 * u - 0.3
        if i == 0:
            return x + 0.8 * (r.curve(fm, fm.curves[0], x) - x)
        comb = [r.curve(rm, rm.curves[3], ch) for ch in (x, x, np.full_like(x, 0.5))]
        return np.stack([r.curve(rm, rm.curves[k], comb[k]) for k in range(3)], -1)

    _assert_close(ours, _per_plane(grid, ref), grid, ["FLOAT_CURVE", "RGB_CURVES"])
    engines.configure(grid.scene, "EEVEE")
    eevee = render(grid.scene)["Combined"]
    u, v, _index = grid.uv()
    inner = (np.abs(u - 0.5) < 0.4) & (np.abs(v - 0.5) < 0.4)  # EEVEE's pixel filter blurs the planes' edges
    inner &= (1.6 * u - 0.3 > 0.0) & (1.6 * u - 0.3 < 1.0)  # past the curves' ends EEVEE extrapolates otherwise
    diff = np.abs(ours[..., :3] - eevee[..., :3])[inner]
    assert diff.mean() < 0.005, diff.mean()


def test_bump_tilts_the_shading_normal_like_eevee(penumbra):
    """A plane under a sun from 45 degrees, Bump (Distance 0.05, Strength 0.8) of the height
    sin(12 u) + 0.5 sin(9 v) into the Principled Normal: within 0.02 mean of EEVEE (measured
    0.0104; the pattern's own spread is 0.087), and clearly not flat."""
    from devkit import material_scenes as ms
    from penumbra.engine.scene.materials import material_from_blender

    scene, mat, bsdf = ms.textured_plane_scene(48, 48, "Bumpy")
    scene.objects["Sun"].rotation_euler = (0.0, math.radians(45.0), 0.0)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    coords = nodes.new("ShaderNodeTexCoord")
    sep = nodes.new("ShaderNodeSeparateXYZ")
    links.new(_out(coords, "UV"), _in(sep, "Vector"))
    waves = []
    for axis, freq in ((0, 12.0), (1, 9.0)):
        mul, sin = nodes.new("ShaderNodeMath"), nodes.new("ShaderNodeMath")
        mul.operation, sin.operation = "MULTIPLY", "SINE"
        mul.inputs[1].default_value = freq
        links.new(sep.outputs[axis], mul.inputs[0])
        links.new(mul.outputs[0], sin.inputs[0])
        waves.append(sin.outputs[0])
    height = nodes.new("ShaderNodeMath")
    height.operation = "MULTIPLY_ADD"
    links.new(waves[1], height.inputs[0])
    height.inputs[1].default_value = 0.5
    links.new(waves[0], height.inputs[2])
    bump = nodes.new("ShaderNodeBump")
    _in(bump, "Distance").default_value = 0.05
    _in(bump, "Strength").default_value = 0.8
    links.new(height.outputs[0], _in(bump, "Height"))
    links.new(_out(bump, "Normal"), _in(bsdf, "Normal"))
    read = material_from_blender(mat)
    assert read.tree is not None and read.tree.normal and not read.messages, read.messages
    ours = _penumbra(scene, samples=8)
    engines.configure(scene, "EEVEE")
    ref = render(scene)["Combined"]
    diff = np.abs(ours[..., :3] - ref[..., :3]).mean()
    assert diff < 0.02, diff
    assert ours[..., 0].std() > 0.05  # the bumps show


# --- Mix / Add Shader as two lobes (shaders/nodes/shader.glsl, NODE_LOBES) ------------------

METAL = (0.9, 0.6, 0.2, 1.0)  # a sharp gold metal: Principled Metallic 1, Roughness 0.05
MATTE = (0.2, 0.4, 0.8, 1.0)  # a blue Diffuse BSDF


def _metal(nodes, bsdf):
    _in(bsdf, "Base Color").default_value = METAL
    _in(bsdf, "Metallic").default_value = 1.0
    _in(bsdf, "Roughness").default_value = 0.05
    return bsdf


def _matte(nodes, color=MATTE):
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    _in(diffuse, "Color").default_value = color
    return diffuse


def _mixed(factor):
    """A sphere builder: Mix Shader of the metal and the matte by ``factor`` (a number, or a
    function of (nodes, links) giving the factor's output socket)."""

    def build(mat, nodes, links, bsdf, output):
        mix = nodes.new("ShaderNodeMixShader")
        if callable(factor):
            links.new(factor(nodes, links), mix.inputs[0])
        else:
            mix.inputs[0].default_value = factor
        links.new(_metal(nodes, bsdf).outputs[0], mix.inputs[1])
        links.new(_matte(nodes).outputs[0], mix.inputs[2])
        links.new(mix.outputs[0], _in(output, "Surface"))

    return build


def _averaged(mat, nodes, links, bsdf, output):
    """The mix above as one averaged Principled (what node_closure_resolve made of it before
    lobes): colour and specular level averaged over coverage, metallic and roughness over the
    reflecting part (the Diffuse counts Roughness 1, Specular 0)."""
    _in(bsdf, "Base Color").default_value = tuple(0.5 * (a + b) for a, b in zip(METAL, MATTE, strict=True))
    _in(bsdf, "Metallic").default_value = 0.5
    _in(bsdf, "Roughness").default_value = 0.525
    _in(bsdf, "Specular IOR Level").default_value = 0.25


def _read(name="Asset"):
    from penumbra.engine.scene.materials import material_from_blender

    return material_from_blender(bpy.data.materials[name])


def _swap_surface(mat, build):
    """``mat``'s tree replaced by a fresh Principled BSDF and Material Output, which ``build``
    sets up (as ``node_scenes.sphere`` builders)."""
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    bsdf, output = nodes.new("ShaderNodeBsdfPrincipled"), nodes.new("ShaderNodeOutputMaterial")
    links.new(bsdf.outputs[0], _in(output, "Surface"))
    build(mat, nodes, links, bsdf, output)


def test_mix_of_a_sharp_metal_and_a_diffuse_is_two_lobes(penumbra):
    """Mix Shader 0.5 of a gold metal at Roughness 0.05 and a blue Diffuse on a sphere under a
    sun (64x64, 8 samples) against EEVEE (16 samples). Away from the highlight (a 7x7 window
    around EEVEE's brightest pixel) two lobes are closer to EEVEE than the one averaged
    Principled drawn before (mean |difference| measured 0.0007 against 0.0340; whole image
    0.039 against 0.080, where the highlight's sub-pixel peak dominates). The metal's sharp
    highlight is there: brightest at EEVEE's brightest pixel, half the metal alone's peak as
    in EEVEE (0.51 and 0.50; the averaged lobe: 0.06). The metal alone's peak is lower than
    EEVEE's (18 against 199 at 8 samples, 112 at 64: a highlight far smaller than a pixel
    converges with the samples), in both renders alike."""
    scene = node_scenes.sphere(64, 64, _mixed(0.5))
    read = _read()
    assert read.tree is not None and read.tree.lobes == 2 and read.tree.fallbacks == 0, read.messages
    assert "TREE_LOBES" in read.features
    mat = bpy.data.materials["Asset"]
    lobes = _penumbra(scene, samples=8)[..., :3]
    engines.configure(scene, "EEVEE")
    ref = render(scene)["Combined"][..., :3]
    _swap_surface(mat, _averaged)
    one = _penumbra(scene, samples=8)[..., :3]
    _swap_surface(mat, lambda m, n, links, bsdf, o: _metal(n, bsdf))
    metal = _penumbra(scene, samples=8)[..., :3]
    engines.configure(scene, "EEVEE")
    metal_ref = render(scene)["Combined"][..., :3]
    lum = np.array([0.2126, 0.7152, 0.0722])
    y, x = np.unravel_index(np.argmax(ref @ lum), ref.shape[:2])
    away = np.ones(ref.shape[:2], bool)
    away[max(y - 3, 0) : y + 4, max(x - 3, 0) : x + 4] = False
    err_lobes, err_one = np.abs(lobes - ref)[away].mean(), np.abs(one - ref)[away].mean()
    ratio_ref = (ref @ lum).max() / (metal_ref @ lum).max()
    ratio_lobes, ratio_one = ((img @ lum).max() / (metal @ lum).max() for img in (lobes, one))
    print(
        f"away from the highlight: lobes {err_lobes:.4f}, one lobe {err_one:.4f}; whole image: lobes "
        f"{np.abs(lobes - ref).mean():.4f}, one lobe {np.abs(one - ref).mean():.4f}; peak / metal's: "
        f"EEVEE {ratio_ref:.3f}, lobes {ratio_lobes:.3f}, one lobe {ratio_one:.3f}"
    )
    assert err_lobes < 0.5 * err_one and err_lobes < 0.004, (err_lobes, err_one)
    assert np.abs(lobes - ref).mean() < np.abs(one - ref).mean()
    assert np.unravel_index(np.argmax(lobes @ lum), ref.shape[:2]) == (y, x)
    assert abs(ratio_lobes - ratio_ref) < 0.1, (ratio_lobes, ratio_ref)
    assert ratio_one < 0.2, ratio_one


def _checker_factor(nodes, links):
    checker = nodes.new("ShaderNodeTexChecker")
    _in(checker, "Scale").default_value = 4.0
    return _out(checker, "Fac")


def test_a_textured_factor_gives_each_pure_shader_where_it_is_0_or_1(penumbra):
    """Mix Shader of the metal and the matte by a Checker (Generated, Scale 4), one sample at
    pixel centres (so every pixel's factor is 0 or 1): where it is 0 the pixel equals the
    metal alone, where 1 the matte alone (within 1e-4); and a Mix of that mix with a third
    (red Diffuse) shader by the same checker (three lobes, merged to two) gives the same
    pixels."""
    scene = node_scenes.sphere(48, 48, _mixed(_checker_factor))
    mat = bpy.data.materials["Asset"]
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    output = next(n for n in nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    mix = next(n for n in nodes if n.bl_idname == "ShaderNodeMixShader")
    assert _read().tree.lobes == 2
    mixed = _penumbra(scene)[..., :3]

    def surface(socket):
        links.new(socket, _in(output, "Surface"))
        return _penumbra(scene)[..., :3]

    checker = next(n for n in nodes if n.bl_idname == "ShaderNodeTexChecker")
    emission = nodes.new("ShaderNodeEmission")
    links.new(_out(checker, "Fac"), _in(emission, "Color"))
    factor = surface(emission.outputs[0])[..., 0]  # the factor itself, emitted
    metal = surface(mix.inputs[1].links[0].from_socket)
    matte = surface(mix.inputs[2].links[0].from_socket)
    outer = nodes.new("ShaderNodeMixShader")
    links.new(_out(checker, "Fac"), outer.inputs[0])
    links.new(mix.outputs[0], outer.inputs[1])
    links.new(_matte(nodes, (0.8, 0.1, 0.1, 1.0)).outputs[0], outer.inputs[2])
    links.new(outer.outputs[0], _in(output, "Surface"))
    nested = _read()
    assert nested.tree is not None and nested.tree.lobes == 2 and "node_mix_merge" in nested.tree.code
    merged = _penumbra(scene)[..., :3]
    zero, one = np.isclose(factor, 0.0, atol=1e-6), np.isclose(factor, 1.0, atol=1e-6)
    sphere = metal.sum(axis=-1) > 0.0
    assert (zero & sphere).sum() > 100 and (one & sphere).sum() > 100
    assert np.abs(mixed - metal)[zero].max() < 1e-4
    assert np.abs(mixed - matte)[one].max() < 1e-4
    assert np.abs(merged - metal)[zero].max() < 1e-4  # factor 0 twice: the metal


def test_add_of_two_diffuse_is_the_diffuse_of_the_summed_colour(penumbra):
    """Add Shader of two Diffuse BSDFs (0.3, 0.1, 0.2) and (0.25, 0.4, 0.1) (two lobes of
    weight 1 each: Blender's Add sums the BSDFs) draws as one Diffuse of (0.55, 0.5, 0.3)
    within 1e-3."""

    def added(mat, nodes, links, bsdf, output):
        add = nodes.new("ShaderNodeAddShader")
        links.new(_matte(nodes, (0.3, 0.1, 0.2, 1.0)).outputs[0], add.inputs[0])
        links.new(_matte(nodes, (0.25, 0.4, 0.1, 1.0)).outputs[0], add.inputs[1])
        links.new(add.outputs[0], _in(output, "Surface"))

    scene = node_scenes.sphere(48, 48, added)
    assert _read().tree.lobes == 2
    both = _penumbra(scene)[..., :3]
    mat = bpy.data.materials["Asset"]
    output = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    mat.node_tree.links.new(_matte(mat.node_tree.nodes, (0.55, 0.5, 0.3, 1.0)).outputs[0], _in(output, "Surface"))
    one = _penumbra(scene)[..., :3]
    assert both.max() > 0.1
    assert np.abs(both - one).max() < 1e-3, np.abs(both - one).max()


def test_single_lobe_trees_keep_their_program(penumbra):
    """Trees that can give one lobe only (a Principled mixed with an Emission or a
    Transparent, a shader alone) compile without NODE_LOBES and with today's code (lobes
    summed by node_mix_shader, no node_tree_closure); a Mix of two surfaces sets it."""
    from penumbra.engine.frame.programs import material_defines

    node_scenes.compiled_sphere(16, 16)  # Mix Shader of a Principled and an Emission
    single = _read("Compiled")
    assert single.tree is not None and single.tree.lobes == 1
    assert "node_mix_shader(" in single.tree.code and "node_tree_closure" not in single.tree.code
    assert "TREE_LOBES" not in single.features and "NODE_LOBES" not in material_defines(single.features)
    node_scenes.sphere(16, 16, _mixed(_checker_factor))
    double = _read()
    assert double.tree.lobes == 2 and material_defines(double.features)["NODE_LOBES"] == 2


def test_two_lobes_keep_the_passes_and_debug_views(penumbra):
    """Add Shader of the metal / matte Mix (0.5) and an Emission (0.3, 0.2, 0.1): the Normal,
    Shadow and Emission passes and the LIGHT_COST debug view equal those of the metal alone
    plus that Emission (one lobe; the lobes share the mesh normal here), within 1e-4."""
    from penumbra.engine.scene.materials import material_from_blender

    def glowing(build):
        def full(mat, nodes, links, bsdf, output):
            build(mat, nodes, links, bsdf, output)
            surface = _in(output, "Surface").links[0].from_socket
            emission = nodes.new("ShaderNodeEmission")
            _in(emission, "Color").default_value = (0.3, 0.2, 0.1, 1.0)
            add = nodes.new("ShaderNodeAddShader")
            links.new(surface, add.inputs[0])
            links.new(emission.outputs[0], add.inputs[1])
            links.new(add.outputs[0], _in(output, "Surface"))

        return full

    def passes(build, name):
        scene = node_scenes.sphere(32, 32, glowing(build), name=name)
        engines.configure(scene, "PENUMBRA")
        scene.view_layers[0].use_pass_normal = True
        out = render(scene, passes=("Combined", "Shadow", "Emission"))
        scene.penumbra.debug_view = "LIGHT_COST"
        out["debug"] = render(scene)["Combined"]
        scene.penumbra.debug_view = "NONE"
        return out, material_from_blender(bpy.data.materials[name])

    two, read_two = passes(_mixed(0.5), "TwoLobes")
    one, read_one = passes(lambda m, n, links, bsdf, o: links.new(_metal(n, bsdf).outputs[0], _in(o, "Surface")), "One")
    assert read_two.tree.lobes == 2 and read_one.tree.lobes == 1
    for name in ("Normal", "Shadow", "Emission", "debug"):
        assert np.abs(two[name] - one[name]).max() < 1e-4, name
    assert two["debug"][16, 16, 0] > 0.0 and two["Normal"][16, 16, :3].any()  # lights counted, normals written
    assert np.abs(two["Emission"][16, 16, :3] - (0.3, 0.2, 0.1)).max() < 1e-4
    assert not np.allclose(two["Combined"], one["Combined"], atol=1e-2)  # the lobes differ


def test_each_lobe_has_its_own_normal_and_the_lobes_sum_by_weight(penumbra):
    """Mix Shader 0.3 of the flat metal and the matte with a Bump into its Normal (sin 40 x):
    the render (one sample at pixel centres) is 0.7 x the metal's + 0.3 x the bumped matte's
    within 1e-4 (2e-3 relative in the sharp highlight, measured 9e-4 there: the GGX peak's
    float rounding differs between the programs; each lobe shaded with its own normal, summed
    by weight); and with a
    Transparent BSDF mixed over that by a Checker (two lobes with alpha: the tree runs in the
    shadow pass too) the opaque cells draw and the holes do not."""

    def bumped(nodes, links):
        kinds = ("ShaderNodeSeparateXYZ", "ShaderNodeMath", "ShaderNodeMath", "ShaderNodeBump")
        sep, mul, sin, bump = (nodes.new(k) for k in kinds)
        mul.operation, sin.operation = "MULTIPLY", "SINE"
        mul.inputs[1].default_value = 40.0
        links.new(_out(nodes.new("ShaderNodeTexCoord"), "Object"), _in(sep, "Vector"))
        links.new(sep.outputs[0], mul.inputs[0])
        links.new(mul.outputs[0], sin.inputs[0])
        _in(bump, "Distance").default_value = 0.02
        links.new(sin.outputs[0], _in(bump, "Height"))
        matte = _matte(nodes)
        links.new(_out(bump, "Normal"), _in(matte, "Normal"))
        return matte

    def mixed(mat, nodes, links, bsdf, output):
        mix = nodes.new("ShaderNodeMixShader")
        mix.inputs[0].default_value = 0.3
        links.new(_metal(nodes, bsdf).outputs[0], mix.inputs[1])
        links.new(bumped(nodes, links).outputs[0], mix.inputs[2])
        links.new(mix.outputs[0], _in(output, "Surface"))

    scene = node_scenes.sphere(48, 48, mixed)
    read = _read()
    assert read.tree.lobes == 2 and read.tree.normal, read.messages
    both = _penumbra(scene)[..., :3]
    mat = bpy.data.materials["Asset"]
    _swap_surface(mat, lambda m, nodes, links, bsdf, o: _metal(nodes, bsdf))
    metal = _penumbra(scene)[..., :3]
    _swap_surface(mat, lambda m, nodes, links, bsdf, o: links.new(bumped(nodes, links).outputs[0], _in(o, "Surface")))
    assert _read().tree is not None and _read().tree.normal  # a Diffuse's Bump: compiled
    matte = _penumbra(scene)[..., :3]
    _swap_surface(mat, lambda m, nodes, links, bsdf, o: links.new(_matte(nodes).outputs[0], _in(o, "Surface")))
    flat = _penumbra(scene)[..., :3]
    expected = 0.7 * metal + 0.3 * matte
    assert np.allclose(both, expected, rtol=2e-3, atol=1e-4), np.abs(both - expected).max()
    assert expected.max() > 1.0  # the metal's highlight is in (hence the relative tolerance)
    assert np.abs(matte - flat).mean() > 0.01, np.abs(matte - flat).mean()  # the bumps show

    def holes(mat, nodes, links, bsdf, output):
        mixed(mat, nodes, links, bsdf, output)
        outer = nodes.new("ShaderNodeMixShader")
        links.new(_checker_factor(nodes, links), outer.inputs[0])
        links.new(_in(output, "Surface").links[0].from_socket, outer.inputs[1])
        links.new(nodes.new("ShaderNodeBsdfTransparent").outputs[0], outer.inputs[2])
        links.new(outer.outputs[0], _in(output, "Surface"))

    _swap_surface(mat, holes)
    read = _read()
    assert read.tree.lobes == 2 and read.uses_alpha, read.messages
    image = _penumbra(scene)[..., :3]
    assert np.isfinite(image).all()
    same = np.abs(image - both).max(axis=-1) < 1e-4
    sphere = np.abs(both - both[0, 0]).max(axis=-1) > 1e-3  # not the world behind
    assert 0.3 < (same & sphere).sum() / sphere.sum() < 0.7  # the opaque cells as before, holes elsewhere
