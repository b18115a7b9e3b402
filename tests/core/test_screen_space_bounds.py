"""The lengths the screen-space techniques take from the draws' bounds: the longest ray
(``draw_list.longest_ray``, reflections and refraction) and a transmissive object's thickness
(``lit_pass.object_thickness``, EEVEE's default: its smallest dimension), at the extremes:
rotated and scaled boxes, zero scale, broken (NaN, infinite) corners, nothing drawn."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()

from penumbra.engine.frame.draw_list import longest_ray  # noqa: E402
from penumbra.engine.frame.lit_pass import object_thickness  # noqa: E402

BITS = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], np.float64)


def box_corners(size, angle=0.0, centre=(0.0, 0.0, 0.0)):
    """The world corners (corner i at bits x, y, z of i) of a box of ``size`` turned ``angle``
    about z."""
    c, s = math.cos(angle), math.sin(angle)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    local = (BITS - 0.5) * np.asarray(size, np.float64)
    return local @ turn.T + np.asarray(centre, np.float64)


@pytest.mark.parametrize("scale", (1e-6, 1.0, 1e6))
def test_the_thickness_is_the_smallest_dimension_at_any_scale_and_turn(scale):
    size = np.array([3.0, 0.5, 2.0]) * scale
    assert object_thickness(box_corners(size, angle=0.7)) == pytest.approx(0.5 * scale, rel=1e-9)


def test_a_flat_or_broken_object_has_no_thickness():
    assert object_thickness(box_corners((2.0, 2.0, 0.0))) == 0.0  # a pane: one interface
    assert object_thickness(np.zeros((8, 3))) == 0.0  # scaled to nothing
    broken = box_corners((1.0, 1.0, 1.0))
    broken[1] = np.nan
    assert object_thickness(broken) == 0.0


def test_the_longest_ray_spans_what_is_drawn_and_ignores_broken_corners():
    draws = [
        SimpleNamespace(corners=box_corners((1.0, 1.0, 1.0))),
        SimpleNamespace(corners=box_corners((1.0, 1.0, 1.0), centre=(10.0, 0.0, 0.0))),
    ]
    assert longest_ray(draws) == pytest.approx(math.sqrt(11.0**2 + 1.0 + 1.0))
    broken = box_corners((1.0, 1.0, 1.0))
    broken[3] = (np.inf, 0.0, np.nan)
    assert longest_ray([SimpleNamespace(corners=broken)]) == pytest.approx(math.sqrt(3.0))
    assert longest_ray([]) == 0.0
    assert longest_ray([SimpleNamespace(corners=np.full((8, 3), np.nan))]) == 0.0
