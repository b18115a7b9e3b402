"""The camera's lens and shutter by sampling: what each sample buys in error, and its cost.

Three scenes from the demo scene without its post layers: ``defocus`` (its camera focused on
the ball at f/0.1: the ground before it and the slab and pillar behind it well out of focus),
``moving`` (the ball crossing the view at 3 units a frame, a shutter of half a frame) and
``spinning`` (the crate turning half a turn a frame), rendered by Penumbra at ``--samples``
(4, 16, 64, 256), Cycles at 16 ... 256 spp and EEVEE at its defaults (16 samples; its depth
of field a post-process, its motion blur one step), all with the same lens, shutter and pixel
filter (Blackman-Harris, Filter Size 1.5: Cycles' Pixel Filter Width 1.5), against Cycles at
``--reference`` spp (1024; direct light: max_bounces 0, cached per clone under
out/reference_cache). For each: the median time of ``--runs`` F12 renders after a warm-up and
the image's MAE in display space (Standard view, sRGB-encoded, clipped to [0, 1]).

Writes ``<out>/camera.csv`` and ``<out>/camera.png`` (error against time per scene, and each
scene's reference beside Penumbra's 64 samples); a Markdown table to stdout. ``--quick``:
160x90, reference 256 spp, one run.
"""

import hashlib
import math
import sys
import time
from pathlib import Path

import bpy
import numpy as np

from devkit import report, scenes, session, timing
from devkit.engines import EEVEE_SAMPLES, configure
from devkit.render import render

HELP = "depth of field: error against time vs Cycles (same lens) and EEVEE -> <out>/camera.csv, camera.png"

CACHE = Path("out") / "reference_cache"
FSTOP = 0.1
CSV_FIELDS = ["scene", "engine", "samples", "time_s", "mae"]


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default out)")
    timing.add_runs_argument(parser, 3, "timed renders per configuration (default 3; 1 with --quick)")
    parser.add_argument("--quick", action="store_true", help="160x90, reference 256 spp, one run")
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--samples", default="4,16,64,256", help="Penumbra's render samples (comma-separated)")
    parser.add_argument("--cycles-spp", default="16,64,128,256", help="Cycles' samples to time (comma-separated)")
    parser.add_argument("--reference", type=int, default=1024, help="Cycles' reference spp (default 1024)")
    parser.add_argument("--scenes", default="defocus,moving,spinning", help="comma-separated: " + ", ".join(SCENES))


def log(message):
    print(f"bench camera: {message}", file=sys.stderr, flush=True)


def _demo(width, height):
    scene = scenes.demo_scene(width, height)
    scene.penumbra.layers.clear()
    scene.view_settings.view_transform = "Standard"
    scene.render.filter_size = scene.penumbra.filter_size = 1.5  # EEVEE's and Penumbra's
    return scene


def defocus(width, height):
    """The demo scene focused on the ball at f/0.1."""
    scene = _demo(width, height)
    cam = scene.camera.data
    cam.dof.use_dof = True
    cam.dof.focus_object = scene.objects["Ball"]
    cam.dof.aperture_fstop = FSTOP
    return scene


def _animated(scene, ob, path, index, values):
    for frame, value in zip((1, 3), values, strict=True):
        getattr(ob, path)[index] = value
        ob.keyframe_insert(path, index=index, frame=frame)
    scene.frame_set(2)
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 0.5
    scene.render.motion_blur_position = "CENTER"
    return scene


def moving(width, height):
    """The ball crossing the view at 3 units a frame (1.5 within the shutter)."""
    scene = _demo(width, height)
    ball = scene.objects["Ball"]
    x = ball.location.x
    return _animated(scene, ball, "location", 0, (x - 3.0, x + 3.0))


def spinning(width, height):
    """The crate turning half a turn a frame about its vertical axis."""
    scene = _demo(width, height)
    return _animated(scene, scene.objects["Crate"], "rotation_euler", 2, (0.0, 2.0 * math.pi))


SCENES = {"defocus": defocus, "moving": moving, "spinning": spinning}


def _cycles(scene, spp):
    configure(scene, "CYCLES", samples=spp)
    scene.cycles.pixel_filter_type = "BLACKMAN_HARRIS"
    scene.cycles.filter_width = scene.penumbra.filter_size  # Cycles widens Blackman-Harris 2x itself: the same window


def display(image):
    """Scene-linear RGB -> sRGB-encoded display values in [0, 1] (the Standard view)."""
    c = np.clip(np.asarray(image, np.float64)[..., :3], 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def reference(name, scene, spp):
    """Cycles' image of scene ``name`` at ``spp`` (display values), cached by Blender version,
    scene, size and spp (and this file's content)."""
    own = hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:10]
    size = f"{scene.render.resolution_x}x{scene.render.resolution_y}"
    key = f"camera-{own}-{bpy.app.version_string}-{name}-{size}-{spp}"
    path = CACHE / f"{hashlib.sha256(key.encode()).hexdigest()[:16]}.npy"
    if path.exists():
        return np.load(path)
    _cycles(scene, spp)
    image = display(render(scene)["Combined"])
    CACHE.mkdir(parents=True, exist_ok=True)
    np.save(path, image)
    return image


def measure(scene, runs, ref):
    image = display(render(scene)["Combined"])  # also the warm-up
    return timing.render(runs, warmup=0).median, float(np.abs(image - ref).mean()), image


def plot(rows, shown, path, title):
    """Error against time per scene (top), each scene's reference and Penumbra's 64 samples."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(shown)
    fig, axes = plt.subplots(3, len(names), figsize=(4.5 * len(names), 10), squeeze=False)
    styles = {"Penumbra": ("tab:blue", "-o"), "Cycles": ("tab:red", "-P"), "EEVEE": ("tab:purple", "*")}
    for col, name in enumerate(names):
        ax = axes[0, col]
        for engine, (colour, style) in styles.items():
            pts = sorted((r for r in rows if r["engine"] == engine and r["scene"] == name), key=lambda r: r["samples"])
            ax.plot([r["time_s"] for r in pts], [r["mae"] for r in pts], style, color=colour, label=engine)
            for r in pts:
                where = (r["time_s"], r["mae"])
                ax.annotate(str(r["samples"]), where, fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per frame (s, median, log)")
        ax.set_ylabel("display MAE vs the reference")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(name, fontsize=9)
        for row, (label, image) in enumerate(shown[name], start=1):
            axes[row, col].imshow(image[::-1], interpolation="nearest")
            axes[row, col].set_title(f"{name}: {label}", fontsize=8)
            axes[row, col].axis("off")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def sweep(name, width, height, spp, samples, cycles_spp, runs):
    """Rows of scene ``name`` and its (reference, Penumbra 64) images."""
    scene = SCENES[name](width, height)
    log(f"{name}: Cycles reference {spp} spp at {width}x{height}")
    ref = reference(name, scene, spp)
    rows, best = [], None
    for n in samples:
        log(f"{name}: Penumbra {n}")
        configure(scene, "PENUMBRA", render_samples=n)
        seconds, mae, image = measure(scene, runs, ref)
        rows.append({"scene": name, "engine": "Penumbra", "samples": n, "time_s": seconds, "mae": mae})
        best = (f"Penumbra {n} samples", image) if n <= 64 or best is None else best
    for n in cycles_spp:
        log(f"{name}: Cycles {n}")
        _cycles(scene, n)
        seconds, mae, _image = measure(scene, runs, ref)
        rows.append({"scene": name, "engine": "Cycles", "samples": n, "time_s": seconds, "mae": mae})
    log(f"{name}: EEVEE")
    configure(scene, "EEVEE", taa_render_samples=EEVEE_SAMPLES)
    seconds, mae, _image = measure(scene, runs, ref)
    rows.append({"scene": name, "engine": "EEVEE", "samples": EEVEE_SAMPLES, "time_s": seconds, "mae": mae})
    return rows, [(f"Cycles {spp} spp", ref), best]


def run(args):
    width, height = (160, 90) if args.quick else (args.width, args.height)
    runs = 1 if args.quick else args.runs
    spp = 256 if args.quick else args.reference
    samples = [int(n) for n in args.samples.split(",") if n.strip()]
    cycles_spp = [int(n) for n in args.cycles_spp.split(",") if n.strip()]
    names = [n.strip() for n in args.scenes.split(",") if n.strip()]
    args.out.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()
    started = time.perf_counter()
    rows, shown = [], {}
    with session.stdout_to_stderr():
        for name in names:
            scene_rows, shown[name] = sweep(name, width, height, spp, samples, cycles_spp, runs)
            rows += scene_rows
    report.write_csv(args.out / "camera.csv", rows, CSV_FIELDS)
    title = (
        f"Depth of field (f/{FSTOP}) and motion blur (a shutter of half a frame), {width}x{height}, against "
        f"Cycles {spp} spp; Blender {bpy.app.version_string}"
    )
    plot(rows, shown, args.out / "camera.png", title)
    cells = [[r["scene"], r["engine"], r["samples"], f"{r['time_s']:.3f}", f"{r['mae']:.4f}"] for r in rows]
    print(f"### {title}\n")
    print(report.markdown_table(["Scene", "Engine", "Samples", "Time (s)", "Display MAE"], cells))
    print(
        f"\nGPU: {session.gpu_renderer() or 'n/a'}; {runs} timed render(s) per configuration; "
        f"{(time.perf_counter() - started) / 60:.1f} min. Wrote camera.csv, camera.png."
    )
    return 0
