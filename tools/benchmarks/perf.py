"""What a frame costs and how it scales, as ratios to Workbench measured in the same run.

The baseline is Blender's Workbench with anti-aliasing off and shadows on (one sample of flat
shading with a shadow, the nearest thing Blender ships to one Penumbra sample). For every
case both engines render the same scene, interleaved (Penumbra, Workbench, Penumbra, ...)
after one untimed render each, ``--runs`` times; a row quotes the medians and their ratio.
Final renders (F12) go through ``bpy.ops.render.render``: a new engine instance per render,
so every Penumbra row pays for extraction, shadow maps and allocation, as a batch render does.

Sections (``--sections``, all by default):
  cpu         where pixels cost nothing (160x90), what a frame's CPU costs: a textured asset
              (``scenes.textured_asset``: four 2048² images, 16k triangles) at 1 sample against
              Workbench on the same scene, and the demo at 16 samples against Workbench's one;
              then one fenced frame of each (``Renderer.fence_stages``): the render thread's
              CPU time and the GPU's per stage, per sample, bytes uploaded, draw calls and
              triangles per pass, and how much of a further sample's CPU is spent inside the
              gpu module's calls (``driver_share``: the driver's own work); and the asset's
              second F12 against its first with the extension's store emptied
              (``engine/store.py``): render-thread CPU, bytes uploaded; the same in wall time
              for spheres under a real HDRI (the world's prefiltered environment kept)
  resolution  demo scene without post layers at 480x270, 960x540 and 1920x1080
  passes      the demo scene at 960x540, F12, timed pass by pass (the GPU waited for with a
              one-pixel read-back before and after each pass): the depth pass and the lit pass
              with PCF 5x5, with a single-tap filter (NONE) and with shadows off
  samples     the demo at 960x540, F12 at 1, 16 and 64 samples against Workbench, with pixels
              settling (Noise Threshold 0.01) and without (0): one further sample's cost
              against the first, the pixels settled, each frame's lit and shadow passes
  viewport    the viewport path at 960x540 (demo scene with its post layers), one engine
              instance: display only, redraw with nothing changed, camera moving (sideways),
              camera orbiting (2 degrees a frame about the world's z), scene edited; each with
              the render thread's CPU a frame and the most maps a frame drew
  lights      N shadowed spot lights over a field of boxes (N = 1, 8, 32, 64): F12, and the
              viewport path with every map reused
  objects     N separate objects (each its own mesh) and N instances of one mesh
  instances   1 and 16 collection instances of the Stanford bunny (69k triangles): F12; the
              same with Render > Simplify > Merge Below at 2 and 4 px (and the image's error
              against every triangle drawn); closed cows
  triangles   one grid mesh of 70k ... 2M triangles: F12, and extraction against a bare copy
              of the same data with ``foreach_get`` (the limit for reading a mesh from Python)
  map_detail  a 1.1M-triangle bunny (the scan, subdivided twice) under a 1.5 m area light at
              480x270 and 16 samples (its maps redrawn each sample from a point of the light):
              Shadows > Caster Detail 0 (every triangle in every map) against the default 2
              map texels, F12 time and triangles drawn into maps, and the image's error
              between the two
  gpu         the targets a GPU is judged by (issue 39): the demo at 640x360 and 16 samples
              against EEVEE's 16 (EEVEE in the baseline column), the textured asset at 960x540
              and 1 sample against Workbench; each with one fenced frame's CPU/GPU split
  materials   16 UV spheres on a ground at 960x540 with constant materials, a 1024² image
              on Base Color, and Base Color + Roughness + a normal map (the textured variants'
              cost against the constant one)

Writes ``<out>/perf.csv``; Markdown tables for the README go to stdout, progress and
Blender's own output to stderr. ``--quick``: fewer sizes and counts, 3 runs.
"""

import math
import statistics
import sys
import time

import bpy
import numpy as np

from devkit import assets, engines, report, scenes, session

HELP = "frame cost and scaling as ratios to Workbench (AA off, shadows on)"
SECTIONS = (
    "cpu",
    "resolution",
    "passes",
    "samples",
    "viewport",
    "lights",
    "objects",
    "instances",
    "map_detail",
    "triangles",
    "materials",
    "gpu",
)
CSV_FIELDS = ["section", "case", "penumbra_ms", "workbench_ms", "ratio", "note", "runs", "blender"]


def add_arguments(parser):
    from pathlib import Path

    from devkit import timing

    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder for perf.csv (default out)")
    timing.add_runs_argument(parser, None, "timed renders per engine and case (default 5; 3 with --quick)")
    parser.add_argument("--quick", action="store_true", help="fewer sizes and counts")
    parser.add_argument(
        "--sections", default=",".join(SECTIONS), help="comma-separated subset of: " + ", ".join(SECTIONS)
    )


# --- engines -------------------------------------------------------------------------------


def _workbench(scene):
    engines.configure(scene, "WORKBENCH")
    scene.display.render_aa = "OFF"
    scene.display.shading.show_shadows = True


def _penumbra(scene):
    engines.configure(scene, "PENUMBRA")


def _eevee(scene):
    engines.configure(scene, "EEVEE")


def _render():
    with session.stdout_to_stderr():
        bpy.ops.render.render(write_still=False)


def paired(scene, runs, baseline=None):
    """Median seconds of interleaved F12 renders: {'PENUMBRA': s, 'WORKBENCH': s} (the second
    key's engine set up by ``baseline`` when given: EEVEE, say)."""
    setups = {"PENUMBRA": _penumbra, "WORKBENCH": baseline or _workbench}
    times = {k: [] for k in setups}
    for setup in setups.values():  # warm-up: shader compilation, first allocations
        setup(scene)
        _render()
    for _ in range(runs):
        for key, setup in setups.items():
            setup(scene)
            start = time.perf_counter()
            _render()
            times[key].append(time.perf_counter() - start)
    _penumbra(scene)
    return {k: statistics.median(v) for k, v in times.items()}


def _row(section, case, t, note="", runs=0):
    p, w = t.get("PENUMBRA"), t.get("WORKBENCH")
    return {
        "section": section,
        "case": case,
        "penumbra_ms": None if p is None else p * 1e3,
        "workbench_ms": None if w is None else w * 1e3,
        "ratio": p / w if p and w else None,
        "note": note,
        "runs": runs,
        "blender": bpy.app.version_string,
    }


# --- scenes ----------------------------------------------------------------------------------


def demo(width, height, post=False):
    scene = scenes.demo_scene(width, height)
    if not post:
        scene.penumbra.layers.clear()
    return scene


def spot_field(count, width=960, height=540):
    """A 24 m ground with a 6x6 field of boxes, lit by ``count`` shadowed spots on a grid 4 m
    above it, each pointing down; total power fixed, so the image stays exposed alike."""
    scene = scenes.empty_scene(width, height)
    scenes.set_world(scene, (0.02, 0.02, 0.03))
    mat = scenes.white()
    scenes.plane(scene, "Ground", size=24.0, mat=mat)
    for i in range(36):
        x, y = (i % 6) * 3.6 - 9.0, (i // 6) * 3.6 - 9.0
        scenes.box(scene, f"Box{i}", center=(x, y, 0.5), size=(0.8, 0.8, 1.0), mat=mat)
    side = math.ceil(math.sqrt(count))
    for i in range(count):
        x = ((i % side) + 0.5) / side * 20.0 - 10.0
        y = ((i // side) + 0.5) / side * 20.0 - 10.0
        scenes.light(
            scene, f"Spot{i}", "SPOT", 4000.0 / count, location=(x, y, 4.0), spot_size=math.radians(50), spot_blend=0.2
        )
    scenes.look_at(scene, (0.0, -17.0, 15.0), (0.0, -1.0, 0.0))
    return scene


def point_field(count, width=160, height=90):
    """``spot_field``'s ground and boxes lit by ``count`` shadowed point lights 4 m above it
    (a point light's map is a cube of six faces, each planned on its own)."""
    scene = spot_field(0, width, height)
    side = math.ceil(math.sqrt(count))
    for i in range(count):
        x = ((i % side) + 0.5) / side * 20.0 - 10.0
        y = ((i // side) + 0.5) / side * 20.0 - 10.0
        scenes.light(scene, f"Point{i}", "POINT", 4000.0 / count, location=(x, y, 4.0))
    return scene


def object_field(count, instanced):
    """``count`` cubes on a square grid over a ground, as separate objects with their own mesh
    or as collection instances of one cube; one sun."""
    scene = scenes.empty_scene(960, 540)
    mat = scenes.white()
    scenes.plane(scene, "Ground", size=40.0, mat=mat)
    side = math.ceil(math.sqrt(count))
    spacing = 36.0 / side
    if instanced:
        source = bpy.data.collections.new("Source")
        scene.collection.children.link(source)
        cube = scenes.box(scene, "Cube", size=(spacing * 0.5,) * 3, mat=mat)
        scene.collection.objects.unlink(cube)
        source.objects.link(cube)
        scene.view_layers[0].layer_collection.children["Source"].exclude = True
    for i in range(count):
        x = ((i % side) + 0.5) * spacing - 18.0
        y = ((i // side) + 0.5) * spacing - 18.0
        if instanced:
            ob = bpy.data.objects.new(f"Instance{i}", None)
            ob.instance_type, ob.instance_collection = "COLLECTION", source
            ob.location = (x, y, spacing * 0.25)
            scene.collection.objects.link(ob)
        else:
            scenes.box(scene, f"Cube{i}", center=(x, y, spacing * 0.25), size=(spacing * 0.5,) * 3, mat=mat)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(35), 0, math.radians(25)))
    scenes.look_at(scene, (0.0, -34.0, 30.0), (0.0, -2.0, 0.0))
    return scene


def bunny_field(count, asset=None, subdivisions=0):
    """``count`` collection instances of a mesh on a ground, one sun: the Stanford bunny (open:
    69k triangles), or ``asset`` with ``subdivisions`` levels of a Subdivision modifier (Spot
    at 2, applied: a closed 94k-triangle cow, drawn without back faces)."""
    scene = scenes.empty_scene(960, 540)
    mat = scenes.white()
    scenes.plane(scene, "Ground", size=20.0, mat=mat)
    source = bpy.data.collections.new("Bunny")
    scene.collection.children.link(source)
    bunny = assets.import_mesh(scene, asset or assets.BUNNY, height=1.0, name="Bunny")
    bunny.data.materials.append(mat)
    if subdivisions:  # applied: the benchmark times drawing, not Blender's subdivision
        modifier = bunny.modifiers.new("Subdivision", "SUBSURF")
        modifier.levels = modifier.render_levels = subdivisions
        evaluated = bunny.evaluated_get(bpy.context.evaluated_depsgraph_get())
        mesh = bpy.data.meshes.new_from_object(evaluated)
        bunny.modifiers.remove(modifier)
        bunny.data = mesh
    scene.collection.objects.unlink(bunny)
    source.objects.link(bunny)
    scene.view_layers[0].layer_collection.children["Bunny"].exclude = True
    for i in range(count):
        ob = bpy.data.objects.new(f"Bunny{i}", None)
        ob.instance_type, ob.instance_collection = "COLLECTION", source
        ob.location = ((i % 4) * 1.6 - 2.4, (i // 4) * 1.6 - 2.4, 0.0)
        scene.collection.objects.link(ob)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(35), 0, math.radians(25)))
    scenes.look_at(scene, (0.0, -9.0, 6.0), (0.0, 0.0, 0.5))
    return scene


def grid_mesh(scene, n, name="Grid"):
    """An n x n quad grid (2 n^2 triangles) of gentle waves, 8 m wide, built with foreach_set."""
    k = n + 1
    u, v = np.meshgrid(np.linspace(-4, 4, k), np.linspace(-4, 4, k))
    co = np.stack([u, v, 0.3 * np.sin(u * 2.0) * np.cos(v * 2.0) + 0.4], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(n))
    a = (j * k + i).ravel()
    quads = np.stack([a, a + 1, a + k + 1, a + k], axis=1)
    me = bpy.data.meshes.new(name)
    me.from_pydata(co, [], quads)
    me.shade_smooth()
    ob = bpy.data.objects.new(name, me)
    scene.collection.objects.link(ob)
    return ob


def bare_copy(mesh):
    """Seconds to copy a mesh's triangle data out with plain ``foreach_get`` (positions,
    triangle corners, corner normals): what any extraction from Python must at least do."""
    start = time.perf_counter()
    mesh.calc_loop_triangles()
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    tri = np.empty(len(mesh.loop_triangles) * 3, np.int32)
    mesh.loop_triangles.foreach_get("loops", tri)
    nor = np.empty(len(mesh.loops) * 3, np.float32)
    mesh.corner_normals.foreach_get("vector", nor)
    return time.perf_counter() - start


# --- sections ------------------------------------------------------------------------------


def fenced_stats():
    """FrameStats of an F12 render of the current scene, as it is set up, with every stage
    fenced (``StageClock``)."""
    from penumbra.engine.frame.renderer import Renderer

    seen = []
    render = Renderer.render

    def recorded(self, *args, **kwargs):
        out = render(self, *args, **kwargs)
        seen.append(out.stats)
        return out

    Renderer.fence_stages, Renderer.render = True, recorded
    try:
        _render()
    finally:
        Renderer.fence_stages, Renderer.render = False, render
    return seen[-1]


def _fenced_stats(scene):
    """``fenced_stats`` of ``scene`` drawn by Penumbra."""
    _penumbra(scene)
    return fenced_stats()


def cpu_note(stats):
    """A FrameStats' CPU/GPU split in a few words (``section_cpu``, docs/benchmarks.md)."""
    cpu, gpu = stats.cpu_seconds, stats.gpu_seconds
    per_sample = sorted(stats.sample_cpu_seconds[1:]) or stats.sample_cpu_seconds
    median = per_sample[len(per_sample) // 2] if per_sample else 0.0
    # A batch's map pass is booked to its first sample (``Renderer._batch``): the mean shares it.
    mean = sum(per_sample) / len(per_sample) if per_sample else 0.0
    stages = ", ".join(f"{k} {v * 1e3:.1f}/{gpu.get(k, 0.0) * 1e3:.1f}" for k, v in sorted(cpu.items()))
    return (
        f"CPU {sum(cpu.values()) * 1e3:.1f} ms, GPU {sum(gpu.values()) * 1e3:.1f} ms; a further sample's CPU "
        f"{median * 1e3:.2f} ms (median; mean {mean * 1e3:.2f} ms); uploaded {stats.upload_bytes / 1024:.0f} KiB; "
        f"draws {stats.draws} "
        f"({stats.shadow_draws} into maps); triangles {stats.triangles} lit, {stats.shadow_triangles} in maps; "
        f"stage CPU/GPU ms: {stages}"
    )


def section_cpu(plan):
    """At 160x90, where the pixels cost next to nothing even on llvmpipe, what a frame's CPU
    work costs against Workbench's: a textured asset at 1 sample, 8 point lights over a field
    of boxes at 1 sample (their maps' planning), and the demo at 16 samples against
    Workbench's one sample; each with the CPU/GPU split of one fenced frame."""
    rows = []
    asset = scenes.textured_asset(160, 90)
    t = paired(asset, plan["runs"])
    rows.append(_row("cpu", "textured asset 160x90, 1 sample", t, cpu_note(_fenced_stats(asset)), plan["runs"]))
    rows.append(_warm_f12(asset, plan["runs"]))  # before the demo replaces the scene
    from devkit import reflection_scenes

    hdri = reflection_scenes.build("hdri_spheres", 160, 90)
    _penumbra(hdri)
    hdri.penumbra.render_samples = 1
    case = "spheres under an HDRI 160x90, 1 sample: a second F12"
    rows.append(_warm_f12(hdri, plan["runs"], case, time.perf_counter))
    points = point_field(8)
    t = paired(points, plan["runs"])
    rows.append(_row("cpu", "8 point lights 160x90, 1 sample", t, cpu_note(_fenced_stats(points)), plan["runs"]))
    scene = demo(160, 90)
    times = {"PENUMBRA": [], "WORKBENCH": []}
    for key, setup in (("PENUMBRA", _penumbra), ("WORKBENCH", _workbench)):  # warm-up
        setup(scene)
        _render()
    for _ in range(plan["runs"]):
        for key, setup in (("PENUMBRA", _penumbra), ("WORKBENCH", _workbench)):
            setup(scene)
            scene.penumbra.render_samples = 16
            start = time.perf_counter()
            _render()
            times[key].append(time.perf_counter() - start)
    t = {k: statistics.median(v) for k, v in times.items()}
    scene.penumbra.render_samples = 16
    note = cpu_note(_fenced_stats(scene))
    inside, calls = driver_share(scene)
    note += f"; of a further sample's CPU, {inside * 1e3:.2f} ms inside {calls:.0f} calls of the gpu module (driver)"
    rows.append(_row("cpu", "demo 160x90, 16 samples (Workbench: 1 sample)", t, note, plan["runs"]))
    return rows


def driver_share(scene, samples=16, runs=6):
    """(render-thread CPU seconds, calls) a further sample of ``scene`` spends inside the gpu
    module's functions (draws, clears, binds, uniforms, state): on llvmpipe the driver's own
    work on the calling thread (state validation, vertex shading and binning of each draw),
    a few microseconds a call on a GPU's driver. Frames of ``samples`` and of 2 samples under
    ``cProfile`` (the thread's CPU clock), the difference per further sample: the profiler
    slows Python, not the time spent inside a C call."""
    import cProfile
    import pstats

    from penumbra.engine.frame.renderer import Renderer

    def inside(count):
        scene.penumbra.render_samples = count
        _render()
        profile = cProfile.Profile(time.thread_time)
        render = Renderer.render

        def profiled(self, *args, **kwargs):
            profile.enable()
            try:
                return render(self, *args, **kwargs)
            finally:
                profile.disable()

        Renderer.render = profiled
        try:
            for _ in range(runs):
                _render()
        finally:
            Renderer.render = render
        seconds = calls = 0.0
        for (_file, _line, name), (_cc, ncalls, tottime, _ct, _callers) in pstats.Stats(profile).stats.items():
            if "of 'GPU" in name or name.startswith("<built-in method gpu."):
                seconds += tottime
                calls += ncalls
        return seconds / runs, calls / runs

    (few, few_calls), (many, many_calls) = inside(2), inside(samples)
    scene.penumbra.render_samples = samples
    return (many - few) / (samples - 2), (many_calls - few_calls) / (samples - 2)


def _warm_f12(scene, runs, case="textured asset 160x90: a second F12's CPU", clock=time.thread_time):
    """The render thread's CPU (``clock``: or the wall time) of an F12 of ``scene`` with the
    extension's store warm (the same scene rendered just before) against one with it emptied
    first (``engine/store.py``; programs and image textures made in both), medians of
    ``runs`` pairs; what the warm one uploaded of meshes and images."""
    from penumbra.engine import store

    _penumbra(scene)
    _render()
    cold, warm = [], []
    for _ in range(runs):
        store.clear()
        for times in (cold, warm):
            start = clock()
            _render()
            times.append(clock() - start)
    stats = fenced_stats()
    t = {"PENUMBRA": statistics.median(warm), "WORKBENCH": statistics.median(cold)}
    what = "render thread's CPU" if clock is time.thread_time else "wall time"
    note = (
        f"{what}, a second F12 (store warm) against the first (store emptied: the baseline column); "
        f"the second uploaded {stats.mesh_upload_bytes} bytes of meshes and {stats.image_upload_bytes} of images"
    )
    return _row("cpu", case, t, note, runs)


def section_resolution(plan):
    rows = []
    for w, h in plan["resolutions"]:
        scene = demo(w, h)
        rows.append(_row("resolution", f"{w}x{h}", paired(scene, plan["runs"]), runs=plan["runs"]))
    return rows


def _time_passes(times, current):
    """Time every shadow (depth) pass and lit pass of the renders that follow, each to a
    one-pixel read-back of the frame's targets before and after it: seconds are appended to
    ``times[current["case"], "depth pass" | "lit pass"]`` while ``current`` names a case.
    Returns what ``_restore`` puts back."""
    from penumbra.engine.frame.lit_pass import LitPass
    from penumbra.engine.frame.renderer import Renderer
    from penumbra.engine.frame.shadow_pass import ShadowPass

    def timed(method, part):
        def run(self, *args, **kwargs):
            current["renderer"].wait_gpu()
            start = time.perf_counter()
            out = method(self, *args, **kwargs)
            current["renderer"].wait_gpu()
            if "case" in current:
                times.setdefault((current["case"], part), []).append(time.perf_counter() - start)
            return out

        return run

    def recorded(method):
        def run(self, *args, **kwargs):
            current["renderer"] = self  # the renderer whose targets ``wait_gpu`` reads
            out = method(self, *args, **kwargs)
            current["stats"] = out.stats  # the last frame's FrameStats
            return out

        return run

    originals = {
        (ShadowPass, "draw"): ShadowPass.draw,
        (LitPass, "draw"): LitPass.draw,
        (Renderer, "render"): Renderer.render,
    }
    ShadowPass.draw = timed(ShadowPass.draw, "depth pass")
    LitPass.draw = timed(LitPass.draw, "lit pass")
    Renderer.render = recorded(Renderer.render)
    return originals


def _restore(originals):
    for (owner, name), method in originals.items():
        setattr(owner, name, method)


# The samples section's cases: (render samples, Noise Threshold). The default threshold lets
# pixels settle after the pilot sample; 0 takes every sample in every pixel.
SAMPLE_CASES = ((1, 0.01), (16, 0.01), (16, 0.0), (64, 0.01), (64, 0.0))


def section_samples(plan):
    """The demo at 960x540, F12 at 1, 16 and 64 render samples against Workbench, interleaved:
    what one further sample costs against the first, with pixels settling (the default Noise
    Threshold) and without (threshold 0), the pixels settled, and how each frame's time splits
    into shadow (depth) passes and lit passes (summed over its samples, the pilot's and the
    settle test's included, each timed as in ``passes``)."""
    scene = demo(960, 540)
    times, current = {}, {}
    frames = {case: [] for case in SAMPLE_CASES}
    settled = {}
    workbench = []
    originals = _time_passes(times, current)

    def setup(case):
        _penumbra(scene)
        scene.penumbra.render_samples, scene.penumbra.adaptive_threshold = case

    try:
        for case in frames:  # warm-up
            setup(case)
            _render()
        _workbench(scene)
        _render()
        for run in range(plan["runs"]):
            for case in frames:
                setup(case)
                current["case"] = (case, run)
                start = time.perf_counter()
                _render()
                frames[case].append(time.perf_counter() - start)
                current.pop("case")
                stats = current["stats"]
                settled[case] = stats.pixels_settled / (960 * 540)
            _workbench(scene)
            start = time.perf_counter()
            _render()
            workbench.append(time.perf_counter() - start)
    finally:
        _restore(originals)
        _penumbra(scene)
        scene.penumbra.adaptive_threshold = 0.01
    w = statistics.median(workbench)
    one = statistics.median(frames[(1, 0.01)])

    def part(case, name):
        return statistics.median(sum(times.get(((case, r), name), [0.0])) for r in range(plan["runs"]))

    rows = [_row("samples", "1 sample", {"PENUMBRA": one, "WORKBENCH": w}, runs=plan["runs"])]
    for case in SAMPLE_CASES[1:]:
        n, threshold = case
        t = statistics.median(frames[case])
        lit, depth = part(case, "lit pass"), part(case, "depth pass")
        label = f"{n} samples, " + (f"Noise Threshold {threshold:g}" if threshold else "threshold 0 (no settling)")
        note = (
            f"samples 2-{n}: {(t - one) / (n - 1) / one:.2f}x the first each; "
            f"{settled[case]:.1%} of pixels settled; lit passes {lit * 1e3:.0f} ms ({lit / t:.0%}), "
            f"shadow passes {depth * 1e3:.0f} ms ({depth / t:.0%})"
        )
        rows.append(_row("samples", label, {"PENUMBRA": t, "WORKBENCH": w}, note, plan["runs"]))
    return rows


def section_passes(plan):
    """The demo at 960x540 pass by pass: the shadow (depth) pass and the lit pass, each timed
    to a one-pixel read-back of its targets before and after it (so each pass's GPU work is
    its own), for PCF 5x5, a single tap (NONE) and shadows off, interleaved."""
    scene = demo(960, 540)
    lights = [ob for ob in scene.objects if ob.type == "LIGHT"]
    cases = {"PCF 5x5": ("PCF", True), "one tap (NONE)": ("NONE", True), "shadows off": ("PCF", False)}
    times = {(case, part): [] for case in cases for part in ("depth pass", "lit pass")}
    current = {}

    def setup(case):
        _penumbra(scene)
        scene.penumbra.shadow_filter, shadowed = cases[case]
        for ob in lights:
            ob.data.use_shadow = shadowed

    originals = _time_passes(times, current)
    try:
        for case in cases:  # warm-up
            setup(case)
            _render()
        for _ in range(plan["runs"]):
            for case in cases:
                setup(case)
                current["case"] = case
                _render()
                current.pop("case")
    finally:
        _restore(originals)
        for ob in lights:
            ob.data.use_shadow = True
    rows = []
    for (case, part), values in times.items():
        if values:
            rows.append(_row("passes", f"{case}: {part}", {"PENUMBRA": statistics.median(values)}, runs=len(values)))
    return rows


def section_viewport(plan):
    """The engine core's viewport path at 960x540 (``viewport_frame`` + ``draw_display``), with
    the default navigation scale (0.5) and with full resolution while moving."""
    rows = _viewport(plan, 0.5)
    moving = _viewport(plan, 1.0, cases=("display only", "camera moving"))
    base = moving[0]["penumbra_ms"]
    row = dict(moving[1], case="camera moving, navigation scale 1", ratio=moving[1]["penumbra_ms"] / base)
    return rows + [row]


def _viewport(plan, navigation_scale, cases=None):
    import gpu

    w, h = 960, 540
    scene = demo(w, h, post=True)
    scene.penumbra.navigation_scale = navigation_scale
    runner = session.GpuRunner()
    runner.register()
    runs = max(plan["runs"], 5)

    def job(engine, depsgraph):
        cam = scene.camera.evaluated_get(depsgraph)
        view = cam.matrix_world.inverted()
        window = cam.calc_matrix_camera(depsgraph, x=w, y=h, scale_x=1.0, scale_y=1.0)
        offscreen = gpu.types.GPUOffScreen(w, h, format="RGBA16F")

        def show(out):
            with offscreen.bind():
                fb = gpu.state.active_framebuffer_get()
                with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
                    gpu.matrix.load_identity()
                    gpu.matrix.load_projection_matrix(_pixel_projection(w, h))
                    engine.draw_display(scene, out.color, w, h)
                fb.read_color(0, 0, 1, 1, 4, 0, "FLOAT")  # waits for the GPU

        moved = [0]

        def move():
            moved[0] += 1
            v = view.copy()
            v.translation.x += 0.01 * moved[0]
            return v

        def orbit():
            from mathutils import Matrix

            moved[0] += 1
            return view @ Matrix.Rotation(math.radians(2.0 * moved[0]), 4, "Z")

        out = engine.viewport_frame(depsgraph, view, window, w, h)[0]
        every = {
            "display only": lambda: show(out),
            "redraw, nothing changed": lambda: show(engine.viewport_frame(depsgraph, view, window, w, h)[0]),
            "camera moving": lambda: show(engine.viewport_frame(depsgraph, move(), window, w, h)[0]),
            "camera orbiting": lambda: show(engine.viewport_frame(depsgraph, orbit(), window, w, h)[0]),
            "scene edited (view still)": lambda: (
                engine.scene_changed(),
                show(engine.viewport_frame(depsgraph, view, window, w, h)[0]),
            ),
        }
        chosen = {k: v for k, v in every.items() if cases is None or k in cases}
        times, cpu, maps = {}, {}, {}
        for name, fn in chosen.items():
            fn()
            samples, threads, drawn = [], [], []
            for _ in range(runs):
                start, thread = time.perf_counter(), time.thread_time()
                fn()
                threads.append(time.thread_time() - thread)
                samples.append(time.perf_counter() - start)
                drawn.append(engine._shown[1].stats.shadow_maps if engine._shown else 0)
            times[name] = statistics.median(samples)
            cpu[name] = statistics.median(threads)
            maps[name] = max(drawn)
        offscreen.free()
        return times, cpu, maps

    try:
        times, cpu, maps = runner(job)
    finally:
        runner.unregister()
    base = times["display only"]
    return [
        {
            "section": "viewport",
            "case": name,
            "penumbra_ms": t * 1e3,
            "workbench_ms": None,
            "ratio": t / base,
            "note": f"ratio to display only; render thread's CPU {cpu[name] * 1e3:.1f} ms a frame; "
            f"maps drawn in a frame at most {maps[name]}",
            "runs": runs,
            "blender": bpy.app.version_string,
        }
        for name, t in times.items()
    ]


def _pixel_projection(w, h):
    from mathutils import Matrix

    return Matrix(((2 / w, 0, 0, -1), (0, 2 / h, 0, -1), (0, 0, -1, 0), (0, 0, 0, 1)))


def _viewport_reused(scene, runs):
    """Median seconds of the engine core's frame with every shadow map reused (one engine
    instance, colour only, as the viewport renders after an edit elsewhere)."""
    from penumbra.engine.scene.extract import camera_from_scene

    runner = session.GpuRunner()
    runner.register()
    r = scene.render

    def job(engine, depsgraph):
        cam = camera_from_scene(depsgraph, scene, r.resolution_x, r.resolution_y)

        def frame():
            engine.render_frame(depsgraph, cam, r.resolution_x, r.resolution_y, aux=False).color.read()

        frame()
        samples = []
        for _ in range(runs):
            start = time.perf_counter()
            frame()
            samples.append(time.perf_counter() - start)
        return statistics.median(samples)

    try:
        return runner(job)
    finally:
        runner.unregister()


def section_lights(plan):
    rows = []
    first = None
    for n in plan["lights"]:
        scene = spot_field(n)
        t = paired(scene, plan["runs"])
        reused = _viewport_reused(scene, plan["runs"])
        first = first or t["PENUMBRA"]
        note = f"{t['PENUMBRA'] / first:.2f}x one light; maps reused {reused * 1e3:.0f} ms"
        rows.append(_row("lights", f"{n} shadowed spots", t, note, plan["runs"]))
    return rows


def section_objects(plan):
    rows = []
    for instanced in (False, True):
        for n in plan["objects"]:
            scene = object_field(n, instanced)
            case = f"{n} {'instances' if instanced else 'objects'}"
            rows.append(_row("objects", case, paired(scene, plan["runs"]), runs=plan["runs"]))
    return rows


def section_instances(plan):
    rows = []
    first = None
    for n in (1, 16):
        scene = bunny_field(n)
        t = paired(scene, plan["runs"])
        first = first or t["PENUMBRA"]
        rows.append(_row("instances", f"{n} bunny instances", t, f"{t['PENUMBRA'] / first:.2f}x one", plan["runs"]))
    # Render > Simplify > Merge Below: the same bunnies at a level of detail, each count against
    # one bunny at the same setting; the error is against the full-detail frame.
    from devkit.render import render

    for pixels in (2.0, 4.0):
        first = None
        for n in (1, 16):
            scene = bunny_field(n)
            _penumbra(scene)
            full = render(scene)["Combined"][..., :3]
            scene.render.use_simplify = True
            scene.penumbra.simplify_pixels = pixels
            simplified = render(scene)["Combined"][..., :3]
            diff = np.abs(simplified - full).max(axis=-1)
            t = paired(scene, plan["runs"])
            first = first or t["PENUMBRA"]
            note = (
                f"{t['PENUMBRA'] / first:.2f}x one at {pixels:g} px; against every triangle: mean error "
                f"{diff.mean():.4f}, {100 * np.mean(diff > 0.05):.1f} % of pixels over 0.05"
            )
            rows.append(_row("instances", f"{n} bunny instances, Merge Below {pixels:g} px", t, note, plan["runs"]))
    first = None
    for n in (1, 16):
        scene = bunny_field(n, assets.SPOT, subdivisions=2)
        t = paired(scene, plan["runs"])
        first = first or t["PENUMBRA"]
        case = f"{n} closed cow instances (94k triangles each)"
        rows.append(_row("instances", case, t, f"{t['PENUMBRA'] / first:.2f}x one", plan["runs"]))
    return rows


def section_map_detail(plan):
    """Penumbra only: Caster Detail 0 and 2 interleaved, F12 medians; the note gives the
    triangles drawn into maps per frame (``FrameStats.shadow_triangles``) and the error."""
    from devkit.render import render

    scene = bunny_field(1, subdivisions=2)
    scene.render.resolution_x, scene.render.resolution_y = 480, 270
    for ob in [o for o in scene.objects if o.type == "LIGHT"]:
        bpy.data.objects.remove(ob)
    scenes.light(scene, "Area", "AREA", 400.0, location=(1.0, -1.5, 3.0), rotation=(math.radians(35), 0, 0), size=1.5)
    _penumbra(scene)
    scene.penumbra.render_samples = 16
    triangles = sum(len(p.vertices) - 2 for p in scene.objects["Bunny"].data.polygons)
    images, drawn, times = {}, {}, {0.0: [], 2.0: []}
    for detail in times:
        scene.penumbra.shadow_caster_detail = detail
        images[detail] = render(scene)["Combined"][..., :3]  # also the warm-up
        drawn[detail] = _map_triangles(scene)
    for _ in range(plan["runs"]):
        for detail in times:
            scene.penumbra.shadow_caster_detail = detail
            start = time.perf_counter()
            _render()
            times[detail].append(time.perf_counter() - start)
    diff = np.abs(images[2.0] - images[0.0]).max(axis=-1)
    rows = []
    for detail, values in times.items():
        t = {"PENUMBRA": statistics.median(values)}
        note = f"{drawn[detail] / 16 / 1e6:.2f}M triangles into maps per sample ({triangles / 1e6:.2f}M in the mesh)"
        if detail:
            note += (
                f"; {times[0.0] and statistics.median(times[0.0]) / t['PENUMBRA']:.2f}x faster than every "
                f"triangle; image error against it: mean {diff.mean():.5f}, max {diff.max():.3f}"
            )
        rows.append(_row("map_detail", f"16 samples, Caster Detail {detail:g}", t, note, plan["runs"]))
    return rows


def _map_triangles(scene):
    """Triangles drawn into shadow maps by one F12 of ``scene`` (its FrameStats)."""
    from penumbra.engine.render_engine import PenumbraEngineCore

    seen = []
    original = PenumbraEngineCore.render_frame

    def recording(self, *args, **kwargs):
        out = original(self, *args, **kwargs)
        seen.append(out.stats.shadow_triangles)
        return out

    PenumbraEngineCore.render_frame = recording
    try:
        _render()
    finally:
        PenumbraEngineCore.render_frame = original
    return sum(seen)


def section_triangles(plan):
    from penumbra.engine.scene.extract import geometry_from_mesh

    rows = []
    for n in plan["grids"]:
        scene = scenes.empty_scene(960, 540)
        grid = grid_mesh(scene, n)
        grid.data.materials.append(scenes.white())
        scenes.plane(scene, "Ground", size=12.0, mat=grid.data.materials[0])
        scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(35), 0, math.radians(25)))
        scenes.look_at(scene, (0.0, -9.0, 7.0), (0.0, 0.0, 0.0))
        t = paired(scene, plan["runs"])
        copies = [bare_copy(grid.data) for _ in range(3)]
        extracts = []
        for _ in range(3):
            start = time.perf_counter()
            geometry_from_mesh(grid.data)
            extracts.append(time.perf_counter() - start)
        copy, extract = statistics.median(copies), statistics.median(extracts)
        note = f"extraction {extract * 1e3:.0f} ms = {extract / copy:.2f}x the bare copy ({copy * 1e3:.0f} ms)"
        rows.append(_row("triangles", f"{2 * n * n:,} triangles", t, note, plan["runs"]))
    return rows


def textured_field(kind):
    """16 UV spheres (with UV maps) over a ground under a sun, every material ``kind``:
    'constant', 'base' (a 1024² image on Base Color) or 'maps' (Base Color, Roughness and a
    normal map, each a 1024² image)."""
    scene = scenes.empty_scene(960, 540)
    mat = scenes.material("Field", (0.7, 0.6, 0.5), roughness=0.5)
    if kind != "constant":
        rng = np.random.default_rng(1)
        tree = mat.node_tree
        bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        inputs = {"base": ("Base Color",), "maps": ("Base Color", "Roughness", "Normal")}[kind]
        for name in inputs:
            image = bpy.data.images.new(name, 1024, 1024)
            image.pixels.foreach_set(rng.random(1024 * 1024 * 4, dtype=np.float32))
            node = tree.nodes.new("ShaderNodeTexImage")
            node.image = image
            if name == "Normal":
                image.colorspace_settings.name = "Non-Color"
                normal_map = tree.nodes.new("ShaderNodeNormalMap")
                normal_map.inputs["Strength"].default_value = 0.3
                tree.links.new(node.outputs["Color"], normal_map.inputs["Color"])
                tree.links.new(normal_map.outputs["Normal"], bsdf.inputs["Normal"])
            else:
                tree.links.new(node.outputs["Color"], bsdf.inputs[name])
    bpy.ops.mesh.primitive_plane_add(size=14.0)
    bpy.context.object.data.materials.append(mat)
    for i in range(16):
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.6, location=((i % 4) * 1.6 - 2.4, (i // 4) * 1.6 - 2.4, 0.6))
        bpy.context.object.data.materials.append(mat)
        bpy.ops.object.shade_smooth()
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(35), 0, math.radians(25)))
    scenes.look_at(scene, (0.0, -9.0, 7.0), (0.0, 0.0, 0.0))
    return scene


def section_materials(plan):
    rows = []
    base = None
    for kind, label in (("constant", "constant"), ("base", "Base Color image"), ("maps", "colour+roughness+normal")):
        t = paired(textured_field(kind), plan["runs"])
        base = base or t["PENUMBRA"]
        rows.append(_row("materials", f"16 spheres, {label}", t, f"{t['PENUMBRA'] / base:.2f}x constant", plan["runs"]))
    return rows


def section_gpu(plan):
    """The GPU targets: the demo (without post layers) at 640x360 and 16 samples against
    EEVEE's 16 samples (``engines.EEVEE_SAMPLES``; EEVEE in the baseline column), and the
    textured asset at 960x540 and 1 sample against Workbench; each with one fenced frame's
    CPU/GPU split. On llvmpipe these are pixel-bound; on a GPU they are the frame's CPU."""
    rows = []
    scene = demo(640, 360)
    scene.penumbra.render_samples = 16
    t = paired(scene, plan["runs"], baseline=_eevee)
    note = "baseline: EEVEE 16 samples; " + cpu_note(_fenced_stats(scene))
    rows.append(_row("gpu", "demo 640x360, 16 samples (EEVEE: 16 samples)", t, note, plan["runs"]))
    asset = scenes.textured_asset(960, 540)
    t = paired(asset, plan["runs"])
    rows.append(_row("gpu", "textured asset 960x540, 1 sample", t, cpu_note(_fenced_stats(asset)), plan["runs"]))
    return rows


PLANS = {
    "full": {
        "resolutions": ((480, 270), (960, 540), (1920, 1080)),
        "lights": (1, 8, 32, 64),
        "objects": (10, 100, 1000, 10000),
        "grids": (187, 500, 1000),  # 70k, 500k, 2M triangles
        "runs": 5,
    },
    "quick": {
        "resolutions": ((960, 540),),
        "lights": (1, 32),
        "objects": (10, 1000),
        "grids": (187, 500),
        "runs": 3,
    },
}


def run(args):
    session.load_penumbra().register()
    plan = dict(PLANS["quick" if args.quick else "full"])
    if args.runs:
        plan["runs"] = args.runs
    chosen = [s.strip() for s in args.sections.split(",") if s.strip()]
    unknown = sorted(set(chosen) - set(SECTIONS))
    if unknown:
        print(f"bench perf: unknown section(s): {', '.join(unknown)}", file=sys.stderr)
        return 2
    rows = []
    for name in chosen:
        print(f"bench perf: {name}", file=sys.stderr, flush=True)
        rows += globals()[f"section_{name}"](plan)
    args.out.mkdir(parents=True, exist_ok=True)
    report.write_csv(args.out / "perf.csv", rows, CSV_FIELDS)
    cells = [
        [
            r["section"],
            r["case"],
            report.cell(r["penumbra_ms"], 4),
            report.cell(r["workbench_ms"], 4),
            f"{r['ratio']:.2f}x" if r["ratio"] else "",
            r["note"],
        ]
        for r in rows
    ]
    print(report.markdown_table(["Section", "Case", "Penumbra (ms)", "Workbench (ms)", "Ratio", "Note"], cells))
    print()
    print(
        f"Blender {bpy.app.version_string}; GPU: {session.gpu_renderer() or 'n/a'}; medians of {plan['runs']} "
        "interleaved renders after one warm-up each. Workbench: anti-aliasing off, shadows on."
    )
    return 0
