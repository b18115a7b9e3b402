"""The Shadow Terminator's geometry offset in its per-corner form (what the lit pass
interpolates) against the offset evaluated directly from the triangle (Cycles' formula)."""

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.scene import terminator  # noqa: E402


def _interpolated(data, t, bary):
    """The per-corner attributes of triangle ``t`` interpolated at ``bary`` as the rasteriser
    does (tabc is flat: the same at every corner)."""
    rows = slice(3 * t, 3 * t + 3)
    return {k: np.asarray(bary) @ v[rows].astype(np.float64) for k, v in data.items()}


def _offset_from_corners(values, n, toward_viewer):
    """lib/lit_terminator.glsl's smooth_surface_offset in numpy."""
    u, v = values["tbary"]
    a, b, c = values["tabc"]
    h = a * u * (u - 1) + (a + b + c) * u * v + b * v * (v - 1)
    if np.dot(n, toward_viewer) > 0:
        h = max(np.min(np.maximum(values["tfront"], 0.0)), 0.5 * h)
    else:
        h = min(-np.min(np.maximum(values["tback"], 0.0)), 0.5 * h)
    return n * h


@pytest.mark.parametrize("seed", range(4))
def test_corner_form_equals_the_direct_offset(seed):
    rng = np.random.default_rng(seed)
    # A low-poly sphere's triangles, normals jittered, plus random triangles.
    positions = rng.normal(size=(60, 3))
    normals = positions / np.linalg.norm(positions, axis=1, keepdims=True)
    normals += 0.1 * rng.normal(size=normals.shape)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    indices = rng.integers(0, 60, size=(40, 3)).astype(np.int32)
    indices = indices[
        (indices[:, 0] != indices[:, 1]) & (indices[:, 1] != indices[:, 2]) & (indices[:, 0] != indices[:, 2])
    ]
    data = terminator.corner_data(positions.astype(np.float32), normals.astype(np.float32), indices)
    for t, tri in enumerate(indices):
        V, N = positions[tri], normals[tri]
        facet = np.cross(V[1] - V[0], V[2] - V[0])
        for bary in rng.dirichlet((1, 1, 1), size=5):
            n = bary @ N
            for side in (facet, -facet):
                want = terminator.smooth_offset(V, N, bary, side)
                got = _offset_from_corners(_interpolated(data, t, bary), n, side)
                np.testing.assert_allclose(got, want, atol=1e-5 * (1 + np.abs(want).max()))


def test_flat_faces_get_no_offset():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    N = np.tile([0, 0, 1], (3, 1)).astype(np.float32)
    data = terminator.corner_data(V, N, np.array([[0, 1, 2]], np.int32))
    for values in data.values():
        if values.shape[1] == 3:
            assert np.all(values == 0.0)


def test_convex_triangle_lifts_outwards_and_towards_the_sphere():
    """On a triangle of a unit sphere's low-poly mesh (vertex normals = positions), the offset
    point lies outside the flat triangle and no further out than the sphere."""
    V = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64)
    bary = np.array([1 / 3, 1 / 3, 1 / 3])
    P = bary @ V
    offset = terminator.smooth_offset(V, V, bary, np.ones(3))
    assert np.dot(offset, np.ones(3)) > 0.0
    assert np.linalg.norm(P) < np.linalg.norm(P + offset) <= 1.0 + 1e-9


def test_degenerate_triangles_are_finite():
    V = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 0], [1e30, 0, 0], [np.nan, 0, 0], [0, 1, 0]], np.float32)
    N = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 1], [0, 0, 1], [0, 0, 1], [np.inf, 0, 0]], np.float32)
    data = terminator.corner_data(V, N, np.array([[0, 1, 2], [3, 4, 5]], np.int32))
    for values in data.values():
        assert np.all(np.isfinite(values))


def test_settings_follow_blender():
    term = terminator.Terminator(geometry_offset=0.1, shading_offset=1.0, normal_offset=0.2)
    assert term.frequency == pytest.approx(2.0)  # Cycles: 1 / (1 - offset / 2)
    matrix = np.diag([2.0, 3.0, -4.0, 1.0])
    assert term.world_normal_offset(matrix) == pytest.approx(0.8)  # object units x largest scale
    assert terminator.Terminator(geometry_offset=0.0, normal_offset=0.2).world_normal_offset(matrix) == 0.0
    assert terminator.offset_amount(0.1, 0.05, -0.02) == 1.0
    assert terminator.offset_amount(0.1, 0.5, 0.5) == 0.0
    assert terminator.offset_amount(0.0, 0.0, 0.0) == 0.0


def test_corner_data_is_remembered_by_the_content_of_its_inputs():
    """Final renders build their batches anew: the corner data of unchanged geometry is the
    one computed before (the same arrays), equal to a fresh computation, and changed geometry
    (one position moved) gets its own."""
    from penumbra.engine.scene import terminator

    rng = np.random.default_rng(4)
    positions = rng.normal(size=(30, 3)).astype(np.float32)
    normals = rng.normal(size=(30, 3)).astype(np.float32)
    indices = rng.integers(0, 30, size=(40, 3)).astype(np.int32)
    first = terminator.corner_data_cached(positions, normals, indices)
    again = terminator.corner_data_cached(positions.copy(), normals.copy(), indices.copy())
    assert again is first
    fresh = terminator.corner_data(positions, normals, indices)
    for name, data in fresh.items():
        np.testing.assert_array_equal(first[name], data)
    moved = positions.copy()
    moved[3, 0] += 0.5
    other = terminator.corner_data_cached(moved, normals, indices)
    assert other is not first
    assert not np.array_equal(other["tfront"], first["tfront"])
