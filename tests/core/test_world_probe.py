"""The world's probe of an interior's openings (``engine/frame/world/probe.py``), on cube
maps made in numpy: the depths a probe at the centre of a box room would read, with and
without openings, and the guide of directions it makes."""

import math

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.frame.world import probe  # noqa: E402
from penumbra.engine.frame.world.directions import PORTAL_SHARE, WorldDistribution  # noqa: E402


def cube(half=(2.0, 2.5, 1.4), openings=()):
    """(directions, solid angles, distances, open) of every probe texel at the centre of a
    box room of half-extents ``half``; a texel is open where its ray leaves the room through
    one of ``openings`` (axis index, sign, (lo, hi) of the two other coordinates in order)."""
    dirs, solid = [], []
    for forward in probe.FACES:
        cam = probe.face_camera(np.zeros(3), forward, 1.0)
        d, s = probe.texel_directions(cam.rotation)
        dirs.append(d.reshape(-1, 3))
        solid.append(s.ravel())
    d, s = np.concatenate(dirs), np.concatenate(solid)
    half = np.asarray(half, np.float64)
    with np.errstate(divide="ignore"):
        t_axes = np.where(np.abs(d) > 1e-12, half / np.abs(d), np.inf)
    axis = np.argmin(t_axes, axis=1)
    t = t_axes[np.arange(len(d)), axis]
    hit = d * t[:, None]
    opened = np.zeros(len(d), bool)
    for ax, sign, (a, b) in openings:
        others = [k for k in range(3) if k != ax]
        inside = (axis == ax) & (np.sign(d[:, ax]) == sign)
        for k, (lo, hi) in zip(others, (a, b), strict=True):
            inside &= (hit[:, k] >= lo) & (hit[:, k] <= hi)
        opened |= inside
    return d, s, np.where(opened, 0.0, t), opened


WINDOW = (1, 1.0, ((-0.8, 0.8), (-0.7, 0.7)))  # in the +Y wall
SKYLIGHT = (2, 1.0, ((-0.6, 0.6), (-0.6, 0.6)))  # in the ceiling


def guide_of(d, s, depth, opened):
    return probe.opening_guide([(d, s, depth, opened, np.zeros(3))])


@pytest.mark.parametrize("openings", [(WINDOW,), (WINDOW, SKYLIGHT)])
def test_an_interiors_guide_draws_through_its_openings(openings):
    """Directions drawn from the guide pass through the openings from somewhere in the room:
    95 % of them lie on the openings' side (towards +Y, or up through the skylight), and its
    density towards the window is many times that of directions no opening lets in."""
    d, s, depth, opened = cube(openings=openings)
    g = guide_of(d, s, depth, opened)
    assert isinstance(g, WorldDistribution)
    rng = np.random.default_rng(1)
    drawn = g._from_image(rng.random(4000), rng.random(4000))
    assert np.all(np.isfinite(drawn)) and np.allclose(np.linalg.norm(drawn, axis=1), 1.0)
    towards = (drawn[:, 1] > 0.0) | ((drawn[:, 2] > 0.0) if len(openings) > 1 else False)
    assert towards.mean() > 0.95, towards.mean()
    # No ray from inside reaches an opening going down through the floor (nor, with the
    # window alone, away from its wall).
    window = np.array([[0.0, 1.0, 0.0]])
    away = np.array([[0.0, 0.0, -1.0]] if len(openings) > 1 else [[0.0, -1.0, 0.0]])
    assert g.image_pdf(window)[0] > 20.0 * max(g.image_pdf(away)[0], 1e-12)
    # a density over the sphere: it integrates to 1
    cells = rng.normal(size=(200000, 3))
    cells /= np.linalg.norm(cells, axis=1)[:, None]
    assert abs(g.image_pdf(cells).mean() * 4.0 * math.pi - 1.0) < 0.03


def test_outdoors_and_closed_rooms_get_no_guide():
    """A room open above (more than INTERIOR_SHARE of the world seen), a closed room (nothing
    open) and a room seen from outside nothing (no wall) take no guide; a camera in the open
    takes none though the middle of its view lies in a room (a house seen from its garden),
    and a camera in a room takes the rays of the middle's probe where that stands inside too."""
    d, s, depth, opened = cube()
    assert guide_of(d, s, depth, opened) is None  # closed
    roofless = opened | (d[:, 2] > 0.0)
    assert guide_of(d, s, np.where(roofless, 0.0, depth), roofless) is None
    everything = np.ones(len(d), bool)
    assert guide_of(d, s, np.zeros(len(d)), everything) is None
    room = (d, s, *cube(openings=(WINDOW,))[2:], np.zeros(3))
    garden = (d, s, np.where(roofless, 0.0, depth), roofless, np.array([0.0, 9.0, 0.0]))
    assert probe.opening_guide([garden, room]) is None
    assert probe.opening_guide([room, garden]) is not None


def test_the_guide_keeps_a_frame_unbiased():
    """Drawn through light portals' share (``directions.PORTAL_SHARE``) beside the world's own
    distribution, every direction keeps a density of at least the rest's share of the
    uniform: the whole-light estimator f cos V L / p is unbiased whatever the guide misses."""
    d, s, depth, opened = cube(openings=(WINDOW,))
    g = guide_of(d, s, depth, opened)
    dist = WorldDistribution(np.eye(9, 3), None, [g])
    rng = np.random.default_rng(2)
    dirs = rng.normal(size=(5000, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    assert np.all(dist.pdf(dirs) >= (1.0 - PORTAL_SHARE) / (4.0 * math.pi) - 1e-12)
    drawn = dist.directions(rng.random((3000, 2)))
    assert np.all(np.isfinite(drawn)) and (drawn[:, 1] > 0.0).mean() > 0.7
