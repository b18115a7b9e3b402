"""What glossy surfaces see: error against time on ``devkit.reflection_scenes``.

``hdri_spheres`` (a mirror, a brushed metal and a polished red ball on a ground under
Blender's own forest.exr, turned 40 deg), ``polished_floor`` (a dark polished floor under a
sun and a dim sky, objects on it), ``probe_floor`` (the same with a Plane Light Probe on the
floor) and ``glass_checker`` (a Glass BSDF ball and a Principled cube of Transmission 1 on a
checker), in this one process:

- Penumbra at 4, 16, 64 render samples: glossy lobes reflect the scene where a Plane probe's
  mirrored capture (``features/planar.py``), a screen-space ray (``features/reflections.py``)
  or a ray marched through the cube maps (``features/cubes.py``) meets it, and the
  Environment Texture prefiltered by roughness elsewhere (``features/world_env.py``);
  transmissive surfaces refract what is behind them (``features/refraction.py``).
- Penumbra without the Plane probes' captures and the cube maps (``features/planar.py``,
  ``features/cubes.py``: the screen's rays alone), without the screen-space techniques too
  (the scene's reflections and the refraction: the world's image alone), and without the
  image too (the world's SH light: what the frame did before issue 50), each technique left
  out of the registry, at 16 and 64. The world ratio's sharp-lobe share (``lit_world.glsl``
  ``world_ratio_share``) is in all: it is not a technique of its own.
- Cycles with one glossy bounce (max_bounces 1; through glass, 8 transmission bounces with
  caustics off) at 16 and 64 spp, EEVEE once
  (``devkit.engines``: 16 TAA samples, no probe baked).

Error: the mean absolute difference of display RGB against Cycles at 256 spp (the bounces
above, the same pixel filter; cached in out/reference_cache) over the objects' pixels
(Workbench's flat object mask), over every pixel, and over the mirror sphere's upper half
(the sky it reflects; its lower half shows the ground and its neighbours). Time: the median
of ``--runs`` F12 renders after the measured one.

-> ``<out>/reflections.csv``, ``<out>/reflections.png`` (error against time per scene, over
the reference, Penumbra's most samples and EEVEE), a Markdown table to stdout.

``--cost``: instead, what the scene's reflections cost, on every scene at 160x90 (where the
pixels cost next to nothing: the CPU's share) and at 960x540, 16 samples: the median of
``--runs`` interleaved F12 renders with Screen Space Reflections on and off (their ratio:
the screen's rays and the camera's cube), and from one fenced frame each
(``Renderer.fence_stages``) a further sample's CPU time and the reflections' stage CPU and GPU
time per traced sample; the cube maps on and off (the ``cubes`` stage per face drawn: six lit
passes once a frame a cube); on a scene with Plane probes, also their captures on and off (the
``planar`` stage per capture: a lit pass each sample).
-> ``<out>/reflections_cost.csv``.
"""

import contextlib
import statistics
import sys
import time
from pathlib import Path

import bpy
import numpy as np

from devkit import reflection_scenes as rs
from devkit import report, session, timing
from devkit.engines import EEVEE_SAMPLES
from tools.benchmarks import perf

HELP = "glossy surfaces: error against time, Penumbra (scene reflections, world image, SH) vs Cycles and EEVEE"
FIELDS = ["scene", "config", "samples", "time_s", "mae_objects", "mae_all", "mae_mirror_upper"]
IMAGE = "Penumbra"
WORLD_ONLY = "Penumbra, world image only"
SH = "Penumbra, SH world light"
SCREEN_ONLY = "Penumbra, screen only (no probe, no cube)"
LEFT_OUT = {
    WORLD_ONLY: ("reflections", "refraction", "planar", "cubes"),
    SH: ("reflections", "refraction", "world_env", "planar", "cubes"),
    SCREEN_ONLY: ("planar", "cubes"),
}
CYCLES = "Cycles, 1 glossy bounce"
EEVEE = f"EEVEE ({EEVEE_SAMPLES} TAA)"


def log(message):
    print(f"bench reflections: {message}", file=sys.stderr, flush=True)


def configs(quick):
    """The configurations of every scene."""
    samples = (4, 16) if quick else (4, 16, 64)
    out = [(IMAGE, "PENUMBRA", n, {"render_samples": n}) for n in samples]
    labels = (SCREEN_ONLY, WORLD_ONLY, SH)
    out += [(label, "PENUMBRA", n, {"render_samples": n}) for label in labels for n in samples[1:]]
    out += [(CYCLES, "CYCLES", n, {"samples": n}) for n in (16, 64)]
    out.append((EEVEE, "EEVEE", EEVEE_SAMPLES, {}))
    return out


def upper_half(mask):
    rows = np.nonzero(mask.any(axis=1))[0]
    out = mask.copy()
    out[: int(np.ceil(0.5 * (rows.min() + rows.max())))] = False
    return out


@contextlib.contextmanager
def without(names):
    """Renderers made inside leave the techniques ``names`` out of their registry."""
    from penumbra.engine.frame import renderer

    kept = renderer.REGISTRY
    renderer.REGISTRY = tuple(f for f in kept if f.name not in names)
    try:
        yield
    finally:
        renderer.REGISTRY = kept


def sweep(args, w, h):
    """(rows, {scene: [(label, display image)]}: the reference, Penumbra's most samples, EEVEE)."""
    rows, shown = [], {}
    for name in rs.SCENES:
        log(f"{name}: Cycles reference, 256 spp at {w}x{h}")
        reference = rs.cycles_reference(name, 256, w, h, cache_dir=args.cache)
        objects = rs.object_mask(name, w, h)
        mirror = upper_half(rs.object_mask(name, w, h, ("Mirror",))) if name == "hdri_spheres" else None
        scene = rs.build(name, w, h)
        shown[name] = [("Cycles 256 spp", reference)]
        most = max(n for label, _e, n, _s in configs(args.quick) if label == IMAGE)
        for label, engine, n, settings in configs(args.quick):
            log(f"{name}: {label}, {n}")
            rs.use_engine(scene, engine, **settings)
            with without(LEFT_OUT.get(label, ())):
                image = rs.render_display(scene)
                seconds = timing.render(args.runs, warmup=0).median
            if (label == IMAGE and n == most) or engine == "EEVEE":
                shown[name].append((f"{label}, {n}", image))
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
    return rows, shown


STYLES = {
    IMAGE: ("tab:blue", "-o"),
    WORLD_ONLY: ("tab:cyan", "--s"),
    SCREEN_ONLY: ("tab:green", "-.d"),
    SH: ("tab:gray", ":^"),
    CYCLES: ("tab:red", "-P"),
    EEVEE: ("tab:purple", "*"),
}


def plot(rows, shown, path, title):
    """Error over the objects against time per scene (top row), and each scene's images."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(shown)
    count = max(len(v) for v in shown.values())
    fig, axes = plt.subplots(1 + count, len(names), figsize=(5.0 * len(names), 3.2 * (1 + count)), squeeze=False)
    for col, name in enumerate(names):
        ax = axes[0, col]
        for label, (colour, style) in STYLES.items():
            pts = sorted((r for r in rows if r["config"] == label and r["scene"] == name), key=lambda r: r["samples"])
            if not pts:
                continue
            ax.plot([r["time_s"] for r in pts], [r["mae_objects"] for r in pts], style, color=colour, label=label)
            for r in pts:
                where = (r["time_s"], r["mae_objects"])
                ax.annotate(str(r["samples"]), where, fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per frame (s, median, log)")
        ax.set_ylabel("display MAE over the objects")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        ax.set_title(name, fontsize=9)
        for row in range(1, 1 + count):
            target = axes[row, col]
            target.axis("off")
            if row - 1 < len(shown[name]):
                label, image = shown[name][row - 1]
                target.imshow(np.clip(image[::-1, :, :3], 0.0, 1.0), interpolation="nearest")
                target.set_title(label, fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


COST_FIELDS = [
    "scene",
    "size",
    "on_s",
    "off_s",
    "ratio",
    "sample_cpu_on_ms",
    "sample_cpu_off_ms",
    "ssr_cpu_ms",
    "ssr_gpu_ms",
    "traced",
]
COST_SIZES = ((160, 90), (960, 540))
COST_SAMPLES = 16


def further_sample_ms(stats):
    later = sorted(stats.sample_cpu_seconds[1:]) or stats.sample_cpu_seconds
    return 1e3 * later[len(later) // 2] if later else 0.0


def screen_switch(scene):
    """Screen Space Reflections on or off (the setting): a context manager per state."""

    @contextlib.contextmanager
    def switch(on):
        scene.penumbra.screen_space_reflections = on
        yield

    return switch


def probe_switch(on):
    """The Plane probes' captures on or off (the planar technique left out of the registry)."""
    return without(() if on else ("planar",))


def cube_switch(on):
    """The cube maps on or off (the cubes technique left out of the registry)."""
    return without(() if on else ("cubes",))


def on_off(args, switch):
    """(median F12 time on, off; fenced stats on, off) of the scene, ``switch(on)`` around each."""
    times = {True: [], False: []}
    for on in (True, False):  # warm-up: shader compilation, first allocations
        with switch(on):
            timing.render(1, warmup=0)
    for _ in range(args.runs):
        for on in (True, False):
            with switch(on):
                times[on].append(timing.render(1, warmup=0).median)
    stats = {}
    for on in (False, True):
        with switch(on):
            stats[on] = perf.fenced_stats()
    return statistics.median(times[True]), statistics.median(times[False]), stats[True], stats[False]


def cost(args):
    """Per scene and size, Screen Space Reflections on against off (the screen's rays and the
    camera's cube), the cube maps on against off (stage ``cubes``, per face drawn); where the
    scene has Plane probes, also their captures on against off (stage ``planar``, per capture)."""
    rows = []
    for w, h in COST_SIZES:
        for name in rs.SCENES:
            scene = rs.use_engine(rs.build(name, w, h), "PENUMBRA", render_samples=COST_SAMPLES)
            probes = any(ob.type == "LIGHT_PROBE" for ob in scene.objects)
            toggles = [
                (name, screen_switch(scene), "reflections", "reflection_samples"),
                (f"{name} (cubes)", cube_switch, "cubes", "cube_faces"),
            ]
            if probes:
                toggles.append((f"{name} (probe)", probe_switch, "planar", "planar_captures"))
            for label, switch, stage, counter in toggles:
                t_on, t_off, on, off = on_off(args, switch)
                traced = max(getattr(on, counter), 1)
                rows.append(
                    {
                        "scene": label,
                        "size": f"{w}x{h}",
                        "on_s": t_on,
                        "off_s": t_off,
                        "ratio": t_on / t_off,
                        "sample_cpu_on_ms": further_sample_ms(on),
                        "sample_cpu_off_ms": further_sample_ms(off),
                        "ssr_cpu_ms": 1e3 * on.cpu_seconds.get(stage, 0.0) / traced,
                        "ssr_gpu_ms": 1e3 * on.gpu_seconds.get(stage, 0.0) / traced,
                        "traced": getattr(on, counter),
                    }
                )
                log(f"  {rows[-1]}")
    return rows


def cost_markdown(rows):
    cells = [
        [
            r["scene"],
            r["size"],
            f"{r['on_s']:.3f}",
            f"{r['off_s']:.3f}",
            f"{r['ratio']:.2f}",
            f"{r['sample_cpu_on_ms']:.2f}",
            f"{r['sample_cpu_off_ms']:.2f}",
            f"{r['ssr_cpu_ms']:.2f} / {r['ssr_gpu_ms']:.2f}",
        ]
        for r in rows
    ]
    header = [
        "Scene",
        "Size",
        "On (s)",
        "Off (s)",
        "On / off",
        "Sample CPU on (ms)",
        "Sample CPU off (ms)",
        "Stage CPU / GPU per traced sample or capture (ms)",
    ]
    return report.markdown_table(header, cells, align="llrrrrrr")


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
    parser.add_argument("--cost", action="store_true", help="the reflections' cost, on against off, instead")


def run(args):
    w, h = rs.DEFAULT_WIDTH, rs.DEFAULT_HEIGHT
    args.out.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()
    started = time.perf_counter()
    if args.cost:
        with session.stdout_to_stderr():
            rows = cost(args)
        report.write_csv(args.out / "reflections_cost.csv", rows, COST_FIELDS)
        print(f"### What the scene's reflections cost ({COST_SAMPLES} samples, F12)\n")
        print(cost_markdown(rows))
        print(
            f"\nBlender {bpy.app.version_string}; GPU: {session.gpu_renderer() or 'n/a'}; median of {args.runs} "
            f"interleaved F12 render(s) each way after a warm-up; per-sample figures from one fenced frame; "
            f"{(time.perf_counter() - started) / 60:.1f} min. Wrote {args.out / 'reflections_cost.csv'}."
        )
        return 0
    with session.stdout_to_stderr():
        rows, shown = sweep(args, w, h)
    report.write_csv(args.out / "reflections.csv", rows, FIELDS)
    title = (
        f"What surfaces see, {w}x{h}: display MAE against Cycles 256 spp (one glossy bounce; through glass "
        f"8 transmission bounces, caustics off); Blender "
        f"{bpy.app.version_string}, {session.gpu_renderer() or 'n/a'}"
    )
    plot(rows, shown, args.out / "reflections.png", title)
    print(f"### Glossy surfaces ({w}x{h}; display RGB MAE against Cycles 256 spp, one glossy bounce)\n")
    print(markdown(rows))
    print(
        f"\nBlender {bpy.app.version_string}; GPU: {session.gpu_renderer() or 'n/a'}; median of {args.runs} "
        f"F12 render(s) per configuration after the measured one; {(time.perf_counter() - started) / 60:.1f} min. "
        f"Wrote {args.out / 'reflections.csv'}."
    )
    return 0
