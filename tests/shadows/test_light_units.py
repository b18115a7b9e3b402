"""Lighting in Blender's light units: a white Lambertian plane under one light, against the
constants measured in Cycles (see the README's light-unit table)."""

import math

import numpy as np

from devkit import scenes
from devkit.render import render
from devkit.scenes import WHITE_ALBEDO as ALBEDO


def _single_light_plane(kind, energy, **props):
    scene = scenes.empty_scene(64, 64)
    scenes.plane(scene, size=200.0, mat=scenes.white())
    scenes.light(scene, "L", kind, energy, location=(0, 0, 2.0), **props)
    scenes.top_camera(scene, height=10.0, ortho_scale=0.04)
    return render(scene)["Combined"][..., 0]


def test_point_light_units_match_cycles_convention(penumbra):
    """Cycles: albedo * P / (4 pi^2 (d^2 + r^2)) on axis (soft falloff on, Blender's default)."""
    lum = _single_light_plane("POINT", 100.0, shadow_soft_size=0.1)
    expected = ALBEDO * 100.0 / (4 * math.pi**2 * (4.0 + 0.01))
    np.testing.assert_allclose(lum.mean(), expected, rtol=0.005)


def test_spot_centre_equals_point_and_cone_edge_cuts(penumbra):
    lum = _single_light_plane("SPOT", 100.0, shadow_soft_size=0.0, spot_size=math.radians(90), spot_blend=0.0)
    np.testing.assert_allclose(lum.mean(), ALBEDO * 100.0 / (16 * math.pi**2), rtol=0.005)


def test_area_light_far_field_units(penumbra):
    """Cycles far field: albedo * P * cos * cos_emitter / (pi^2 d^2)."""
    lum = _single_light_plane("AREA", 100.0, size=0.01)
    np.testing.assert_allclose(lum.mean(), ALBEDO * 100.0 / (math.pi**2 * 4.0), rtol=0.005)


def test_world_colour_is_ambient(penumbra):
    scene = scenes.empty_scene(32, 32)
    scenes.set_world(scene, (0.2, 0.3, 0.4))
    scenes.plane(scene, size=200.0, mat=scenes.white())
    scenes.top_camera(scene, height=10.0, ortho_scale=1.0)
    c = render(scene)["Combined"]
    np.testing.assert_allclose(c[16, 16, :3], ALBEDO * np.array([0.2, 0.3, 0.4]), rtol=1e-4)
