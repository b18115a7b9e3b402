"""Anisotropic GGX (shaders/lib/anisotropy.glsl): the Principled BSDF's Anisotropic and
Anisotropic Rotation and the Glossy BSDF's Anisotropy against the same lobe in numpy
(devkit.analytic.ggx_aniso_reflectance, with Cycles' roughness mapping). A plane fills an
orthographic view, so every pixel sees the same angles and the image mean is one evaluation of
the BSDF."""

import math

import numpy as np
import pytest

from devkit import analytic, scenes
from devkit.plane_scenes import SUN, plane_mean
from devkit.plane_scenes import directions as _directions
from devkit.render import group_off_and_on

METAL = (0.9, 0.8, 0.7)


def _tangent(tree, node, tangent):
    """Link ``tangent`` (a world vector) into ``node``'s Tangent input."""
    combine = tree.nodes.new("ShaderNodeCombineXYZ")
    for i, value in enumerate(tangent):
        combine.inputs[i].default_value = value
    tree.links.new(combine.outputs[0], node.inputs["Tangent"])


def _principled(rough, amount, rotation=0.0, tangent=(1.0, 0.0, 0.0)):
    def make():
        mat = scenes.material("Brushed", METAL, roughness=rough, metallic=1.0)
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Anisotropic"].default_value = amount
        bsdf.inputs["Anisotropic Rotation"].default_value = rotation
        if tangent is not None:
            _tangent(mat.node_tree, bsdf, tangent)
        return mat

    return make


def _glossy(rough, amount, tangent=(1.0, 0.0, 0.0)):
    def make():
        mat = scenes.material("Glossy", METAL)
        tree = mat.node_tree
        node = tree.nodes.new("ShaderNodeBsdfAnisotropic")
        node.inputs["Color"].default_value = (*METAL, 1.0)
        node.inputs["Roughness"].default_value = rough
        node.inputs["Anisotropy"].default_value = amount
        _tangent(tree, node, tangent)
        tree.links.new(node.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
        return mat

    return make


def _plane(make, view_deg, sun_elevation=None, samples=1, sun_azimuth=0.0, at=(0.0, 0.0)):
    return plane_mean(make, view_deg, sun_elevation, samples, sun_azimuth, at=at)


def _metal_fresnel(c):
    f0 = np.array(METAL)
    return f0 + (1.0 - f0) * analytic.fresnel_shape(c)


def _metal(ax, ay, v, to_light):
    """The metal's anisotropic lobe under a light, times the multiple-scattering gain at the
    roughness of alpha = sqrt(alpha_x alpha_y) (Cycles' microfacet_ggx_preserve_energy)."""
    rough = math.sqrt(math.sqrt(ax * ay))
    gain = analytic.ggx_ms_gain(float(np.mean(METAL)), 1.0, rough, v[2])
    return analytic.ggx_aniso_reflectance(_metal_fresnel, ax, ay, v, to_light) * gain


def _principled_alphas(rough, amount):
    aspect = math.sqrt(1.0 - 0.9 * amount)
    a = max(rough * rough, 0.002)
    return min(max(a / aspect, 0.002), 1.0), min(max(a * aspect, 0.002), 1.0)


@pytest.mark.parametrize(
    ("rough", "amount", "elevation", "azimuth"),
    [(0.4, 0.8, 40, 0.3), (0.5, 1.0, 30, 1.2), (0.3, 0.5, 55, 2.2), (0.6, 0.9, 25, 0.0)],
)
def test_an_anisotropic_metal_under_a_sun_is_the_lobe(penumbra, rough, amount, elevation, azimuth):
    """A metal of Anisotropic ``amount`` along x seen at 50 degrees under a sun: the anisotropic
    GGX of alpha_x = r^2 / sqrt(1 - 0.9 A), alpha_y = r^2 sqrt(1 - 0.9 A) with its
    multiple-scattering gain, within 3 %; and not the isotropic lobe's value (the anisotropy
    shows)."""
    v, to_light = _directions(50, elevation, azimuth)
    ax, ay = _principled_alphas(rough, amount)
    ref = SUN * _metal(ax, ay, v, to_light)
    ours = _plane(_principled(rough, amount), 50, elevation, sun_azimuth=azimuth)
    assert np.allclose(ours, ref, rtol=0.03), (ours, ref)
    a = max(rough * rough, 0.002)
    iso = SUN * _metal(a, a, v, to_light)
    assert np.abs(ref - iso).max() > 0.1 * iso.max()


def test_the_rotation_turns_the_tangent(penumbra):
    """Anisotropic Rotation 0.25 (a quarter turn about the normal) of a tangent along x is the
    tangent along y without rotation (within 1 %), and neither is the x tangent's image."""
    args = (50, 35)
    turned = _plane(_principled(0.45, 0.9, rotation=0.25, tangent=(1.0, 0.0, 0.0)), *args, sun_azimuth=0.6)
    along_y = _plane(_principled(0.45, 0.9, tangent=(0.0, 1.0, 0.0)), *args, sun_azimuth=0.6)
    along_x = _plane(_principled(0.45, 0.9, tangent=(1.0, 0.0, 0.0)), *args, sun_azimuth=0.6)
    assert np.allclose(turned, along_y, rtol=0.01), (turned, along_y)
    assert np.abs(along_x - along_y).max() > 0.1 * along_y.max()


@pytest.mark.parametrize("amount", [-0.6, 0.6, -1.0])
def test_the_glossy_bsdfs_anisotropy_both_ways(penumbra, amount):
    """A Glossy BSDF's Anisotropy a: alpha_x = r^2 / (1 + a), alpha_y = r^2 (1 + a) below 0 and
    r^2 (1 - a), r^2 / (1 - a) above (a within +-0.99), Cycles' glossy closure, within 3 %; -a
    along x is +a along y (within 1 %)."""
    rough, view, elevation, azimuth = 0.5, 55, 35, 0.8
    a = max(-0.99, min(0.99, amount))
    alpha = rough * rough
    ax, ay = (alpha / (1 + a), alpha * (1 + a)) if a < 0 else (alpha * (1 - a), alpha / (1 - a))
    v, to_light = _directions(view, elevation, azimuth)
    ref = SUN * _metal(min(max(ax, 0.002), 1.0), min(max(ay, 0.002), 1.0), v, to_light)
    ours = _plane(_glossy(rough, amount), view, elevation, sun_azimuth=azimuth)
    assert np.allclose(ours, ref, rtol=0.03), (ours, ref)
    if abs(amount) < 0.99:
        other = _plane(_glossy(rough, -amount, tangent=(0.0, 1.0, 0.0)), view, elevation, sun_azimuth=azimuth)
        assert np.allclose(ours, other, rtol=0.01), (ours, other)


def test_the_default_tangent_is_cycles_radial_tangent(penumbra):
    """An unlinked Tangent is Cycles' radial tangent about the object's Z: on a plane at the
    origin, seen around (100, 0), it runs along +y there, so the image is the one of a Tangent
    linked to +y (within 1 %) and not of one along x."""
    args = (50, 35)
    radial = _plane(_principled(0.45, 0.9, tangent=None), *args, sun_azimuth=0.6, at=(100.0, 0.0))
    along_y = _plane(_principled(0.45, 0.9, tangent=(0.0, 1.0, 0.0)), *args, sun_azimuth=0.6, at=(100.0, 0.0))
    along_x = _plane(_principled(0.45, 0.9, tangent=(1.0, 0.0, 0.0)), *args, sun_azimuth=0.6, at=(100.0, 0.0))
    assert np.allclose(radial, along_y, rtol=0.01), (radial, along_y)
    assert np.abs(along_x - along_y).max() > 0.1 * along_y.max()


@pytest.mark.parametrize(("view", "tangent"), [(60, (1.0, 0.0, 0.0)), (60, (0.0, 1.0, 0.0)), (20, (1.0, 0.0, 0.0))])
def test_an_anisotropic_metal_in_a_uniform_world_has_its_own_albedo(penumbra, view, tangent):
    """Under a uniform world an anisotropic metal sends back the isotropic one's light (same
    alpha_x alpha_y, same multiple-scattering gain) times the ratio of the two lobes' albedos
    integrated in numpy (what the stretched lobe sends below the surface is lost), within 2 %
    (the frame's drawn reflections: 4 a pixel x 16 samples)."""
    aniso = _plane(_principled(0.5, 0.9, tangent=tangent), view, samples=16)
    iso = _plane(_principled(0.5, 0.0), view, samples=16)
    v = np.array([0.0, -math.sin(math.radians(view)), math.cos(math.radians(view))])
    ax, ay = _principled_alphas(0.5, 0.9)
    if tangent[1] == 1.0:  # the lobe's x axis along the world's y: turn the view into its frame
        v = np.array([v[1], -v[0], v[2]])
    a = 0.25
    ratio = analytic.ggx_aniso_albedo(ax, ay, v) / analytic.ggx_aniso_albedo(a, a, v)
    assert np.allclose(aniso / iso, ratio, rtol=0.02), (aniso / iso, ratio)
    if view == 60:
        assert abs(ratio - 1.0) > 0.02  # the anisotropy shows


def test_anisotropic_zero_is_the_isotropic_surface(penumbra, gpu_call):
    """Anisotropic 0: the same image bit for bit as a Principled BSDF never given anisotropy,
    with no NODE_ANISO variant; above 0 the variant has it."""
    off = {"Anisotropic Rotation": 0.3}  # an input of anisotropy 0
    (plain, zero, aniso), compiled = group_off_and_on(gpu_call, off, {"Anisotropic": 1.0}, "NODE_ANISO")
    assert np.array_equal(plain, zero) and compiled == [False, True]
    assert not np.array_equal(plain, aniso)


@pytest.mark.parametrize(("rough", "amount", "elevation"), [(0.0, 1.0, 40), (1.0, 1.0, 30), (0.2, 1.0, 2)])
def test_the_anisotropic_extremes(penumbra, rough, amount, elevation):
    """Roughness 0 (both axes at the floor), roughness 1 (alpha_x clamped to 1, as Cycles), a
    sun 2 degrees over the horizon: finite and >= 0 (the harness checks it) and the numpy lobe's
    value within 5 % (or 1e-4 where it is dark)."""
    v, to_light = _directions(50, elevation, 0.4)
    ax, ay = _principled_alphas(rough, amount)
    ref = SUN * _metal(ax, ay, v, to_light)
    ours = _plane(_principled(rough, amount), 50, elevation, sun_azimuth=0.4)
    assert np.isfinite(ours).all()
    assert np.allclose(ours, ref, rtol=0.05, atol=1e-4), (ours, ref)


@pytest.mark.parametrize(("tangent", "at"), [((1.0, 0.0, 0.0), (0.0, 0.0)), (None, (70.0, 70.0))])
def test_the_anisotropic_lobe_is_cycles_under_a_sun(penumbra, tangent, at):
    """A brushed metal (Anisotropic 1, roughness 0.4) under a sun, its tangent linked along x or
    Cycles' radial one (seen around (70, 70), where it runs diagonally): Cycles' own value at
    one sample (a sun at angle 0 is sampled exactly) within 2 %."""
    view, elevation, azimuth = 50, 35, 0.6

    make = _principled(0.4, 1.0, tangent=tangent)
    ours = plane_mean(make, view, elevation, 1, azimuth, at=at)
    cycles = plane_mean(make, view, elevation, 1, azimuth, engine="CYCLES", at=at)
    assert cycles.mean() > 1e-3
    assert np.allclose(ours, cycles, rtol=0.02), (ours, cycles)
