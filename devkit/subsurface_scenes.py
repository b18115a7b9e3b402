"""Scenes and references of the subsurface tests and of ``tools/fit_random_walk.py``: a plane
lit across the hard edge of a spot, and Burley's profile as a pixel kernel that convolves a
render of the same plane without subsurface (what the diffusion must make of it)."""

import math

import numpy as np

from devkit import analytic, scenes


def material(base=(0.8, 0.5, 0.3), weight=1.0, radius=(1.0, 0.2, 0.1), scale=0.05, method="BURLEY"):
    """A Principled BSDF without specular: ``base`` of which ``weight`` scatters below the
    surface, Subsurface Radius x Scale by ``method`` (BURLEY, RANDOM_WALK)."""
    mat = scenes.material("Skin", base, roughness=0.5, specular=0.0)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.subsurface_method = method
    bsdf.inputs["Subsurface Weight"].default_value = weight
    bsdf.inputs["Subsurface Radius"].default_value = radius
    bsdf.inputs["Subsurface Scale"].default_value = scale
    return mat


def spot_edge_scene(make, size=128, width=2.0):
    """A plane seen from above (orthographic, ``width`` across, ``size`` pixels) lit by a
    hard-edged spot high above: the edge of its cone crosses the view near x = 0, lit on the -x
    side; no world light. ``make()`` gives the plane's material."""
    scene = scenes.empty_scene(size, size)
    scenes.set_world(scene, (0.0, 0.0, 0.0))
    scenes.plane(scene, size=40.0, mat=make())
    scenes.camera(scene, (0.0, 0.0, 5.0), (0.0, 0.0, 0.0), ortho_scale=width, clip=(0.1, 20.0))
    half = math.radians(30.0)
    height = 10.0
    scenes.light(
        scene,
        "Spot",
        "SPOT",
        20000.0,
        location=(-height * math.tan(half), 0.0, height),
        spot_size=2 * half,
        spot_blend=0.0,
        shadow_soft_size=0.0,
    )
    return scene


def burley_kernel(d, pixel, reach):
    """Burley's profile integrated over each pixel of a (2 reach + 1)^2 grid of ``pixel``-wide
    pixels (8 x 8 points a pixel), the centre pixel taking what the others leave of 1."""
    sub = (np.arange(8) + 0.5) / 8 - 0.5
    offsets = np.arange(-reach, reach + 1)
    x = (offsets[:, None] + sub[None, :]).ravel() * pixel
    xx, yy = np.meshgrid(x, x)
    r = np.hypot(xx, yy)
    density = analytic.burley_radial(d, r) / (2 * math.pi * np.maximum(r, 1e-12)) / analytic.BURLEY_TRUNCATE_CDF
    n = 2 * reach + 1
    kernel = (density * (pixel / 8) ** 2).reshape(n, 8, n, 8).sum(axis=(1, 3))
    kernel[reach, reach] = 0.0
    kernel[reach, reach] = 1.0 - kernel.sum()
    return kernel


def convolve_burley(image, d, pixel):
    """``image`` (h, w) convolved with Burley's profile of distance ``d`` (world units) on
    ``pixel``-wide pixels, its borders extended (by the FFT of the padded image)."""
    reach = int(math.ceil(analytic.BURLEY_TRUNCATE * d / pixel))
    kernel = burley_kernel(d, pixel, reach)
    padded = np.pad(image, reach, mode="edge")
    k = np.zeros_like(padded)
    k[: 2 * reach + 1, : 2 * reach + 1] = kernel
    k = np.roll(k, (-reach, -reach), axis=(0, 1))
    return np.real(np.fft.ifft2(np.fft.fft2(padded) * np.fft.fft2(k)))[reach:-reach, reach:-reach]
