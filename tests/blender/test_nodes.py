"""Compiled shader node trees (engine/scene/nodetree.py): each node family drives an Emission
shader on a grid of planes (devkit/node_scenes.py, one plane per mode, 8x8 pixels each, one
Penumbra sample at pixel centres), compared with its numpy twin (devkit/node_reference.py)
evaluated at each pixel's analytic UV; tolerances are stated at each assertion."""

import numpy as np

from devkit import engines, node_reference, node_scenes
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


def test_map_range_clamp_and_float_mix(penumbra):
    """Map Range (each interpolation, clamped and not, from [0.2, 0.8] to [-1, 2], 3 steps), and
    the reversed source range; Clamp (Min Max and Range with min > max); Mix (Float) and Mix
    (Vector, non-uniform factor): the numpy reference within 2e-3, value = 1.4u - 0.2."""
    from penumbra.engine.scene.nodetree import MAP_RANGE_TYPES

    cases = [(t, c, False) for t in MAP_RANGE_TYPES for c in (False, True)] + [(t, True, True) for t in MAP_RANGE_TYPES]
    cases += [("CLAMP", "MINMAX", False), ("CLAMP", "RANGE", False), ("MIX", "FLOAT", False), ("MIX", "VECTOR", False)]
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
