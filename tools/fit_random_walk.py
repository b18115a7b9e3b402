"""Fits Cycles' Random Walk subsurface as Burley's profile: the factors shaders/nodes/shader.glsl
``node_sss_walk`` draws it with, measured from Cycles itself.

    .venv/blender-5.2/bin/python -m tools.fit_random_walk [--quick]

Cycles' Random Walk takes Radius x Scale / 4 pi as the mean free path l of a volume whose
single-scattering albedo it inverts from the surface albedo A (Chiang, Kutz and Burley 2016), and
walks the light through it. Penumbra draws every subsurface as Burley's normalized diffusion
(Christensen and Burley 2015), which Cycles' Christensen-Burley method uses with d = l. Here the
walk is measured: a plane lit across the hard edge of a spot (``devkit.subsurface_scenes``),
rendered by Cycles with the Random Walk (``--spp``, 512) and without subsurface (the light each
point receives), with four base colours, so twelve albedos from 0.05 to 0.98. For each albedo,
the rows of the view's centre of the walk's render are fitted by the plain render convolved with
Burley's profile of d = k l times an amplitude c0 (k on a log grid, c0 by least squares): k is
how far the walk spreads the light, c0 how much of it leaves towards a camera on the normal
(the walk's light leaves unlike a Lambertian surface's). A polynomial in A is then fitted to
each, over the albedos up to 0.9 (above it the profile outgrows the view):

    k(A) = k0 + k1 A + k2 A^2,   c0(A) = c0 + c1 A

with their largest relative residuals; ``node_sss_walk`` carries them. The renders are cached
under out/reference_cache by Blender's version; ``--quick`` renders 128 spp (a check of the tool).
"""

import argparse
import math
import sys

import numpy as np

from devkit import engines, session, subsurface_scenes
from devkit.render import cached_image, render

SIZE, WIDTH, ELL = 128, 2.0, 0.02  # pixels, the view's width, the walk's mean free path
BASES = ((0.05, 0.1, 0.2), (0.3, 0.45, 0.6), (0.7, 0.8, 0.9), (0.95, 0.98, 0.4))
FIT_BELOW = 0.9  # the polynomials' albedos (above, the profile outgrows the view)
ROWS = slice(34, 94)
COLS = slice(16, 112)


def _render(base, weight, spp):
    def make():
        mat = lambda: subsurface_scenes.material(  # noqa: E731
            base=base, weight=weight, radius=(1.0, 1.0, 1.0), scale=ELL * 4 * math.pi, method="RANDOM_WALK"
        )
        scene = subsurface_scenes.spot_edge_scene(mat, SIZE, WIDTH)
        engines.configure(scene, "CYCLES", samples=spp)
        return render(scene)["Combined"][..., :3]

    return cached_image("random_walk", __file__, f"{base}-{weight}-{spp}", make)


def fit_channel(walk, plain):
    """(k, c0, residual over the lit light) of one channel's renders."""
    y = walk[ROWS, COLS].mean(axis=0)
    best = None
    for k in np.geomspace(0.3, 20.0, 120):
        e = subsurface_scenes.convolve_burley(plain, k * ELL, WIDTH / SIZE)[ROWS, COLS].mean(axis=0)
        c0 = float((e * y).sum() / (e * e).sum())
        err = float(np.abs(y - c0 * e).mean() / y.max())
        if best is None or err < best[2]:
            best = (float(k), c0, err)
    return best


def run(spp):
    rows = []
    for base in BASES:
        walk = _render(base, 1.0, spp)
        plain = _render(base, 0.0, 16)
        for c, albedo in enumerate(base):
            k, c0, err = fit_channel(walk[..., c], plain[..., c])
            rows.append((albedo, k, c0, err))
            print(f"A {albedo:.2f}  k {k:6.3f}  c0 {c0:.3f}  residual {err:.4f}", file=sys.stderr)
    data = np.array(sorted(r for r in rows if r[0] <= FIT_BELOW))
    pk = np.polyfit(data[:, 0], data[:, 1], 2)[::-1]
    pc = np.polyfit(data[:, 0], data[:, 2], 1)[::-1]
    dk = np.abs(np.polyval(pk[::-1], data[:, 0]) / data[:, 1] - 1).max()
    dc = np.abs(np.polyval(pc[::-1], data[:, 0]) / data[:, 2] - 1).max()
    print(f"k(A) = {pk[0]:.3f} + {pk[1]:.3f} A + {pk[2]:.3f} A^2 (within {dk:.1%})")
    print(f"c0(A) = {pc[0]:.3f} + {pc[1]:.3f} A (within {dc:.1%})")
    print(f"residuals {data[:, 3].min():.4f}-{data[:, 3].max():.4f} of the lit light")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="128 spp")
    parser.add_argument("--spp", type=int, default=512)
    args = parser.parse_args(argv)
    session.load_penumbra().register()
    with session.stdout_to_stderr():
        run(128 if args.quick else args.spp)
    return 0


if __name__ == "__main__":
    sys.exit(main())
