"""One evaluation of a BSDF as a render: a plane filling an orthographic view, so every pixel
sees the same angles and the image mean is the BSDF's value for that view and light (the
Principled BSDF's tests: energy, coat, film, sheen, anisotropy).

The camera looks from -y towards +y, ``view_deg`` from the plane's normal (+z); a sun of
``elevation`` shines from +y, turned by ``azimuth`` about z; without a sun the world is a
uniform grey of ``WORLD``."""

import math

from devkit import engines, scenes
from devkit.render import render

SUN = 3.0  # the sun's irradiance (W/m^2)
WORLD = 0.5  # the uniform world's radiance


def directions(view_deg, elevation, azimuth=0.0):
    """(towards the camera, towards the sun) as unit vectors about +z."""
    t, z = math.radians(view_deg), math.radians(90 - elevation)
    s = (0.0, math.sin(z), math.cos(z))
    c, n = math.cos(azimuth), math.sin(azimuth)
    return (0.0, -math.sin(t), math.cos(t)), (c * s[0] - n * s[1], n * s[0] + c * s[1], s[2])


def plane_scene(make, view_deg, elevation=None, azimuth=0.0, at=(0.0, 0.0), sun_angle=0.0, size=16):
    """A fresh scene (``make()`` is called in it for the plane's material): the plane seen at
    ``view_deg`` around its point ``at``, under a sun of ``elevation`` (the sun's ``sun_angle``
    in radians) or, with ``elevation`` None, under the uniform world."""
    scene = scenes.empty_scene(size, size)
    scenes.plane(scene, size=400.0, mat=make())
    t = math.radians(view_deg)
    scenes.camera(scene, (at[0], at[1] - 20 * math.sin(t), 20 * math.cos(t)), (t, 0, 0), ortho_scale=1.0)
    if elevation is None:
        scenes.set_world(scene, (WORLD, WORLD, WORLD))
    else:
        z = math.radians(90 - elevation)
        scenes.light(scene, "Sun", "SUN", SUN, rotation=(-z, 0, azimuth), angle=sun_angle)
    return scene


def plane_mean(make, view_deg, elevation=None, samples=1, azimuth=0.0, engine="PENUMBRA", **scene_args):
    """The mean RGB of ``plane_scene``'s render by ``engine`` at ``samples``."""
    scene = plane_scene(make, view_deg, elevation, azimuth, **scene_args)
    key = "samples" if engine == "CYCLES" else "render_samples"
    engines.configure(scene, engine, **{key: samples})
    return render(scene)["Combined"][..., :3].mean(axis=(0, 1))
