"""The Principled BSDF's Thin Film (shaders/lib/thin_film.glsl, lit_bsdf.glsl) against the same
model in numpy (devkit.analytic.thin_film_fresnel: the Airy summation integrated against the
CIE sensitivities, Belcour and Barla 2017; ggx_reflectance). A plane fills an orthographic
view, so every pixel sees the same angles and the image mean is one evaluation of the BSDF."""

import math

import numpy as np
import pytest

from devkit import analytic, scenes
from devkit.plane_scenes import SUN, plane_mean
from devkit.render import group_off_and_on


def _filmed(base, rough, thickness, film_ior=1.33, ior=1.5, metallic=0.0):
    mat = scenes.material("Filmed", (base, base, base), roughness=rough, metallic=metallic)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["IOR"].default_value = ior
    bsdf.inputs["Thin Film Thickness"].default_value = thickness
    bsdf.inputs["Thin Film IOR"].default_value = film_ior
    return mat


def _plane(make, view_deg, elevation):
    """The plane of material ``make()`` at ``view_deg`` under a sun of ``elevation``, black world."""
    return plane_mean(make, view_deg, elevation, 1, sun_angle=math.radians(0.5))


@pytest.mark.parametrize("thickness", [250.0, 400.0, 650.0])
def test_a_film_on_a_black_dielectric_reflects_as_the_airy_model(penumbra, thickness):
    """A black base (no diffuse): the pixel is the sun's light times the GGX lobe with the
    film's reflectance at the half vector, within 3 % per channel; the film colours it."""
    view, elevation = 40.0, 45.0
    t, z = math.radians(view), math.radians(90 - elevation)
    v, to_light = (0.0, -math.sin(t), math.cos(t)), (0.0, math.sin(z), math.cos(z))
    ref = SUN * analytic.ggx_reflectance(
        lambda c: analytic.thin_film_fresnel(c, thickness, 1.33, 1.5), 0.3, v, to_light
    )
    ours = _plane(lambda: _filmed(0.0, 0.3, thickness), view, elevation)
    assert np.allclose(ours, ref, rtol=0.03, atol=1e-4), (ours, ref)
    assert ours.max() > 1.3 * ours.min()  # iridescent: not grey


def test_specular_tint_and_ior_level_reach_the_film(penumbra):
    """Specular Tint multiplies the film's reflectance and Specular IOR Level moves the base's
    IOR to the one whose F0 is 2 level times the IOR's, as Cycles' principled closure does:
    the airy model at that IOR times the tint, within 3 % per channel."""
    view, elevation, tint, level = 40.0, 45.0, (1.0, 0.6, 0.3), 0.9
    t, z = math.radians(view), math.radians(90 - elevation)
    v, to_light = (0.0, -math.sin(t), math.cos(t)), (0.0, math.sin(z), math.cos(z))
    f0 = ((1.5 - 1.0) / 2.5) ** 2 * 2.0 * level
    eta = (1.0 + math.sqrt(f0)) / (1.0 - math.sqrt(f0))
    ref = (
        SUN
        * np.array(tint)
        * analytic.ggx_reflectance(lambda c: analytic.thin_film_fresnel(c, 400.0, 1.33, eta), 0.3, v, to_light)
    )

    def make():
        mat = _filmed(0.0, 0.3, 400.0)
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Specular Tint"].default_value = (*tint, 1.0)
        bsdf.inputs["Specular IOR Level"].default_value = level
        return mat

    ours = _plane(make, view, elevation)
    assert np.allclose(ours, ref, rtol=0.03, atol=1e-4), (ours, ref)


def test_a_vanishing_film_is_the_plain_dielectric(penumbra):
    """A film of 1 nm fades to none: the plane is the same as without a film, within 2 %."""
    filmed = _plane(lambda: _filmed(0.0, 0.3, 1.0), 40.0, 45.0)
    plain = _plane(lambda: scenes.material("Plain", (0.0, 0.0, 0.0), roughness=0.3), 40.0, 45.0)
    assert np.allclose(filmed, plain, rtol=0.02), (filmed, plain)


def test_film_thickness_zero_compiles_no_film(penumbra, gpu_call):
    """Thickness 0: bit for bit the surface without a film, no NODE_FILM variant; above 0 the
    variant has it."""
    on = {"Thin Film Thickness": 400.0}
    (plain, zero, filmed), compiled = group_off_and_on(gpu_call, {"Thin Film IOR": 1.8}, on, "NODE_FILM")
    assert np.array_equal(plain, zero) and compiled == [False, True]
    assert not np.array_equal(plain, filmed)


def test_a_film_on_a_metal_is_named(penumbra):
    from penumbra.engine.scene.materials import material_from_blender

    scenes.empty_scene(8, 8)
    read = material_from_blender(_filmed(0.8, 0.3, 500.0, metallic=1.0))
    assert read.tree is not None and read.tree.film
    assert any("Thin Film on the metallic part is not drawn" in m for m in read.messages), read.messages
    assert not any("Thin Film Thickness is not drawn" in m for m in read.messages)
