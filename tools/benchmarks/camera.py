"""Depth of field by lens sampling: what each sample buys in error, and what it costs.

The demo scene without its post layers, its camera focused on the ball at f/0.1 (the ground
before it and the slab and pillar behind it well out of focus), rendered by Penumbra at
``--samples`` (4, 16, 64, 256), Cycles at 16 ... 256 spp and EEVEE at its defaults (16
samples, its depth of field a post-process), all with the same lens and the same pixel filter
(Blackman-Harris, Filter Size 1.5: Cycles' Pixel Filter Width 1.5), against Cycles at ``--reference`` spp
(1024; direct light: max_bounces 0, cached per clone under out/reference_cache). For each: the
median time of ``--runs`` F12 renders after a warm-up and the image's MAE in display space
(Standard view, sRGB-encoded, clipped to [0, 1]).

Writes ``<out>/camera.csv`` and ``<out>/camera.png`` (error against time, and the reference
beside Penumbra's 16 and 64 samples); a Markdown table to stdout. ``--quick``: 160x90,
reference 256 spp.
"""

import hashlib
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
CSV_FIELDS = ["engine", "samples", "time_s", "mae"]


def add_arguments(parser):
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (default out)")
    timing.add_runs_argument(parser, 3, "timed renders per configuration (default 3; 1 with --quick)")
    parser.add_argument("--quick", action="store_true", help="160x90, reference 256 spp, one run")
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--samples", default="4,16,64,256", help="Penumbra's render samples (comma-separated)")
    parser.add_argument("--cycles-spp", default="16,64,128,256", help="Cycles' samples to time (comma-separated)")
    parser.add_argument("--reference", type=int, default=1024, help="Cycles' reference spp (default 1024)")


def log(message):
    print(f"bench camera: {message}", file=sys.stderr, flush=True)


def build(width, height):
    """The demo scene without post layers, focused on the ball at f/0.1."""
    scene = scenes.demo_scene(width, height)
    scene.penumbra.layers.clear()
    scene.view_settings.view_transform = "Standard"
    cam = scene.camera.data
    cam.dof.use_dof = True
    cam.dof.focus_object = scene.objects["Ball"]
    cam.dof.aperture_fstop = FSTOP
    scene.render.filter_size = scene.penumbra.filter_size = 1.5  # EEVEE's and Penumbra's
    return scene


def _cycles(scene, spp):
    configure(scene, "CYCLES", samples=spp)
    scene.cycles.pixel_filter_type = "BLACKMAN_HARRIS"
    scene.cycles.filter_width = scene.penumbra.filter_size  # Cycles widens Blackman-Harris 2x itself: the same window


def display(image):
    """Scene-linear RGB -> sRGB-encoded display values in [0, 1] (the Standard view)."""
    c = np.clip(np.asarray(image, np.float64)[..., :3], 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def reference(scene, spp):
    """Cycles' image at ``spp`` (display values), cached by Blender version, size and spp."""
    key = f"camera-{bpy.app.version_string}-{scene.render.resolution_x}x{scene.render.resolution_y}-{spp}-{FSTOP}"
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


def plot(rows, shown, ref, path, title):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(12, 7))
    ax = fig.add_subplot(2, 1, 1)
    styles = {"Penumbra": ("tab:blue", "-o"), "Cycles": ("tab:red", "-P"), "EEVEE": ("tab:purple", "*")}
    for engine, (colour, style) in styles.items():
        pts = sorted((r for r in rows if r["engine"] == engine), key=lambda r: r["samples"])
        ax.plot([r["time_s"] for r in pts], [r["mae"] for r in pts], style, color=colour, label=engine)
        for r in pts:
            ax.annotate(
                str(r["samples"]), (r["time_s"], r["mae"]), fontsize=7, xytext=(3, 3), textcoords="offset points"
            )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time per frame (s, median, log)")
    ax.set_ylabel("display MAE vs the Cycles reference")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title, fontsize=9)
    for k, (label, image) in enumerate([("Cycles reference", ref), *shown]):
        sub = fig.add_subplot(2, 3, 4 + k)
        sub.imshow(image[::-1], interpolation="nearest")
        sub.set_title(label, fontsize=8)
        sub.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run(args):
    width, height = (160, 90) if args.quick else (args.width, args.height)
    runs = 1 if args.quick else args.runs
    spp = 256 if args.quick else args.reference
    samples = [int(n) for n in args.samples.split(",") if n.strip()]
    cycles_spp = [int(n) for n in args.cycles_spp.split(",") if n.strip()]
    args.out.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()
    started = time.perf_counter()
    rows, shown = [], []
    with session.stdout_to_stderr():
        scene = build(width, height)
        log(f"Cycles reference {spp} spp at {width}x{height}")
        ref = reference(scene, spp)
        for n in samples:
            log(f"Penumbra {n}")
            configure(scene, "PENUMBRA", render_samples=n)
            seconds, mae, image = measure(scene, runs, ref)
            rows.append({"engine": "Penumbra", "samples": n, "time_s": seconds, "mae": mae})
            if n in (16, 64):
                shown.append((f"Penumbra {n} samples", image))
        for n in cycles_spp:
            log(f"Cycles {n}")
            _cycles(scene, n)
            seconds, mae, _image = measure(scene, runs, ref)
            rows.append({"engine": "Cycles", "samples": n, "time_s": seconds, "mae": mae})
        log("EEVEE")
        configure(scene, "EEVEE", taa_render_samples=EEVEE_SAMPLES)
        seconds, mae, _image = measure(scene, runs, ref)
        rows.append({"engine": "EEVEE", "samples": EEVEE_SAMPLES, "time_s": seconds, "mae": mae})
    report.write_csv(args.out / "camera.csv", rows, CSV_FIELDS)
    title = (
        f"Depth of field (demo scene, f/{FSTOP}, focused on the ball), {width}x{height}, against Cycles {spp} spp; "
        f"Blender {bpy.app.version_string}"
    )
    plot(rows, shown, ref, args.out / "camera.png", title)
    cells = [[r["engine"], r["samples"], f"{r['time_s']:.3f}", f"{r['mae']:.4f}"] for r in rows]
    print(f"### {title}\n")
    print(report.markdown_table(["Engine", "Samples", "Time (s)", "Display MAE"], cells))
    print(
        f"\nGPU: {session.gpu_renderer() or 'n/a'}; {runs} timed render(s) per configuration; "
        f"{(time.perf_counter() - started) / 60:.1f} min. Wrote camera.csv, camera.png."
    )
    return 0
