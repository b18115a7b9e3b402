"""Benchmarks, one command each (modules in tools/benchmarks/):

    camera    depth of field: error against time vs Cycles (same lens, 1024 spp) and EEVEE
              -> <out>/camera.csv, camera.png
    assets    glTF assets (devkit/gltf/) imported with Blender's importer: error against Cycles and
              time, Penumbra against EEVEE -> <out>/assets.csv, assets.png
    frame     render time of Penumbra, EEVEE, Workbench and Cycles on the demo scene
              -> <out>/benchmark.csv
    passes    Blender's light and colour passes against Cycles' (max bounces 0), the passes'
              algebra, and what asking for passes costs -> <out>/passes.csv, passes_cost.csv
    perf      frame cost and scaling as ratios to Workbench: resolution, viewport redraw,
              lights, objects, instances, triangles, extraction -> <out>/perf.csv
    reflections  glossy surfaces under a real HDRI, a polished floor, glass: error against time,
              Penumbra (scene reflections, world image, SH) vs Cycles one glossy bounce, EEVEE
              -> <out>/reflections.csv, reflections.png; --cost: on against off, 160x90 and 960x540
    samples   render samples: error against time vs Cycles spp and EEVEE, cost per sample,
              an edge close-up -> <out>/samples.csv, samples.png, samples_closeup.png
    principled  the Principled BSDF's input groups (the coat at its extremes) on spheres under a
              sun and an HDRI, against Cycles 1024 spp and EEVEE -> <out>/principled.csv
    post      cost of each post layer; separable against direct 2-D blur -> <out>/post_costs.csv
    shadows   shadow error against frame time, scaling, per-frame work, JITTER early out
              -> <out>/shadow_tradeoff.csv, shadow_pareto.png, scaling.csv, scaling.png
    soak      process memory over repeated F12 renders (300 of a 160x90 frame by default)
              -> <out>/soak.csv
    terminator  frame time with Shadow Terminator Geometry Offset 0 against 0.1 (smooth
              spheres) -> stdout
    volumes   fog, light shafts and a backlit box: single scattering through the shadow maps,
              error against time vs Cycles (Volume Bounces 0) and EEVEE
              -> <out>/volumes.csv, volumes.png
    world     the world's light with visibility: error against time on scenes lit by the world
              alone, Penumbra (world shadows on and off, one bounce) against Cycles and EEVEE
              -> <out>/world.csv, world.png

Run from the repository root, e.g.::

    .venv/blender-5.2/bin/python -m tools.bench frame --out out --runs 5
    .venv/blender-5.2/bin/python -m tools.bench shadows --quick

Markdown tables for the README go to stdout, progress and Blender's own output to stderr.
``python -m tools.bench <command> --help`` lists each command's options.
"""

import argparse

from devkit import session
from tools.benchmarks import (
    assets,
    camera,
    frame,
    passes,
    perf,
    post,
    principled,
    reflections,
    samples,
    shadows,
    soak,
    terminator,
    volumes,
    world,
)

COMMANDS = {
    "assets": assets,
    "camera": camera,
    "frame": frame,
    "passes": passes,
    "perf": perf,
    "post": post,
    "principled": principled,
    "reflections": reflections,
    "samples": samples,
    "shadows": shadows,
    "soak": soak,
    "terminator": terminator,
    "volumes": volumes,
    "world": world,
}


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="python -m tools.bench", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="{" + ",".join(COMMANDS) + "}")
    for name, module in COMMANDS.items():
        command = sub.add_parser(
            name, help=module.HELP, description=module.__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
        )
        module.add_arguments(command)
    args = parser.parse_args(argv)
    return COMMANDS[args.command].run(args)


if __name__ == "__main__":
    session.run(main)
