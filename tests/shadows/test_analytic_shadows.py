"""Shadow regions against analytic geometry: a ray from every visible plane point towards the
light, tested against the caster box, for every light type and filter, at extreme scales, and
the Shadow render pass."""

import math

import numpy as np
import pytest

from devkit.analytic import camera_matrices, iou, plane_hits, ray_hits_box
from devkit.render import render
from devkit.scenes import WHITE_ALBEDO as ALBEDO

FILTERS = ["NONE", "HARDWARE", "PCF", "JITTER", "PCSS"]


def measure(scene, sun_tilt_deg, scale):
    """(visible-plane mask, analytic shadow mask, luminance, lit-plane radiance) of a
    ``sun_box_scene``."""
    out = render(scene, passes=("Combined", "Depth"))
    color, depth = out["Combined"], out["Depth"][..., 0]
    view, proj, w, h = camera_matrices(scene)
    p, plane_depth = plane_hits(view, proj, w, h)
    on_plane = np.abs(depth - plane_depth) < 1e-3 * 15 * scale
    t = math.radians(sun_tilt_deg)
    d = np.array([0.0, math.sin(t), -math.cos(t)])
    analytic = ray_hits_box(p, -d, (-0.5 * scale, -0.5 * scale, 1.0 * scale), (0.5 * scale, 0.5 * scale, 2.0 * scale))
    lit_value = ALBEDO / math.pi * scene.objects["Sun"].data.energy * math.cos(t)
    lum = color[..., 0]
    return on_plane, analytic, lum, lit_value


@pytest.mark.parametrize("shadow_filter", ["NONE", "PCF"])
@pytest.mark.parametrize("tilt", [0.0, 45.0])
def test_box_shadow_matches_projected_footprint(sun_box_scene, tilt, shadow_filter):
    scene = sun_box_scene(tilt, shadow_filter=shadow_filter)
    on_plane, analytic, lum, lit_value = measure(scene, tilt, 1.0)
    assert on_plane.sum() > 0.5 * on_plane.size
    shadow = lum < 0.5 * lit_value
    assert analytic[on_plane].sum() > 200  # the shadow is in view
    score = iou(shadow[on_plane], analytic[on_plane])
    assert score > 0.98, f"IoU {score:.3f}"  # measured: 1.000 (NONE), 0.9945 (PCF at 45°)
    # Lit plane far from the shadow edge has exactly Blender's sun irradiance (albedo/pi*E*cos).
    interior_lit = on_plane & ~analytic
    np.testing.assert_allclose(np.median(lum[interior_lit]), lit_value, rtol=0.01)
    # Shadow interior is black (no world light in this scene).
    assert np.median(lum[on_plane & analytic]) < 0.02 * lit_value


@pytest.mark.parametrize("scale", [1e-3, 1e3, 1e4])
def test_box_shadow_holds_at_extreme_scales(sun_box_scene, scale):
    scene = sun_box_scene(45.0, scale=scale)
    on_plane, analytic, lum, lit_value = measure(scene, 45.0, scale)
    shadow = lum < 0.5 * lit_value
    score = iou(shadow[on_plane], analytic[on_plane])
    assert score > 0.98, f"IoU {score:.3f} at scale {scale}"
    # No acne: the lit part of the plane is lit everywhere but within 2 px of the edge.
    acne = (on_plane & ~analytic & shadow).sum() / max((on_plane & ~analytic).sum(), 1)
    assert acne < 0.01


@pytest.mark.parametrize("kind", ["SUN", "SPOT", "POINT", "AREA"])
@pytest.mark.parametrize("shadow_filter", FILTERS)
def test_every_light_and_filter_casts_the_analytic_shadow(shadow_scene, analytic_shadow, kind, shadow_filter):
    scene = shadow_scene(kind, shadow_filter)
    _lum, visibility, on_plane, shadowed = analytic_shadow(scene, scene.objects["L"])
    lit = on_plane & ~shadowed
    assert shadowed[on_plane].sum() > 300  # the shadow is in view
    measured = visibility < 0.5
    score = iou(measured[on_plane], shadowed[on_plane])
    assert score > 0.95, f"{kind}/{shadow_filter}: IoU {score:.3f}"
    # No acne: lit plane pixels away from the edge are not darkened.
    assert (lit & measured).sum() / lit.sum() < 0.01


def test_shadow_pass_is_the_visibility_of_direct_light(shadow_scene, analytic_shadow):
    """The Shadow render pass equals (render with shadows) / (render without) for one light."""
    scene = shadow_scene("SPOT", "PCF")
    shadow = render(scene, passes=("Combined", "Depth", "Shadow"))["Shadow"][..., 0]
    _lum, visibility, on_plane, shadowed = analytic_shadow(scene, scene.objects["L"])
    np.testing.assert_allclose(shadow[on_plane], visibility[on_plane], atol=1e-5)
    assert iou((shadow < 0.5)[on_plane], shadowed[on_plane]) > 0.95
    assert np.all((shadow >= 0.0) & (shadow <= 1.0))
