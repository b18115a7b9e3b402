"""Scenes and measurements shared by the shadow tests: a unit box floating over a white
Lambertian plane (``devkit.scenes.box_over_plane``), lit by one light, and its shadow compared
with the analytic one. Fixtures hand out the builders, so each test builds a fresh scene."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.analytic import camera_matrices, plane_hits, ray_hits_box
from devkit.render import render

# The box of box_over_plane() at its default place: a unit cube centred 1.5 over the plane.
BOX_LO, BOX_HI = (-0.5, -0.5, 1.0), (0.5, 0.5, 2.0)


@pytest.fixture
def sun_box_scene(penumbra):
    """``sun_box_scene(sun_tilt_deg, scale=1.0, shadow_filter="PCF", size=192)``: the box over
    a 40-unit plane, both scaled by ``scale``, a sun of strength 3 ("Sun") tilted about X by
    ``sun_tilt_deg``, and a tilted orthographic camera that sees the plane under and behind
    the box; ``size`` x ``size`` pixels, map 2048."""

    def build(sun_tilt_deg, scale=1.0, shadow_filter="PCF", size=192):
        scene = scenes.empty_scene(size, size)
        scenes.box_over_plane(scene, plane_size=40.0 * scale, box_center=(0, 0, 1.5 * scale), box_size=scale)
        scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(sun_tilt_deg), 0, 0))
        fwd = np.array([0.0, math.sin(math.radians(35)), -math.cos(math.radians(35))])
        pos = -fwd * 15.0 * scale + np.array([0, 0.8, 0]) * scale
        scenes.camera(
            scene, tuple(pos), (math.radians(35), 0, 0), ortho_scale=7.0 * scale, clip=(0.1 * scale, 40 * scale)
        )
        scene.penumbra.shadow_filter = shadow_filter
        scene.penumbra.shadow_map_size = 2048
        return scene

    return build


@pytest.fixture
def shadow_scene(penumbra):
    """``shadow_scene(kind, shadow_filter, size=160)``: the box over a 30-unit plane, lit by
    one hard light "L" of ``kind`` ('SUN', 'SPOT', 'POINT', 'AREA') from above; shadows fall
    towards -Y, the camera's side, so the box does not hide them. Map 2048."""

    def build(kind, shadow_filter, size=160):
        scene = scenes.empty_scene(size, size)
        scenes.box_over_plane(scene, plane_size=30.0)
        if kind == "SUN":
            scenes.light(scene, "L", "SUN", 3.0, rotation=(math.radians(-30), 0, 0), angle=0.0)
        elif kind == "SPOT":
            scenes.light(
                scene,
                "L",
                "SPOT",
                800.0,
                location=(0, 2.0, 5.0),
                rotation=(math.radians(-20), 0, 0),
                spot_size=math.radians(100),
                spot_blend=0.0,
                shadow_soft_size=0.0,
            )
        elif kind == "POINT":
            scenes.light(scene, "L", "POINT", 800.0, location=(0.3, 2.0, 5.0), shadow_soft_size=0.0)
        else:
            scenes.light(scene, "L", "AREA", 800.0, location=(0.3, 2.0, 5.0), size=0.01)
        scenes.camera(scene, (0, -9.0, 12.0), (math.radians(37), 0, 0), ortho_scale=8.0, clip=(0.1, 40))
        scene.penumbra.shadow_filter = shadow_filter
        scene.penumbra.shadow_map_size = 2048
        return scene

    return build


def _analytic_shadow(scene, light_ob, lo=BOX_LO, hi=BOX_HI):
    out = render(scene, passes=("Combined", "Depth"))
    lum, depth = out["Combined"][..., 0], out["Depth"][..., 0]
    light_ob.data.use_shadow = False
    unshadowed = render(scene)["Combined"][..., 0]
    light_ob.data.use_shadow = True
    with np.errstate(divide="ignore", invalid="ignore"):
        visibility = np.where(unshadowed > 1e-6, lum / unshadowed, 1.0)
    view, proj, w, h = camera_matrices(scene)
    p, plane_depth = plane_hits(view, proj, w, h)
    on_plane = (np.abs(depth - plane_depth) < 1e-3 * np.maximum(plane_depth, 1.0)) & (unshadowed > 1e-6)
    if light_ob.data.type == "SUN":
        d = -np.array(light_ob.matrix_world.to_3x3().col[2])
        to_light = np.broadcast_to(-d, p.shape)
    else:
        to_light = np.array(light_ob.location) - p
    shadowed = ray_hits_box(p, to_light, lo, hi)
    return lum, visibility, on_plane, shadowed


@pytest.fixture
def analytic_shadow(penumbra):
    """``analytic_shadow(scene, light_ob, lo=BOX_LO, hi=BOX_HI)`` renders ``scene`` and returns
    (luminance, shadow visibility, visible-plane mask, analytic shadow mask) for the z = 0
    plane and the caster box [lo, hi]; rows bottom-up.

    Visibility is the render divided by the same render with the light's shadow off, so the
    light's falloff and cone do not count as shadow."""
    return _analytic_shadow
