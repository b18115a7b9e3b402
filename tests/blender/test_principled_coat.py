"""The Principled BSDF's coat (shaders/lib/lit_bsdf.glsl coat_setup, coat_brdf) against the same
layering integrated in numpy (devkit.analytic: the coat a dielectric GGX of its roughness and
IOR, what it reflects towards the viewer kept from the layers below, its tint over the path
through it, as Cycles' Principled BSDF layers them). A plane fills an orthographic view, so every
pixel sees the same angles and the image mean is one evaluation of the BSDF."""

import math

import numpy as np
import pytest

from devkit import analytic, scenes
from devkit.plane_scenes import SUN, WORLD, plane_mean
from devkit.plane_scenes import directions as _directions
from devkit.render import group_off_and_on


def _material(base, rough, weight, coat_rough, ior=1.5, tint=(1.0, 1.0, 1.0), specular=0.5):
    mat = scenes.material("Coated", (base, base, base), roughness=rough, specular=specular)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Coat Weight"].default_value = weight
    bsdf.inputs["Coat Roughness"].default_value = coat_rough
    bsdf.inputs["Coat IOR"].default_value = ior
    bsdf.inputs["Coat Tint"].default_value = (*tint, 1.0)
    return mat


def _plane(make, view_deg, sun_elevation=None, samples=4, sun_azimuth=0.0):
    return plane_mean(make, view_deg, sun_elevation, samples, sun_azimuth, sun_angle=math.radians(0.5))


@pytest.mark.parametrize(
    ("weight", "coat_rough", "tint", "elevation"),
    [(1.0, 0.3, (1.0, 1.0, 1.0), 40), (0.5, 0.5, (1.0, 1.0, 1.0), 25), (1.0, 0.2, (0.9, 0.6, 0.3), 40)],
)
def test_a_coat_under_a_sun_matches_the_layered_bsdf(penumbra, weight, coat_rough, tint, elevation):
    """A rough grey dielectric (roughness 0.8) under a coat, seen at 60 degrees under a sun:
    the layers below through what the coat lets through, plus the coat's own highlight, within
    3 % per channel (the lights' specular carries no multiple scattering: docs/design.md)."""
    v, to_light = _directions(60, elevation)
    below = analytic.coat_below(weight, coat_rough, v[2], 1.5, tint)
    base = sum(analytic.principled_dielectric(0.45, 0.8, v, to_light))
    ref = SUN * (below * base + analytic.coat_reflectance(weight, coat_rough, v, to_light))
    ours = _plane(lambda: _material(0.45, 0.8, weight, coat_rough, tint=tint), 60, elevation)
    assert np.allclose(ours, ref, rtol=0.03), (ours, ref)
    if weight == 1.0 and tint == (1.0, 1.0, 1.0):
        uncoated = _plane(lambda: scenes.material("Plain", (0.45, 0.45, 0.45), roughness=0.8), 60, elevation)
        assert abs(ours.mean() - uncoated.mean()) > 0.02 * uncoated.mean()  # the coat changes it


@pytest.mark.parametrize(("coat_rough", "tint"), [(0.3, (1.0, 1.0, 1.0)), (0.05, (0.5, 0.7, 1.0))])
def test_the_coat_keeps_the_worlds_energy(penumbra, coat_rough, tint):
    """A white diffuse (albedo 1, no specular of its own) under a coat in a uniform world: what
    the coat reflects is what the diffuse below no longer gets, so an untinted coat sends back
    exactly the world (within 0.5 %); a tinted one (1 - E) tint^(1 / cos_t) + E of it."""
    ours = _plane(lambda: _material(1.0, 0.5, 1.0, coat_rough, tint=tint, specular=0.0), 60)
    mu = math.cos(math.radians(60))
    ref = WORLD * (analytic.coat_below(1.0, coat_rough, mu, 1.5, tint) + analytic.coat_albedo(coat_rough, mu, 1.5))
    assert np.allclose(ours, ref, rtol=0.01), (ours, ref)
    if tint == (1.0, 1.0, 1.0):
        assert np.allclose(ours, WORLD, rtol=0.005), ours


def test_the_coats_reflection_is_reciprocal(penumbra):
    """A black base under a coat (only the coat reflects): swapping the view and the sun's
    directions gives the same BRDF, f(v, l) = f(l, v), within 1 %."""

    def make():
        return _material(0.0, 0.5, 1.0, 0.35, specular=0.0)

    a, b = 50.0, 70.0  # angles from the normal
    forward = _plane(make, a, 90.0 - b, samples=1)  # view a, sun at b (elevation 90 - b)
    backward = _plane(make, b, 90.0 - a, samples=1)
    f_forward = forward.mean() / (SUN * math.cos(math.radians(b)))
    f_backward = backward.mean() / (SUN * math.cos(math.radians(a)))
    assert f_forward > 1e-3
    assert f_forward == pytest.approx(f_backward, rel=0.01)
    v, to_light = _directions(a, 90.0 - b)
    ref = analytic.coat_reflectance(1.0, 0.35, v, to_light) / math.cos(math.radians(b))
    assert f_forward == pytest.approx(ref, rel=0.03)


def test_coat_weight_zero_is_the_surface_without_a_coat(penumbra, gpu_call):
    """Coat Weight 0: the same image bit for bit as a Principled BSDF never given a coat, with
    no coat in its program (no NODE_COAT variant); above 0 the variant has it."""
    off = {"Coat Roughness": 0.2, "Coat Tint": (0.2, 0.5, 0.9, 1.0)}  # inputs of a coat of weight 0
    (plain, zero, coated), compiled = group_off_and_on(gpu_call, off, {"Coat Weight": 1.0}, "NODE_COAT")
    assert np.array_equal(plain, zero) and compiled == [False, True]
    assert not np.array_equal(plain, coated)


def test_the_groups_not_drawn_are_named_and_the_coat_is_not(penumbra):
    """A coat, a sheen, a subsurface, a thin film and anisotropy (the Principled BSDF's and a
    Glossy BSDF's) are drawn, not named, and the Material panel's summary says so; what the
    subsurface does not draw (its Anisotropy) is named."""
    from penumbra.engine.scene.materials import material_from_blender

    scenes.empty_scene(8, 8)
    mat = _material(0.5, 0.5, 1.0, 0.2)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    for name, value in (("Sheen Weight", 1.0), ("Subsurface Weight", 0.5), ("Anisotropic", 0.5)):
        bsdf.inputs[name].default_value = value
    bsdf.inputs["Thin Film Thickness"].default_value = 300.0
    bsdf.inputs["Subsurface Anisotropy"].default_value = 0.5
    read = material_from_blender(mat)
    assert any("Subsurface Anisotropy (the diffusion is isotropic)" in m for m in read.messages), read.messages
    drawn = ("Coat Weight", "Thin Film", "Sheen", "Anisotropic", "Subsurface Weight")
    assert not any(name in m for m in read.messages for name in drawn), read.messages
    tree = read.tree
    assert tree is not None and tree.coat and tree.film and tree.sheen and tree.aniso and tree.sss
    from penumbra.engine.scene.materials import summary

    assert any(text.startswith("Coat:") for _icon, text in summary(read))
    assert any(text.startswith("Sheen:") for _icon, text in summary(read))
    assert any(text.startswith("Anisotropic:") for _icon, text in summary(read))
    assert any(text.startswith("Subsurface:") for _icon, text in summary(read))
    glossy = scenes.material("Brushed", (0.8, 0.8, 0.8))
    tree = glossy.node_tree
    node = tree.nodes.new("ShaderNodeBsdfAnisotropic")
    node.inputs["Anisotropy"].default_value = 0.7
    tree.links.new(node.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    read = material_from_blender(glossy)
    assert read.tree is not None and read.tree.aniso
    assert not any("Anisotropy" in m for m in read.messages), read.messages
