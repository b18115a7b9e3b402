"""A point light's six cube faces planned together (``planning.perspective_tiles``): every face
is fitted alone, then the visible receivers and the casters are clipped to all the faces'
frustums in one pass (``lightspace.pieces_in_many``, ``light_bins.polytope_vertices_many``).
The maps are those of the faces planned one at a time, bit for bit: the same operations on
each triple of planes, each piece and each face, in fewer, larger numpy calls."""

import math

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.shadows import light_bins, lightspace, planning  # noqa: E402


def _bits(a):
    return np.asarray(a, np.float64).tobytes()


def _same(a, b):
    return a.shape == b.shape and _bits(a) == _bits(b)


def _tile_key(tile):
    if tile is None:
        return None
    fit = tile.fit
    held = None if tile.held is None else _bits(tile.held)
    return (_bits(fit.view), _bits(fit.proj), fit.near, fit.far, fit.texel_per_distance, _bits(tile.casters), held)


def _scene(rng, trial):
    """Random boxes at scales 10^-2 to 10^2 (a flat ground under a third of them), a camera's
    visible receivers and a light among the boxes."""
    scale = 10 ** rng.uniform(-2, 2)
    count = int(rng.integers(1, 12))
    centres = rng.normal(size=(count, 3)) * 3 * scale
    sizes = rng.uniform(0.05, 2, size=(count, 3)) * scale
    if trial % 3 == 0:
        centres[0], sizes[0] = (0.0, 0.0, -scale), (20 * scale, 20 * scale, 0.0)
    corners = np.stack([lightspace.box_corners(c - s / 2, c + s / 2) for c, s in zip(centres, sizes, strict=True)])
    view = lightspace.look_at(rng.normal(size=3) * 8 * scale, -rng.normal(size=3))
    camera = lightspace.perspective(rng.uniform(0.4, 1.5), 16 / 9, 0.01 * scale, 200 * scale) @ view
    light = rng.normal(size=3) * 1.5 * scale + (0.0, 0.0, 2.5 * scale)
    return scale, corners, lightspace.visible_receivers(corners, camera), light


def test_polytopes_intersected_together_are_the_ones_intersected_alone():
    """Boxes cut by frusta (the planning's case) and random polytopes of 4 to 18 planes, several
    at once: each one's vertices equal, bit for bit, those found for it alone."""
    rng = np.random.default_rng(3)
    for trial in range(200):
        planes = int(rng.integers(4, 19))
        count = int(rng.integers(1, 6))
        if trial % 2:
            stacked = light_bins._unit_planes(rng.normal(size=(count * planes, 4))).reshape(count, planes, 4)
        else:
            view = lightspace.look_at(rng.normal(size=3) * 5, rng.normal(size=3))
            frustum = light_bins.frustum_planes(lightspace.perspective(rng.uniform(0.2, 2.5), 1.0, 0.05, 50.0) @ view)
            lo = rng.normal(size=(count, 3)) * 3
            hi = lo + rng.uniform(0.0, 4.0, size=(count, 3))
            stacked = np.stack([np.concatenate([frustum, light_bins.box_planes(a, b)]) for a, b in zip(lo, hi)])
        tolerances = 1e-6 * rng.uniform(0.1, 100.0, size=count)
        together = light_bins.polytope_vertices_many(stacked, tolerances)
        assert len(together) == count
        for planes_k, tolerance, got in zip(stacked, tolerances, together, strict=True):
            alone = light_bins.polytope_vertices(planes_k, tolerance)
            assert _same(got, alone), trial
    assert light_bins.polytope_vertices_many(np.zeros((0, 6, 4)), []) == []


def test_box_planes_are_the_boxes_faces_with_unit_outward_normals():
    lo, hi = np.array([-1.0, 0.0, 2.0]), np.array([3.0, 0.5, 2.0])
    planes = light_bins.box_planes(lo, hi)
    inside = np.array([[1.0, 0.25, 2.0], [-1.0, 0.0, 2.0], [3.0, 0.5, 2.0]])
    outside = np.array([[3.1, 0.25, 2.0], [1.0, -0.1, 2.0], [1.0, 0.25, 2.01]])
    assert np.all(inside @ planes[:, :3].T - planes[:, 3] <= 0.0)
    assert np.all(np.any(outside @ planes[:, :3].T - planes[:, 3] > 0.0, axis=1))
    np.testing.assert_array_equal(np.linalg.norm(planes[:, :3], axis=1), 1.0)


def test_boxes_and_pieces_clipped_to_several_regions_at_once_are_those_clipped_to_each():
    rng = np.random.default_rng(5)
    for trial in range(60):
        _scale, corners, receivers, light = _scene(rng, trial)
        face = lightspace.perspective(math.pi / 2, 1.0, 0.01, 100.0)
        regions = [light_bins.frustum_planes(face @ lightspace.look_at(light, f)) for f in lightspace.CUBE_FORWARDS]
        boxes = [corners[rng.random(len(corners)) < 0.6] for _ in regions]
        together = lightspace.pieces_in_many(regions, boxes, receivers.pieces)
        for planes, region_boxes, got in zip(regions, boxes, together, strict=True):
            alone = lightspace.pieces_in(planes, region_boxes, receivers.pieces)
            assert len(got) == len(alone) and all(_same(a, b) for a, b in zip(got, alone, strict=True)), trial


@pytest.mark.parametrize("kept", [False, True])
def test_a_cubes_faces_planned_together_are_the_faces_planned_one_at_a_time(kept):
    """Six faces of a light among random boxes, cropped to what a camera sees, at map sizes
    32-2048, with a hard kernel or a soft light's radius, twice (with ``kept``, the second
    takes the windows the first kept): each tile equals, bit for bit, the tile of its face
    planned alone with its own memo and kept windows. Some faces have no tile."""
    rng = np.random.default_rng(9)
    planned = 0
    for trial in range(80):
        scale, corners, receivers, light = _scene(rng, trial)
        boxes = planning.Boxes.of(corners)
        flat_free = lightspace.FlatCasters(corners).free(position=light)
        windows_alone, windows_together = ({}, {}) if kept else (None, None)
        for _repeat in range(2):
            size = int(2 ** rng.integers(5, 12))
            kernel = float(rng.choice([0.0, 3.0]))
            soft = float(rng.choice([0.0, 0.1 * scale]))
            eyes = [planning.Eye(light, f, math.pi / 2) for f in lightspace.CUBE_FORWARDS]
            memo = {}
            alone = [
                planning.perspective_tile(
                    eye, boxes, size, kernel, soft, planning.Crop(receivers, flat_free, windows_alone), memo
                )
                for eye in eyes
            ]
            together = planning.perspective_tiles(
                eyes, boxes, [size] * 6, kernel, soft, planning.Crop(receivers, flat_free, windows_together), {}
            )
            assert [_tile_key(t) for t in together] == [_tile_key(t) for t in alone], trial
            planned += sum(t is not None for t in alone)
        if kept:
            assert windows_alone.keys() == windows_together.keys()
    assert planned > 50


def test_faces_near_the_kept_windows_bound_are_planned_one_after_the_other():
    """With the kept windows near their bound, a crop empties them: the faces are then planned
    in turn, each finding what the one before it left, as one at a time. The light's windows
    kept from a wider view hold the narrower view's for the faces before the crop that empties
    them, and not for those after it, so planning them all from one look at the kept windows
    would differ."""
    light = np.array([0.0, 0.0, 3.0])
    corners = np.stack(
        [lightspace.box_corners((-10.0, -10.0, 0.0), (10.0, 10.0, 0.0))]
        + [
            lightspace.box_corners((x - 0.3, y - 0.3, 0.0), (x + 0.3, y + 0.3, 0.8))
            for x, y in ((2, 0), (-2, 1), (0, -2))
        ]
    )
    boxes = planning.Boxes.of(corners)
    flat_free = lightspace.FlatCasters(corners).free(position=light)  # the ground casts nothing
    view = lightspace.look_at((0.0, -9.0, 6.0), (0.0, 9.0, -6.0))
    wide, narrow = (
        lightspace.visible_receivers(corners, lightspace.perspective(math.radians(a), 1.5, 0.1, 100.0) @ view)
        for a in (70.0, 60.0)
    )
    eyes = [planning.Eye(light, f, math.pi / 2) for f in lightspace.CUBE_FORWARDS]
    first = {}
    planning.perspective_tiles(eyes, boxes, [256] * 6, 3.0, 0.0, planning.Crop(wide, flat_free, first), {})
    assert len(first) >= 2  # the faces that see a box's shadow, cropped
    filler = {("other light", k): (0.0, 0.0, 0.0, 0.0, 0.0) for k in range(planning._KEPT_WINDOWS - len(first))}
    alone_windows, together_windows = {**first, **filler}, {**first, **filler}
    memo = {}
    alone = [
        planning.perspective_tile(eye, boxes, 256, 3.0, 0.0, planning.Crop(narrow, flat_free, alone_windows), memo)
        for eye in eyes
    ]
    together = planning.perspective_tiles(
        eyes, boxes, [256] * 6, 3.0, 0.0, planning.Crop(narrow, flat_free, together_windows), {}
    )
    assert len(alone_windows) < len(first) + len(filler)  # emptied on the way
    assert [_tile_key(t) for t in together] == [_tile_key(t) for t in alone]
    assert alone_windows == together_windows
    # Taken from one look at the kept windows, the faces after the emptying would differ.
    fresh = planning.perspective_tiles(eyes, boxes, [256] * 6, 3.0, 0.0, planning.Crop(narrow, flat_free, {}), {})
    stale = planning.perspective_tiles(
        eyes, boxes, [256] * 6, 3.0, 0.0, planning.Crop(narrow, flat_free, dict(first)), {}
    )
    assert [_tile_key(t) for t in fresh] != [_tile_key(t) for t in stale]


def test_a_cubes_faces_are_clipped_in_three_passes_not_three_a_face(monkeypatch):
    """Planning a point light's six faces clips the receivers and casters with at most three
    calls of ``polytope_vertices_many`` (the receivers, the casters, what each cropped map
    holds), where one face at a time made about three for every face (and one call per piece)."""
    rng = np.random.default_rng(17)
    calls = []
    many = light_bins.polytope_vertices_many

    def counted(planes, tolerances):
        calls.append(len(planes))
        return many(planes, tolerances)

    monkeypatch.setattr(light_bins, "polytope_vertices_many", counted)
    for trial in range(40):
        _scale, corners, receivers, light = _scene(rng, 3 * trial)
        eyes = [planning.Eye(light, f, math.pi / 2) for f in lightspace.CUBE_FORWARDS]
        del calls[:]
        tiles = planning.perspective_tiles(
            eyes, planning.Boxes.of(corners), [512] * 6, 3.0, 0.0, planning.Crop(receivers, None), {}
        )
        assert len(calls) <= 3, (trial, calls)
        if sum(t is not None for t in tiles) >= 2:
            assert sum(calls) >= 2  # the faces' pieces went in together


@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e4])
def test_degenerate_scenes_plan_the_same_faces_together_with_finite_maps(scale):
    """At 10^-4 and 10^4 m: a light on a box's corner, a light inside a box, boxes of no
    volume (a point, a segment, a flat card) and a ground. Planned together or one face at a
    time, the tiles are equal, and every map's matrices are finite with near < far."""
    s = scale
    corners = np.stack(
        [
            lightspace.box_corners((-10 * s, -10 * s, 0.0), (10 * s, 10 * s, 0.0)),  # a ground
            lightspace.box_corners((0.0, 0.0, 0.0), (s, s, s)),  # the light sits on its corner
            lightspace.box_corners((2 * s, 2 * s, s), (2 * s, 2 * s, s)),  # a point
            lightspace.box_corners((-2 * s, s, 0.5 * s), (-s, s, 0.5 * s)),  # a segment
            lightspace.box_corners((s, -3 * s, 0.0), (2 * s, -3 * s, 2 * s)),  # a card
            lightspace.box_corners((-3 * s, -3 * s, 0.0), (-2 * s, -2 * s, 2 * s)),  # holds the second light
        ]
    )
    view = lightspace.look_at((0.0, -12 * s, 8 * s), (0.0, 12.0, -8.0))
    receivers = lightspace.visible_receivers(corners, lightspace.perspective(0.9, 1.5, 0.01 * s, 100 * s) @ view)
    boxes = planning.Boxes.of(corners)
    for light in (np.array([s, s, s]), np.array([-2.5 * s, -2.5 * s, s])):
        flat_free = lightspace.FlatCasters(corners).free(position=light)
        eyes = [planning.Eye(light, f, math.pi / 2) for f in lightspace.CUBE_FORWARDS]
        for size, kernel, soft in ((2048, 3.0, 0.0), (16, 0.0, 0.2 * s)):
            crop = planning.Crop(receivers, flat_free)
            memo = {}
            alone = [planning.perspective_tile(eye, boxes, size, kernel, soft, crop, memo) for eye in eyes]
            together = planning.perspective_tiles(eyes, boxes, [size] * 6, kernel, soft, crop, {})
            assert [_tile_key(t) for t in together] == [_tile_key(t) for t in alone]
            tiles = [t for t in together if t is not None]
            assert tiles, (scale, light, size)
            for tile in tiles:
                assert np.all(np.isfinite(tile.fit.view_proj)) and 0.0 < tile.fit.near < tile.fit.far
