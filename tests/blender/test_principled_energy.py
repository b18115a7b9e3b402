"""A rough Principled dielectric against Blender's own BSDF, integrated in numpy
(devkit.analytic.principled_dielectric: GGX, height-correlated Smith, the exact dielectric
Fresnel, multiple scattering as Cycles' microfacet_ggx_preserve_energy adds it, the diffuse
weighted by 1 - the specular's albedo as closure_layering_weight does). That reference agrees
with Cycles (direct light only, 128 spp) within 0.3 % on every case here.

The plane fills an orthographic view, so every pixel sees the same angles and the image mean
is one evaluation of the BSDF. Penumbra's Karis fit of the specular albedo (before the
tabulated one) left the diffuse 2.5 % too bright at a grazing view under a low sun and the
world's light 3.7-4.5 % too dark there (57 % on the specular alone); the bounds below sit
between those errors and the measured ones (Blender 5.2 and 4.5 alike).
"""

import math

import numpy as np
import pytest

from devkit import analytic, scenes
from devkit.plane_scenes import SUN, WORLD, plane_mean


def _plane(view_deg, rough, base, sun_elevation=None):
    def make():
        return scenes.material("Rough", (base, base, base), roughness=rough, specular=0.5)

    return float(plane_mean(make, view_deg, sun_elevation, 4, sun_angle=math.radians(0.5)).mean())


@pytest.mark.parametrize(
    ("rough", "elevation", "bound"),
    # measured -1.3 % and -0.5 % (the Karis fit: +2.5 % and -2.7 %); the rest is the
    # multiple scattering each light's specular still lacks (docs/design.md)
    [(0.8, 15, 0.02), (0.8, 45, 0.02)],
)
def test_rough_dielectric_under_a_sun_matches_blenders_bsdf(penumbra, rough, elevation, bound):
    t, z = math.radians(80), math.radians(90 - elevation)
    # The camera sits at -y looking towards +y; the sun shines from +y (forward scattering).
    v = (0.0, -math.sin(t), math.cos(t))
    to_light = (0.0, math.sin(z), math.cos(z))
    ref = SUN * sum(analytic.principled_dielectric(0.45, rough, v, to_light))
    ours = _plane(80, rough, 0.45, elevation)
    assert ours / ref - 1.0 == pytest.approx(0.0, abs=bound), (ours, ref)


@pytest.mark.parametrize(
    ("rough", "base"),
    # measured -0.0 %, +0.0 % and +0.2 % (the Karis fit: -3.7 %, -4.5 % and -57 %)
    [(1.0, 0.45), (0.8, 0.45), (0.8, 0.0)],
)
def test_rough_dielectric_under_the_world_matches_blenders_bsdf(penumbra, rough, base):
    ref = WORLD * analytic.principled_dielectric_albedo(base, rough, math.cos(math.radians(80)))
    ours = _plane(80, rough, base)
    assert ours / ref - 1.0 == pytest.approx(0.0, abs=0.01), (ours, ref)
    assert np.isfinite(ours)
