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
        cell.links.new(m.outputs[0], cell.emission.inputs["Color"])
    image = _penumbra(grid.scene)
    expected = _per_plane(grid, lambda i, u, v: node_reference.math(MATH_OPS[i], 4 * u - 2, 4 * v - 1.9, 0.5))
    _assert_close(image, expected, grid, MATH_OPS)
