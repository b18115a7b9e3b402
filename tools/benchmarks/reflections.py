"""What glossy surfaces see: error against time on ``devkit.reflection_scenes``.

``hdri_spheres`` (a mirror, a brushed metal and a polished red ball on a ground under
Blender's own forest.exr, turned 40 deg) and ``polished_floor`` (a dark polished floor under a
sun and a dim sky, objects on it), in this one process:

- Penumbra at 4, 16, 64 render samples: glossy lobes read the Environment Texture prefiltered
  by roughness (``features/world_env.py``).
- Penumbra with that technique left out of the registry (glossy lobes read the world's SH
  light: what the frame did before it) at 16 and 64. The world ratio's sharp-lobe share
  (``lit_world.glsl`` ``world_ratio_share``) is in both: it is not a technique of its own.
- Cycles with one glossy bounce (max_bounces 1) at 16 and 64 spp, EEVEE once
  (``devkit.engines``: 16 TAA samples, no probe baked).

Error: the mean absolute difference of display RGB against Cycles at 256 spp (one glossy
bounce, the same pixel filter; cached in out/reference_cache) over the objects' pixels
(Workbench's flat object mask), over every pixel, and over the mirror sphere's upper half
(the sky it reflects; where its lower half shows the ground and its neighbours, Cycles traces
them, Penumbra shows the image's own ground: no scene reflections yet). Time: the median of
``--runs`` F12 renders after the measured one.

-> ``<out>/reflections.csv``; a Markdown table to stdout.
"""

import contextlib
import sys
import time
from pathlib import Path

import bpy
import numpy as np

from devkit import reflection_scenes as rs
from devkit import report, session, timing
from devkit.engines import EEVEE_SAMPLES

HELP = "glossy surfaces: error against time, Penumbra (image or SH reflections) vs Cycles and EEVEE"
FIELDS = ["scene", "config", "samples", "time_s", "mae_objects", "mae_all", "mae_mirror_upper"]
IMAGE = "Penumbra"
SH = "Penumbra, SH reflections"
CYCLES = "Cycles, 1 glossy bounce"
EEVEE = f"EEVEE ({EEVEE_SAMPLES} TAA)"


def log(message):
    print(f"bench reflections: {message}", file=sys.stderr, flush=True)


def configs(quick):
    samples = (4, 16) if quick else (4, 16, 64)
    out = [(IMAGE, "PENUMBRA", n, {"render_samples": n}) for n in samples]
    out += [(SH, "PENUMBRA", n, {"render_samples": n}) for n in samples[1:]]
    out += [(CYCLES, "CYCLES", n, {"samples": n}) for n in (16, 64)]
    out.append((EEVEE, "EEVEE", EEVEE_SAMPLES, {}))
    return out


def upper_half(mask):
    rows = np.nonzero(mask.any(axis=1))[0]
    out = mask.copy()
    out[: int(np.ceil(0.5 * (rows.min() + rows.max())))] = False
    return out


@contextlib.contextmanager
def without_world_env():
    """Renderers made inside leave ``world_env`` out of their registry."""
    from penumbra.engine.frame import renderer

    kept = renderer.REGISTRY
    renderer.REGISTRY = tuple(f for f in kept if f.name != "world_env")
    try:
        yield
    finally:
        renderer.REGISTRY = kept


def sweep(args, w, h):
    rows = []
    for name in rs.SCENES:
        log(f"{name}: Cycles reference, 256 spp at {w}x{h}")
        reference = rs.cycles_reference(name, 256, w, h, cache_dir=args.cache)
        objects = rs.object_mask(name, w, h)
        mirror = upper_half(rs.object_mask(name, w, h, ("Mirror",))) if name == "hdri_spheres" else None
        scene = rs.build(name, w, h)
        for label, engine, n, settings in configs(args.quick):
            log(f"{name}: {label}, {n}")
            rs.use_engine(scene, engine, **settings)
            with without_world_env() if label == SH else contextlib.nullcontext():
                image = rs.render_display(scene)
                seconds = timing.render(args.runs, warmup=0).median
            rows.append(
                {
                    "scene": name,
                    "config": label,
                    "samples": n,
                    "time_s": seconds,
                    "mae_objects": rs.object_mae(image, reference, objects),
                    "mae_all": float(np.abs(image - reference).mean()),
                    "mae_mirror_upper": None if mirror is None else rs.object_mae(image, reference, mirror),
                }
            )
            log(f"  {rows[-1]}")
    return rows


def markdown(rows):
    cells = [
        [
            r["scene"],
            r["config"],
            r["samples"],
            f"{r['time_s']:.3f}",
            f"{r['mae_objects']:.4f}",
            f"{r['mae_all']:.4f}",
            "" if r["mae_mirror_upper"] is None else f"{r['mae_mirror_upper']:.4f}",
        ]
        for r in rows
    ]
    header = ["Scene", "Configuration", "Samples", "Time (s)", "MAE objects", "MAE all", "MAE mirror, upper"]
    return report.markdown_table(header, cells, align="llrrrrr")


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default out)")
    timing.add_runs_argument(parser, 3, "timed renders per configuration, after the measured one")
    parser.add_argument("--quick", action="store_true", help="fewer sample counts")
    parser.add_argument("--cache", type=Path, default=rs.CACHE, help="Cycles reference cache folder")


def run(args):
    w, h = rs.DEFAULT_WIDTH, rs.DEFAULT_HEIGHT
    args.out.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()
    started = time.perf_counter()
    with session.stdout_to_stderr():
        rows = sweep(args, w, h)
    report.write_csv(args.out / "reflections.csv", rows, FIELDS)
    print(f"### Glossy surfaces ({w}x{h}; display RGB MAE against Cycles 256 spp, one glossy bounce)\n")
    print(markdown(rows))
    print(
        f"\nBlender {bpy.app.version_string}; GPU: {session.gpu_renderer() or 'n/a'}; median of {args.runs} "
        f"F12 render(s) per configuration after the measured one; {(time.perf_counter() - started) / 60:.1f} min. "
        f"Wrote {args.out / 'reflections.csv'}."
    )
    return 0
