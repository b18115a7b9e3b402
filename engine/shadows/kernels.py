"""Filter kernels: plain numpy, no bpy and no gpu.

Every kernel is normalised here once and handed to the shaders as data, so the GLSL never
re-derives weights (and a Gaussian typo cannot hide in a shader).
"""

import numpy as np


def gaussian_1d(radius, sigma=None):
    """Normalised 1-D Gaussian weights for offsets ``-radius..radius``.

    ``sigma`` defaults to ``radius / 2`` (the kernel then spans +-2 sigma). A radius of 0, or a
    sigma of 0, is the identity kernel ``[1]``.
    """
    radius = max(0, int(radius))
    if sigma is None:
        sigma = radius / 2.0
    if radius == 0 or sigma <= 0.0:
        w = np.zeros(2 * radius + 1)
        w[radius] = 1.0
        return w
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    w = np.exp(-(x * x) / (2.0 * sigma * sigma))
    return w / w.sum()


def pcf_kernel(size, sigma=None):
    """Normalised ``size`` x ``size`` Gaussian weights of percentage-closer filtering
    (Reeves, Salesin and Cook 1987, "Rendering Antialiased Shadows with Depth Maps").

    Returns an array of rows ``(dx, dy, weight)`` with integer texel offsets. ``size`` is made
    odd; ``sigma`` defaults to ``size / 5`` texels (one texel for the usual 5x5 kernel).
    """
    w1 = pcf_weights(size, sigma)
    r = len(w1) // 2
    w2 = np.outer(w1, w1)
    w2 /= w2.sum()
    dy, dx = np.mgrid[-r : r + 1, -r : r + 1]
    return np.stack([dx.ravel(), dy.ravel(), w2.ravel()], axis=1)


def pcf_weights(size, sigma=None):
    """The 1-D factor of ``pcf_kernel``: ``size`` (made odd) normalised Gaussian weights whose
    outer product is the NxN kernel. The lit pass compiles these in as constants."""
    size = max(1, int(size))
    if size % 2 == 0:
        size += 1
    r = size // 2
    if sigma is None:
        sigma = max(size / 5.0, 1e-6)
    return gaussian_1d(r, sigma) if r > 0 else np.ones(1)


RING = 8  # samples per ring of the jittered disk; the outer ring is evaluated first


def jitter_disk(size=32, samples=16, seed=1):
    """Per-pixel jittered disk samples, stored in a 3-D texture indexed by the pixel, with an
    early exit when the outer ring agrees (Uralsky 2005, "Efficient Soft-Edged Shadows Using
    Pixel Shader Branching", GPU Gems 2 ch. 17); strata warped to the disk by polar mapping.

    Returns (size, size, samples, 2) offsets inside the unit disk. Samples come in rings of
    ``RING``, outermost ring first, so a shader can test the outer ring and stop early when it
    agrees. Strata: ring i covers radii sqrt((i..i+1)/rings) (equal areas), angle sector k covers
    2*pi*(k..k+1)/RING; each sample is jittered inside its stratum, independently per pixel.
    Deterministic for a given seed, so frames are reproducible across machines.
    """
    samples = max(RING, int(samples) // RING * RING)
    rings = samples // RING
    rng = np.random.default_rng(seed)
    ju = rng.random((size, size, rings, RING))
    jv = rng.random((size, size, rings, RING))
    i = np.arange(rings)[::-1][None, None, :, None]  # outer ring first
    k = np.arange(RING)[None, None, None, :]
    r = np.sqrt((i + ju) / rings)
    a = 2.0 * np.pi * (k + jv) / RING
    out = np.stack([r * np.cos(a), r * np.sin(a)], axis=-1)
    return out.reshape(size, size, samples, 2)
