"""Shadow quality against cost: Penumbra's filters, EEVEE and Cycles on the reference scenes.

Five measurements, all in this one process on the same scenes (``devkit.reference_kit``),
engines set up by ``devkit.engines``:

1. Trade-off: every Penumbra configuration of filter x shadow_map_size (x shadow_samples for
   JITTER and PCSS), EEVEE (16 TAA samples) and Cycles at 1, 4, 16 and 64 spp render every
   reference scene. Error is MAE and shadow IoU of the per-pixel visibility against converged
   Cycles (512 spp; 256 with --quick; cached in out/reference_cache). Time is the median of
   ``--runs`` calls of ``bpy.ops.render.render(write_still=False)`` after the two renders of
   the accuracy measurement (which are the warm-up).
   -> ``<out>/shadow_tradeoff.csv`` and ``<out>/shadow_pareto.png``.
2. Scaling: frame time against resolution and triangle count (the floating sphere's detail)
   for Penumbra (PCF, defaults), EEVEE (16 TAA samples) and Cycles (16 spp), one warm-up
   render each. -> ``<out>/scaling.csv`` and ``<out>/scaling.png``.
3. Per-frame work from Penumbra's own FrameStats (rendered through ``devkit.session.GpuRunner``):
   shadow maps drawn and reused, passes, draws, texture memory, for the cases that show which
   work a frame skips.
4. JITTER with ``shadow_early_out`` on and off at 1280x720, interleaved in the same run.
5. Detailed casters on large grounds (``kit.DETAILED_SCENES``, 320x180, Cycles 64 spp):
   IoU, missed and false shadow fractions, texels per metre at the caster and frame time
   against Workbench's in the same run, for PCF and PCSS at the defaults.
   -> ``<out>/shadow_detailed.csv``.
6. Thin casters (``kit.THIN_SCENES``, 320x180): shadows a few pixels wide, against Cycles
   through the same pixel filter (``kit.matched_filter``; 1024 spp, 256 with --quick): IoU
   and MAE of Penumbra at the default 16 samples and at 64, EEVEE (16 TAA) and Cycles 16 spp
   with the same filter, each with its median frame time. -> ``<out>/shadow_thin.csv``.

``--sections`` runs a subset (tradeoff, scaling, work, early_out, detailed, thin).

Machines here are shared and noisy: absolute times only describe this run; compare engines
and configurations by their ratios. Markdown tables for the README go to stdout, progress and
Blender's own output to stderr. ``--quick`` (two scenes, fewer configurations, one timed run
unless --runs says otherwise) takes about 1.5 minutes; a full run about 8 minutes, on 2 shared
cores with llvmpipe, the Cycles references included (cached for later runs).
"""

import dataclasses
import sys
import time
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

from devkit import reference_kit as kit
from devkit import report, scenes, session, timing
from devkit.engines import CYCLES_SAMPLES, EEVEE_SAMPLES, configure

HELP = "shadow error against frame time, scaling, per-frame work, JITTER early out"
FIXED_FILTERS = ("NONE", "HARDWARE", "PCF")  # cost independent of shadow_samples
SAMPLED_FILTERS = ("JITTER", "PCSS")


@dataclasses.dataclass(frozen=True)
class Plan:
    """What one run measures."""

    scenes: tuple
    map_sizes: tuple
    samples: tuple
    cycles_spp: tuple
    reference_spp: int
    width: int
    height: int
    resolutions: tuple  # scaling: (width, height) at the default sphere detail
    segments: tuple  # scaling: sphere segments at ``triangle_resolution``
    triangle_resolution: tuple
    runs: int


FULL = Plan(
    scenes=kit.LIGHT_SCENES,
    map_sizes=(512, 1024, 2048, 4096),
    samples=(8, 16, 32),
    cycles_spp=(1, 4, 16, 64),
    reference_spp=512,
    width=160,
    height=90,
    resolutions=((160, 90), (320, 180), (640, 360)),
    segments=(32, 100, 318),  # ~1k, 10k, 100k triangles in the scene
    triangle_resolution=(320, 180),
    runs=3,
)

QUICK = Plan(
    scenes=("sun_soft", "spot"),
    map_sizes=(512, 2048),
    samples=(8, 32),
    cycles_spp=(1, 4, 16, 64),
    reference_spp=256,
    width=160,
    height=90,
    resolutions=((160, 90), (320, 180)),
    segments=(32, 100),
    triangle_resolution=(160, 90),
    runs=1,
)


def log(message):
    print(f"bench shadows: {message}", file=sys.stderr, flush=True)


# --- 1. accuracy against time ----------------------------------------------------------------


def penumbra_configs(plan):
    """``scene.penumbra`` settings of every Penumbra configuration of the sweep. Maps have
    exactly the swept size (Texels per Pixel 0), not the size the pixels need, so the sweep
    measures what a map size buys."""
    configs = []
    for filt in FIXED_FILTERS + SAMPLED_FILTERS:
        for size in plan.map_sizes:
            for samples in plan.samples if filt in SAMPLED_FILTERS else (None,):
                settings = {"shadow_filter": filt, "shadow_map_size": size, "shadow_texels_per_pixel": 0.0}
                if samples is not None:
                    settings["shadow_samples"] = samples
                configs.append(settings)
    return configs


def with_shadow(scene, enabled):
    kit.scene_light(scene).data.use_shadow = enabled


def measure(scene, engine, settings, reference, runs, unshadowed=None):
    """Accuracy and median frame time of one configuration on one scene.

    Renders the frame without shadows (unless ``unshadowed`` luminance is given: Penumbra's
    does not depend on its shadow settings), then with shadows; the visibility is their ratio.
    These renders are also the warm-up of the ``runs`` timed renders that follow.
    Returns (median seconds, compare() dict, unshadowed luminance)."""
    configure(scene, engine, **settings)
    if unshadowed is None:
        with_shadow(scene, False)
        try:
            unshadowed = kit.render_luminance(scene)
        finally:
            with_shadow(scene, True)
    shadowed = kit.render_luminance(scene)
    seconds = timing.render(runs, warmup=0).median
    return seconds, kit.compare(kit.visibility_from(shadowed, unshadowed), reference), unshadowed


def tradeoff(plan, cache_dir):
    """One row (dict: engine, filter, map_size, samples, scene, time_s, iou, mae, mae_penumbra)
    per configuration and scene; Cycles references are rendered first (or read from the cache)."""
    references = {}
    for name in plan.scenes:
        log(f"Cycles reference {name} ({plan.reference_spp} spp, {plan.width}x{plan.height})")
        references[name] = kit.cycles_reference(name, plan.reference_spp, plan.width, plan.height, cache_dir)

    rows = []

    def add(engine, filt, size, samples, name, seconds, score):
        rows.append(
            {
                "engine": engine,
                "filter": filt,
                "map_size": size,
                "samples": samples,
                "scene": name,
                "time_s": seconds,
                "iou": score["iou"],
                "mae": score["mae"],
                "mae_penumbra": score["mae_penumbra"],
            }
        )

    for name in plan.scenes:
        scene = kit.build(name, plan.width, plan.height)
        ref = references[name]
        log(f"{name}: Penumbra, {len(penumbra_configs(plan))} configurations")
        unshadowed = None
        for settings in penumbra_configs(plan):
            seconds, score, unshadowed = measure(scene, "PENUMBRA", settings, ref, plan.runs, unshadowed)
            add(
                "Penumbra",
                settings["shadow_filter"],
                settings["shadow_map_size"],
                settings.get("shadow_samples", ""),
                name,
                seconds,
                score,
            )
        log(f"{name}: EEVEE")
        seconds, score, _ = measure(scene, "EEVEE", {"taa_render_samples": EEVEE_SAMPLES}, ref, plan.runs)
        add("EEVEE", "", "", EEVEE_SAMPLES, name, seconds, score)
        for spp in plan.cycles_spp:
            log(f"{name}: Cycles {spp} spp")
            seconds, score, _ = measure(scene, "CYCLES", {"samples": spp}, ref, plan.runs)
            add("Cycles", "", "", spp, name, seconds, score)
    return rows


def summarise(rows):
    """One row per configuration: mean over scenes of median time, MAE and IoU."""
    groups = {}
    for row in rows:
        key = (row["engine"], row["filter"], row["map_size"], row["samples"])
        groups.setdefault(key, []).append(row)
    summary = []
    for (engine, filt, size, samples), group in groups.items():
        summary.append(
            {
                "engine": engine,
                "filter": filt,
                "map_size": size,
                "samples": samples,
                "scene": "mean",
                "time_s": float(np.mean([r["time_s"] for r in group])),
                "iou": float(np.mean([r["iou"] for r in group])),
                "mae": float(np.mean([r["mae"] for r in group])),
                "mae_penumbra": float(np.nanmean([r["mae_penumbra"] for r in group])),
            }
        )
    pareto_flags(summary)
    return summary


def pareto_flags(summary):
    """Mark the Penumbra configurations no other Penumbra configuration beats on both time
    and MAE."""
    pen = [r for r in summary if r["engine"] == "Penumbra"]
    for r in summary:
        r["pareto"] = r["engine"] == "Penumbra" and not any(
            o is not r
            and o["time_s"] <= r["time_s"]
            and o["mae"] <= r["mae"]
            and (o["time_s"] < r["time_s"] or o["mae"] < r["mae"])
            for o in pen
        )


def config_label(row):
    if row["engine"] == "Penumbra":
        extra = f" x{row['samples']}" if row["samples"] != "" else ""
        return f"{row['filter']} {row['map_size']}{extra}"
    if row["engine"] == "EEVEE":
        return f"EEVEE ({row['samples']} TAA)"
    return f"Cycles {row['samples']} spp"


def plot_pareto(summary, path, plan):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 6))
    colours = {
        "NONE": "tab:gray",
        "HARDWARE": "tab:brown",
        "PCF": "tab:blue",
        "JITTER": "tab:orange",
        "PCSS": "tab:green",
    }
    markers = {"NONE": "o", "HARDWARE": "s", "PCF": "D", "JITTER": "^", "PCSS": "v"}
    for filt in FIXED_FILTERS + SAMPLED_FILTERS:
        pts = [r for r in summary if r["engine"] == "Penumbra" and r["filter"] == filt]
        if pts:
            ax.scatter(
                [r["time_s"] for r in pts],
                [r["mae"] for r in pts],
                c=colours[filt],
                marker=markers[filt],
                label=f"Penumbra {filt}",
                alpha=0.8,
                zorder=3,
            )
    front = sorted((r for r in summary if r.get("pareto")), key=lambda r: r["time_s"])
    if front:
        ax.step(
            [r["time_s"] for r in front],
            [r["mae"] for r in front],
            where="post",
            color="black",
            lw=1.2,
            label="Penumbra Pareto front",
            zorder=2,
        )
        for r in front:
            ax.annotate(config_label(r), (r["time_s"], r["mae"]), fontsize=7, xytext=(4, 4), textcoords="offset points")
    eevee = [r for r in summary if r["engine"] == "EEVEE"]
    if eevee:
        ax.scatter(
            [r["time_s"] for r in eevee],
            [r["mae"] for r in eevee],
            c="tab:purple",
            marker="*",
            s=160,
            label=f"EEVEE ({EEVEE_SAMPLES} TAA)",
            zorder=3,
        )
    cycles = sorted((r for r in summary if r["engine"] == "Cycles"), key=lambda r: r["samples"])
    if cycles:
        ax.plot(
            [r["time_s"] for r in cycles],
            [r["mae"] for r in cycles],
            "-P",
            color="tab:red",
            label="Cycles (1-64 spp)",
            zorder=3,
        )
        for r in cycles:
            ax.annotate(
                f"{r['samples']} spp",
                (r["time_s"], r["mae"]),
                fontsize=7,
                xytext=(-6, -12),
                textcoords="offset points",
                color="tab:red",
                ha="right",
            )
    ax.set_xscale("log")
    ax.set_xlabel("time per frame (s, median, log scale)")
    ax.set_ylabel(f"visibility MAE vs Cycles {plan.reference_spp} spp (mean over scenes)")
    ax.set_title(
        f"Shadow error against frame time: {len(plan.scenes)} scenes, {plan.width}x{plan.height}, "
        f"Blender {bpy.app.version_string}",
        fontsize=10,
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --- 2. scaling ----------------------------------------------------------------------------------


SCALING_ENGINES = (
    ("Penumbra (PCF)", "PENUMBRA", {"shadow_filter": "PCF"}),
    (f"EEVEE ({EEVEE_SAMPLES} TAA)", "EEVEE", {"taa_render_samples": EEVEE_SAMPLES}),
    (f"Cycles ({CYCLES_SAMPLES} spp)", "CYCLES", {"samples": CYCLES_SAMPLES}),
)


def scaling(plan):
    """Frame time of each scaling engine at each (resolution, sphere detail) point."""
    points = [(w, h, 32) for (w, h) in plan.resolutions]
    points += [(*plan.triangle_resolution, seg) for seg in plan.segments]
    points = list(dict.fromkeys(points))  # the shared base point once
    rows = []
    for w, h, seg in points:
        scene = kit.build("sun_soft", w, h)
        kit.set_sphere_detail(scene, seg)
        tris = scenes.triangle_count(scene)
        for label, engine, settings in SCALING_ENGINES:
            log(f"scaling: {label} at {w}x{h}, {tris} triangles")
            configure(scene, engine, **settings)
            rows.append(
                {
                    "engine": label,
                    "width": w,
                    "height": h,
                    "triangles": tris,
                    "time_s": timing.render(plan.runs, warmup=1).median,
                }
            )
    baseline = SCALING_ENGINES[0][0]
    base = {(r["width"], r["height"], r["triangles"]): r["time_s"] for r in rows if r["engine"] == baseline}
    for r in rows:
        r["ratio"] = r["time_s"] / base[r["width"], r["height"], r["triangles"]]
    return rows


def plot_scaling(rows, plan, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_res, ax_tri) = plt.subplots(1, 2, figsize=(11, 4.5))
    base_tris = min(r["triangles"] for r in rows)
    for label, _, _ in SCALING_ENGINES:
        res = sorted(
            (r for r in rows if r["engine"] == label and r["triangles"] == base_tris),
            key=lambda r: r["width"] * r["height"],
        )
        ax_res.plot([r["width"] * r["height"] for r in res], [r["time_s"] for r in res], "-o", label=label)
        tw, th = plan.triangle_resolution
        tri = sorted(
            (r for r in rows if r["engine"] == label and (r["width"], r["height"]) == (tw, th)),
            key=lambda r: r["triangles"],
        )
        ax_tri.plot([r["triangles"] for r in tri], [r["time_s"] for r in tri], "-o", label=label)
    ax_res.set_title(f"resolution ({base_tris} triangles)", fontsize=10)
    ax_res.set_xlabel("pixels")
    ax_tri.set_title(f"triangles ({plan.triangle_resolution[0]}x{plan.triangle_resolution[1]})", fontsize=10)
    ax_tri.set_xlabel("triangles")
    for ax in (ax_res, ax_tri):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel("time per frame (s, median)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"Frame time scaling, sun_soft scene, Blender {bpy.app.version_string}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --- 3. per-frame work ---------------------------------------------------------------------------


def moved(camera, offset):
    """``camera`` translated by ``offset`` in world space (the view looks the same way)."""
    from penumbra.engine.scene.extract import Camera

    shift = np.eye(4)
    shift[:3, 3] = -np.asarray(offset, float)
    return Camera(view=camera.view @ shift, projection=camera.projection, is_ortho=camera.is_ortho)


def frames(runner, scene, width, height, offsets=((0, 0, 0),)):
    """FrameStats of consecutive frames in one engine instance (as in the viewport), the
    camera moved by each of ``offsets`` in turn."""

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, scene, width, height)
        return [engine.render_frame(depsgraph, moved(camera, o), width, height).stats for o in offsets]

    return runner(job)


def point_over_plane(plane_size):
    """A point light 3 units over the middle of a plane with a small box on it."""
    scene = scenes.empty_scene(160, 90)
    scenes.box_over_plane(scene, plane_size=plane_size, box_center=(0.3, 0.2, 0.25), box_size=0.5)
    scenes.light(scene, "Point", "POINT", 500.0, location=(0, 0, 3.0), shadow_soft_size=0.2)
    scenes.look_at(scene, (0, -6, 5), (0, 0, 0))
    return scene


def frame_work(plan):
    """(case, FrameStats) rows: the work each case makes a frame do."""
    runner = session.GpuRunner()
    runner.register()
    rows = []
    w, h = plan.width, plan.height
    try:
        scene = kit.build("sun_soft", w, h)
        rows.append(("sun, use_shadow on", frames(runner, scene, w, h)[0]))
        with_shadow(scene, False)
        rows.append(("sun, use_shadow off", frames(runner, scene, w, h)[0]))
        with_shadow(scene, True)
        for size in (512, 2048, 4096):
            scene.penumbra.shadow_map_size = size
            rows.append((f"sun, map {size}", frames(runner, scene, w, h)[0]))
        scene.penumbra.shadow_map_size = 2048
        # Two consecutive frames in one engine instance; the second one's work is reported.
        # The camera's clip range is 0.1-100: its frustum's bounds hold the whole scene, so a
        # VIEW fit equals the SCENE fit; with clip_end 30 the VIEW fit follows the camera.
        fits = ("SCENE", "VIEW") if hasattr(scene.penumbra, "shadow_sun_fit") else (None,)
        for fit, clip_end in [(f, 100.0) for f in fits] + ([("VIEW", 30.0)] if fits[0] else []):
            if fit is not None:
                scene.penumbra.shadow_sun_fit = fit
            scene.camera.data.clip_end = clip_end
            name = f"sun fit {fit}, clip_end {clip_end:g}" if fit else "sun"
            for move in (0.0, 0.25, 2.0):
                second = frames(runner, scene, w, h, ((0, 0, 0), (move, 0, 0)))[1]
                rows.append((f"{name}, 2nd frame, camera {'moved %g' % move if move else 'still'}", second))
        scene.camera.data.clip_end = 100.0
        scene = kit.build("point", w, h)
        rows.append(("point scene: light 3.6 over a 24-unit plane, 3 casters", frames(runner, scene, w, h)[0]))
        scene = point_over_plane(4.0)
        rows.append(("point light 3 over a 4-unit plane, 1 box", frames(runner, scene, w, h)[0]))
    finally:
        runner.unregister()
    return rows


def early_out(plan, width=1280, height=720, samples=(16, 32, 64)):
    """Median frame time of JITTER with shadow_early_out on and off, interleaved."""
    scene = kit.build("sun_soft", width, height)
    rows = []
    for n in samples:
        times = {True: [], False: []}
        for flag in (True, False):  # warm-up: each variant's shader
            configure(scene, "PENUMBRA", shadow_filter="JITTER", shadow_samples=n, shadow_early_out=flag)
            bpy.ops.render.render(write_still=False)
        for _ in range(max(plan.runs, 5)):  # cheap renders: a few more for a steadier ratio
            for flag in (True, False):
                configure(scene, "PENUMBRA", shadow_filter="JITTER", shadow_samples=n, shadow_early_out=flag)
                times[flag].append(timing.render(1, warmup=0).times[0])
        rows.append(
            {
                "samples": n,
                "on": timing.Timing(tuple(times[True])).median,
                "off": timing.Timing(tuple(times[False])).median,
            }
        )
        log(f"early out, {n} samples: {rows[-1]}")
    return rows, (width, height)


# --- 5. detailed casters on large grounds ----------------------------------------------------------

DETAILED_SPP = 64  # Cycles reference: sharp lights, the 50 % contour has converged
DETAILED_FILTERS = ("PCF", "PCSS")


def texels_per_metre(runner, scene):
    """Shadow-map texels per metre at the detailed caster (the largest mesh that is not the
    ground or a wall): the finest map of the light, at the caster's distance for local lights.
    Read from the frame's own shadow plan (``ShadowPass.plan``)."""
    from penumbra.engine.frame import shadow_pass

    plans = []
    original = shadow_pass.ShadowPass.plan

    def recording(self, *args, **kwargs):
        plans.append(original(self, *args, **kwargs))
        return plans[-1]

    light = kit.scene_light(scene)
    meshes = [ob for ob in scene.objects if ob.type == "MESH" and len(ob.data.polygons) > 12]
    caster = max(meshes, key=lambda ob: len(ob.data.polygons))
    centre = np.mean([caster.matrix_world @ Vector(c) for c in caster.bound_box], axis=0)
    distance = float(np.linalg.norm(centre - np.array(light.matrix_world.translation)))

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        w, h = scene.render.resolution_x, scene.render.resolution_y
        engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, w, h), w, h)

    shadow_pass.ShadowPass.plan = recording
    try:
        runner(job)
    finally:
        shadow_pass.ShadowPass.plan = original
    sizes = [t.fit.texel + t.fit.texel_per_distance * distance for p in plans for t in p.tiles]
    return 1.0 / min(sizes) if sizes else float("nan")


def detailed(plan, cache_dir):
    """Per detailed scene and filter: IoU, missed and false shadow fractions against Cycles,
    texels per metre at the caster and the median frame time (and Workbench's, the same run)."""
    width, height = kit.DETAILED_WIDTH, kit.DETAILED_HEIGHT
    runner = session.GpuRunner()
    runner.register()
    rows = []
    try:
        for name in kit.DETAILED_SCENES:
            log(f"detailed scene {name}")
            ref = kit.cycles_reference(name, DETAILED_SPP, width, height, cache_dir)
            scene = kit.build(name, width, height)
            configure(scene, "WORKBENCH")
            bpy.ops.render.render(write_still=False)
            workbench = timing.render(plan.runs, warmup=0).median
            for filt in DETAILED_FILTERS:
                configure(scene, "PENUMBRA", shadow_filter=filt)
                with_shadow(scene, False)
                unshadowed = kit.render_luminance(scene)
                with_shadow(scene, True)
                vis = kit.visibility_from(kit.render_luminance(scene), unshadowed)
                seconds = timing.render(plan.runs, warmup=0).median
                valid = np.isfinite(vis) & np.isfinite(ref)
                n = max(int(valid.sum()), 1)
                rows.append(
                    {
                        "scene": name,
                        "filter": filt,
                        "iou": kit.compare(vis, ref)["iou"],
                        "missed": float(((ref < 0.5) & (vis >= 0.5) & valid).sum() / n),
                        "false": float(((ref >= 0.5) & (vis < 0.5) & valid).sum() / n),
                        "texels_per_m": texels_per_metre(runner, scene),
                        "time_s": seconds,
                        "workbench_s": workbench,
                    }
                )
                log(f"  {rows[-1]}")
    finally:
        runner.unregister()
    return rows


THIN_SPP, THIN_SPP_QUICK = 1024, 256
THIN_CONFIGS = (
    ("Penumbra, 16 samples", "PENUMBRA", {"render_samples": 16}),
    ("Penumbra, 64 samples", "PENUMBRA", {"render_samples": 64}),
    (f"EEVEE, {EEVEE_SAMPLES} TAA", "EEVEE", {}),
    ("Cycles, 16 spp", "CYCLES", {"samples": 16}),
)


def thin(plan, cache_dir, quick):
    """Per thin-caster scene and configuration: IoU and MAE against Cycles through the same
    pixel filter, and the median frame time of the shadowed render."""
    width, height = kit.DETAILED_WIDTH, kit.DETAILED_HEIGHT
    rows = []
    for name in kit.THIN_SCENES:
        log(f"thin scene {name}")
        ref = kit.cycles_reference(name, THIN_SPP_QUICK if quick else THIN_SPP, width, height, cache_dir)
        for label, engine, settings in THIN_CONFIGS:
            scene = kit.build(name, width, height)
            extra = kit.matched_filter(scene) if engine == "CYCLES" else {}
            vis = kit.measure_visibility(scene, engine, **settings, **extra)
            seconds = timing.render(plan.runs, warmup=0).median
            score = kit.compare(vis, ref)
            rows.append({"scene": name, "config": label, "iou": score["iou"], "mae": score["mae"], "time_s": seconds})
            log(f"  {rows[-1]}")
    return rows


# --- output ----------------------------------------------------------------------------------------


def md_tradeoff(summary):
    cells = [
        [
            r["engine"],
            config_label(r),
            f"{r['time_s'] * 1e3:.0f}",
            f"{r['mae']:.4f}",
            f"{r['mae_penumbra']:.3f}",
            f"{r['iou']:.3f}",
            "yes" if r["pareto"] else "",
        ]
        for r in sorted(summary, key=lambda r: (r["engine"] != "Penumbra", r["time_s"]))
    ]
    header = ["Engine", "Configuration", "Time/frame (ms)", "MAE", "MAE in penumbrae", "IoU", "Penumbra Pareto"]
    return report.markdown_table(header, cells, align="llrrrrc")


def md_per_scene(rows, plan):
    """IoU / MAE per scene for Penumbra's defaults (map 2048, 16 samples), EEVEE and Cycles."""
    default_size = 2048 if 2048 in plan.map_sizes else plan.map_sizes[-1]
    default_samples = 16 if 16 in plan.samples else plan.samples[-1]
    lines = []

    def line(label, pick):
        cells = []
        for name in plan.scenes:
            match = [r for r in rows if r["scene"] == name and pick(r)]
            cells.append(f"{match[0]['iou']:.3f} / {match[0]['mae']:.4f}" if match else "")
        lines.append([label, *cells])

    for filt in FIXED_FILTERS + SAMPLED_FILTERS:
        samples = default_samples if filt in SAMPLED_FILTERS else ""
        suffix = f", {samples} samples" if samples != "" else ""
        line(
            f"Penumbra {filt} ({default_size}{suffix})",
            lambda r, f=filt, s=samples: (
                r["engine"] == "Penumbra" and r["filter"] == f and r["map_size"] == default_size and r["samples"] == s
            ),
        )
    line(f"EEVEE ({EEVEE_SAMPLES} TAA)", lambda r: r["engine"] == "EEVEE")
    for spp in plan.cycles_spp:
        line(f"Cycles {spp} spp", lambda r, s=spp: r["engine"] == "Cycles" and r["samples"] == s)
    return report.markdown_table(["Engine", *plan.scenes], lines)


def md_scaling(rows):
    cells = [
        [r["engine"], f"{r['width']}x{r['height']}", f"{r['triangles']:,}", f"{r['time_s']:.3f}", f"{r['ratio']:.2f}x"]
        for r in rows
    ]
    return report.markdown_table(
        ["Engine", "Resolution", "Triangles", "Median (s)", "Relative to Penumbra"], cells, align="llrrr"
    )


def md_work(rows):
    cells = [
        [case, s.shadow_maps, s.shadow_maps_reused, s.passes, s.draws, f"{s.texture_bytes / 2**20:.1f}"]
        for case, s in rows
    ]
    header = ["Case", "Shadow maps drawn", "Reused", "Passes", "Draws", "Texture memory (MiB)"]
    return report.markdown_table(header, cells)


def md_detailed(rows):
    cells = [
        [
            r["scene"],
            r["filter"],
            f"{r['iou']:.3f}",
            f"{r['missed'] * 100:.2f} %",
            f"{r['false'] * 100:.2f} %",
            f"{r['texels_per_m']:,.0f}",
            f"{r['time_s'] * 1e3:.0f}",
            f"{r['time_s'] / r['workbench_s']:.2f}x",
        ]
        for r in rows
    ]
    header = ["Scene", "Filter", "IoU", "Missed", "False", "Texels/m at caster", "ms/frame", "/ Workbench"]
    return report.markdown_table(header, cells, align="llrrrrrr")


def md_thin(rows):
    configs = [label for label, _engine, _settings in THIN_CONFIGS]
    cells = []
    for name in kit.THIN_SCENES:
        line = [name]
        for label in configs:
            r = next((r for r in rows if r["scene"] == name and r["config"] == label), None)
            line.append(f"{r['iou']:.3f} / {r['mae']:.4f} / {r['time_s'] * 1e3:.0f}" if r else "")
        cells.append(line)
    return report.markdown_table(["Scene", *configs], cells)


def md_early_out(rows, size):
    cells = [[r["samples"], f"{r['on'] * 1e3:.0f}", f"{r['off'] * 1e3:.0f}", f"{r['off'] / r['on']:.2f}"] for r in rows]
    header = [f"JITTER samples ({size[0]}x{size[1]})", "Early out on (ms)", "Off (ms)", "Off / on"]
    return report.markdown_table(header, cells, align="rrrr")


# --- command ---------------------------------------------------------------------------------------


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default out)")
    timing.add_runs_argument(parser, None, f"timed renders per configuration ({FULL.runs}; {QUICK.runs} with --quick)")
    parser.add_argument("--quick", action="store_true", help="fewer scenes and configurations (about 2-3 minutes)")
    parser.add_argument("--width", type=int, default=None, help="trade-off resolution (default 160)")
    parser.add_argument("--height", type=int, default=None, help="trade-off resolution (default 90)")
    parser.add_argument("--cache", type=Path, default=kit.DEFAULT_CACHE, help="Cycles reference cache folder")
    parser.add_argument(
        "--sections",
        default=",".join(SECTIONS),
        help=f"comma-separated subset of {', '.join(SECTIONS)} (default: all)",
    )


SECTIONS = ("tradeoff", "scaling", "work", "early_out", "detailed", "thin")


def run(args):
    base = QUICK if args.quick else FULL
    plan = dataclasses.replace(
        base, runs=args.runs or base.runs, width=args.width or base.width, height=args.height or base.height
    )
    args.out.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()
    started = time.perf_counter()

    sections = [x.strip() for x in args.sections.split(",") if x.strip()]
    unknown = sorted(set(sections) - set(SECTIONS))
    if unknown:
        raise SystemExit(f"bench shadows: unknown section(s) {', '.join(unknown)}; known: {', '.join(SECTIONS)}")
    with session.stdout_to_stderr():
        rows = tradeoff(plan, args.cache) if "tradeoff" in sections else None
        scale_rows = scaling(plan) if "scaling" in sections else None
        work_rows = frame_work(plan) if "work" in sections else None
        early = early_out(plan) if "early_out" in sections else None
        detailed_rows = detailed(plan, args.cache) if "detailed" in sections else None
        thin_rows = thin(plan, args.cache, args.quick) if "thin" in sections else None
    gpu = session.gpu_renderer() or "n/a"
    written = []
    if rows is not None:
        summary = summarise(rows)
        fields = ["engine", "filter", "map_size", "samples", "scene", "time_s", "mae", "mae_penumbra", "iou", "pareto"]
        report.write_csv(args.out / "shadow_tradeoff.csv", rows + summary, fields)
        plot_pareto(summary, args.out / "shadow_pareto.png", plan)
        written += ["shadow_tradeoff.csv", "shadow_pareto.png"]
    if scale_rows is not None:
        scaling_fields = ["engine", "width", "height", "triangles", "time_s", "ratio"]
        report.write_csv(args.out / "scaling.csv", scale_rows, scaling_fields)
        plot_scaling(scale_rows, plan, args.out / "scaling.png")
        written += ["scaling.csv", "scaling.png"]
    if detailed_rows is not None:
        fields = ["scene", "filter", "iou", "missed", "false", "texels_per_m", "time_s", "workbench_s"]
        report.write_csv(args.out / "shadow_detailed.csv", detailed_rows, fields)
        written.append("shadow_detailed.csv")
    if thin_rows is not None:
        report.write_csv(args.out / "shadow_thin.csv", thin_rows, ["scene", "config", "iou", "mae", "time_s"])
        written.append("shadow_thin.csv")

    elapsed = time.perf_counter() - started
    conditions = (
        f"Blender {bpy.app.version_string}; GPU: {gpu}; {'--quick' if args.quick else 'full'} run, "
        f"{plan.runs} timed render(s) per configuration after the warm-up; {elapsed / 60:.1f} min in all."
    )
    if rows is not None:
        print(
            f"### Shadow error against frame time (mean over {', '.join(plan.scenes)}; "
            f"{plan.width}x{plan.height}; reference Cycles {plan.reference_spp} spp)\n"
        )
        print(md_tradeoff(summary))
        print("\nPer scene, IoU / MAE:\n")
        print(md_per_scene(rows, plan))
    if scale_rows is not None:
        print("\n### Scaling\n")
        print(md_scaling(scale_rows))
    if work_rows is not None:
        print("\n### Per-frame work (Penumbra FrameStats)\n")
        print(md_work(work_rows))
    if early is not None:
        print()
        print(md_early_out(*early))
    if detailed_rows is not None:
        print(
            f"\n### Detailed casters on large grounds ({kit.DETAILED_WIDTH}x{kit.DETAILED_HEIGHT}, defaults "
            f"but the filter; reference Cycles {DETAILED_SPP} spp; missed/false: share of the valid pixels)\n"
        )
        print(md_detailed(detailed_rows))
    if thin_rows is not None:
        spp = THIN_SPP_QUICK if args.quick else THIN_SPP
        print(
            f"\n### Thin casters ({kit.DETAILED_WIDTH}x{kit.DETAILED_HEIGHT}; IoU / MAE / ms per frame against "
            f"Cycles {spp} spp through the same pixel filter)\n"
        )
        print(md_thin(thin_rows))
    print(f"\n{conditions}")
    print(f"Wrote {', '.join(str(args.out / w) for w in written)}.")
    return 0
