"""Lighting in Blender's light units: a white Lambertian plane under one light, against the
constants measured in Cycles (see the README's light-unit table)."""

import math

import numpy as np
import pytest

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


@pytest.mark.parametrize(
    "kind, props, ratio",
    [
        ("AREA", {"size": 2.0}, 4.0),
        ("AREA", {"size": 0.5}, 0.25),
        ("AREA", {"shape": "DISK", "size": 2.0}, math.pi),
        ("AREA", {"shape": "RECTANGLE", "size": 2.0, "size_y": 0.5}, 1.0),
        ("POINT", {"shadow_soft_size": 1.0}, 4.0 * math.pi),
        ("SPOT", {"shadow_soft_size": 0.25, "spot_size": math.radians(120)}, math.pi / 4.0),
        ("SUN", {"angle": math.radians(40)}, math.pi * math.sin(math.radians(20)) ** 2),
        ("POINT", {"shadow_soft_size": 0.0}, 1.0),
    ],
)
def test_normalize_off_scales_power_by_the_emitter_area(penumbra, kind, props, ratio):
    """Light › Normalize off: the power is per unit of emitter area. Cycles' ratios (unnormalised
    over normalised, measured at the centre of this set-up): 4, 0.25, pi, 1, 4 pi, pi / 4 and
    pi sin^2(20 deg) = 0.3675; a point of radius 0 is unchanged."""
    on = _single_light_plane(kind, 1.0 if kind == "SUN" else 100.0, **props).mean()
    off = _single_light_plane(kind, 1.0 if kind == "SUN" else 100.0, normalize=False, **props).mean()
    np.testing.assert_allclose(off / on, ratio, rtol=1e-4)


def test_a_non_uniformly_scaled_spot_lights_an_ellipse(penumbra):
    """A spot's object scale stretches its cone along its X and Y (relative to Z), as in
    Blender's engines: straight down from 2 m with a 60 degree cone scaled (2, 0.5, 1), the
    lit footprint is the ellipse of semi-axes 2 tan 30 deg * (2, 0.5); a uniform scale leaves
    the cone round. Its shadow map covers the wider cone: a box in the stretched part, 47
    degrees off the axis, shadows the ground behind it."""
    size, view = 128, 6.0
    half = math.tan(math.radians(30.0)) * 2.0

    def render_spot(scale, box=False):
        scene = scenes.empty_scene(size, size)
        scenes.plane(scene, size=40.0, mat=scenes.white())
        if box:
            scenes.box(scene, "Box", center=(1.6, 0.0, 0.5), size=(0.4, 0.4, 0.4), mat=scenes.white())
        spot = scenes.light(scene, "L", "SPOT", 100.0, location=(0, 0, 2.0), spot_size=math.radians(60), spot_blend=0.0)
        spot.data.shadow_soft_size = 0.0
        spot.scale = scale
        scenes.top_camera(scene, height=10.0, ortho_scale=view)
        return render(scene)["Combined"][..., 0]

    centres = ((np.arange(size) + 0.5) / size - 0.5) * view
    x, y = np.meshgrid(centres, centres)
    pixel = view / size
    for scale, (ax, ay) in (((2.0, 0.5, 1.0), (2.0, 0.5)), ((3.0, 3.0, 3.0), (1.0, 1.0))):
        lit = render_spot(scale) > 1e-4
        r = np.hypot(x / (half * ax), y / (half * ay))
        edge = np.abs(r - 1.0) < 1.5 * pixel / (half * min(ax, ay))
        assert np.array_equal(lit[~edge], (r < 1.0)[~edge]), scale
    lum = render_spot((2.0, 0.5, 1.0), box=True)
    row, behind, mirror = size // 2, int((2.1 / view + 0.5) * size), int((-2.1 / view + 0.5) * size)
    assert lum[row, mirror] > 1e-3 and lum[row, behind] < 0.1 * lum[row, mirror]


@pytest.mark.parametrize("metallic", [0.0, 1.0])
def test_light_influence_factors_scale_diffuse_and_specular(penumbra, metallic):
    """Light › Influence › Diffuse and Specular (EEVEE's): a plane without specular (Specular
    IOR Level 0) under Diffuse 0.37 is 0.37 as bright and ignores Specular; a rough metal
    (no diffuse) under Specular 0.25 is 0.25 as bright and ignores Diffuse."""

    def lum(diffuse=1.0, specular=1.0):
        scene = scenes.empty_scene(32, 32)
        mat = scenes.material("M", (0.8, 0.8, 0.8), roughness=0.6, specular=0.0, metallic=metallic)
        scenes.plane(scene, size=200.0, mat=mat)
        light = scenes.light(scene, "L", "POINT", 100.0, location=(0.3, 0.0, 2.0), shadow_soft_size=0.1)
        light.data.diffuse_factor, light.data.specular_factor = diffuse, specular
        scenes.camera(scene, (0.0, 0.0, 6.0), (0.0, 0.0, 0.0), ortho_scale=0.4, clip=(0.1, 20.0))
        return render(scene)["Combined"][..., 0].mean()

    base = lum()
    assert base > 1e-3
    if metallic:
        np.testing.assert_allclose(lum(specular=0.25) / base, 0.25, rtol=1e-4)
        np.testing.assert_allclose(lum(diffuse=0.0) / base, 1.0, rtol=1e-4)
    else:
        np.testing.assert_allclose(lum(diffuse=0.37) / base, 0.37, rtol=1e-4)
        np.testing.assert_allclose(lum(specular=0.0) / base, 1.0, rtol=1e-4)
