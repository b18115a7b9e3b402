"""glTF assets as a new user meets them: the files of ``devkit/gltf/`` (PBR textures:
base colour, metallic-roughness, normal, emissive, occlusion; alpha-blended and alpha-clipped
parts; a specular-glossiness material; thin emissive lines) imported with Blender's own glTF
importer, each on a ground under a sun and an area light (``devkit.assets.gltf_scene``), and
rendered by Penumbra (defaults, 16 samples), EEVEE (16 TAA samples) and Cycles (16 spp), all
set up by ``devkit.engines`` (Cycles: direct light only, plus transparent bounces so alpha
shows).

Error is the mean absolute difference of the display-referred RGB (the 'Standard' view, 0..1)
against converged Cycles (1024 spp; 256 with --quick; cached in out/reference_cache). Time is
the median of ``--runs`` F12 renders after the render that is measured (the warm-up). The
render report's warnings of each Penumbra render are recorded: a warning that names
something the asset does not use is a false one.

-> ``<out>/assets.csv`` and a contact sheet ``<out>/assets.png`` (or ``--sheet``): rows are
assets; columns the Cycles reference, Penumbra, EEVEE and |error| x4 of both. ``--quick``
(one timed run, 256 spp references) took 8 minutes on 2 busy shared cores with llvmpipe, most
of it EEVEE's renders (the alpha-blended asset's above all); cached references save about 2.
"""

import hashlib
import os
import sys
import tempfile
from pathlib import Path

import bpy
import numpy as np

from devkit import assets, engines, report, session, timing
from devkit import reference_kit as kit
from devkit.render import render
from devkit.session import ROOT

HELP = "glTF assets imported with Blender's importer: error against Cycles and time, Penumbra vs EEVEE"
WIDTH, HEIGHT = 240, 135
SETTINGS = {
    "PENUMBRA": {"render_samples": 16},
    "EEVEE": {},
    "CYCLES": {"samples": 16, "transparent_max_bounces": 8},
}
COMPARED = ("PENUMBRA", "EEVEE", "CYCLES")
CACHE = ROOT / "out" / "reference_cache"
FIELDS = ["asset", "engine", "samples", "mae", "time_s", "warnings"]


def add_arguments(parser):
    parser.add_argument("--out", default="out")
    timing.add_runs_argument(parser, None, "timed renders per engine and asset (default 3; 1 with --quick)")
    parser.add_argument("--quick", action="store_true", help="references at 256 spp, one timed run")
    parser.add_argument("--reference-spp", type=int, default=None, help="Cycles reference samples (default 1024)")
    parser.add_argument("--only", default="", help="comma-separated asset names (default: all)")
    parser.add_argument("--sheet", default=None, help="where the contact sheet goes (default <out>/assets.png)")


def log(message):
    print(f"bench assets: {message}", file=sys.stderr, flush=True)


def display(linear):
    """Scene-linear RGB(A) -> display RGB in 0..1 through the 'Standard' view (sRGB)."""
    x = np.clip(np.nan_to_num(linear[..., :3], nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)
    return np.where(x <= 0.0031308, x * 12.92, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def mae(a, b):
    return float(np.mean(np.abs(a - b)))


class Captured:
    """File descriptor 1 (where Blender prints the render report in background mode) into a
    temporary file for the duration; ``text`` holds what was printed."""

    def __enter__(self):
        sys.stdout.flush()
        self._file = tempfile.TemporaryFile()
        self._saved = os.dup(1)
        os.dup2(self._file.fileno(), 1)
        return self

    def __exit__(self, *exc):
        sys.stdout.flush()
        os.dup2(self._saved, 1)
        os.close(self._saved)
        self._file.seek(0)
        self.text = self._file.read().decode(errors="replace")
        self._file.close()
        sys.stderr.write(self.text)
        return False


def warnings_in(text):
    """The warning and error lines of a render report."""
    return [line.strip() for line in text.splitlines() if line.lstrip().lower().startswith(("warning", "error"))]


def reference(name, spp, cache_dir=CACHE):
    """Display RGB of converged Cycles for asset ``name``: from the cache when present (keyed by
    the file's contents, samples, size and Blender line), else rendered and cached."""
    digest = hashlib.sha256((assets.GLTF / f"{name}.glb").read_bytes()).hexdigest()[:12]
    major, minor = bpy.app.version[:2]
    path = Path(cache_dir) / f"gltf-{name}-{digest}-{spp}spp-{WIDTH}x{HEIGHT}-blender{major}.{minor}.npy"
    if path.exists():
        return np.load(path)
    scene = assets.gltf_scene(name, WIDTH, HEIGHT)
    engines.configure(scene, "CYCLES", **dict(SETTINGS["CYCLES"], samples=spp))
    with session.stdout_to_stderr():
        image = display(render(scene)["Combined"][::-1])
    kit.save_npy(path, image)
    return image


def measure(scene, engine, ref, runs):
    """(display image, MAE against ``ref``, median seconds, warnings) of one engine."""
    engines.configure(scene, engine, **SETTINGS[engine])
    with Captured() as out:
        image = display(render(scene)["Combined"][::-1])
    with session.stdout_to_stderr():
        seconds = timing.render(runs, warmup=0).median
    return image, mae(image, ref), seconds, warnings_in(out.text)


def draw_sheet(path, results, spp):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    columns = (f"Cycles {spp} spp", "Penumbra", "EEVEE", "|Penumbra - ref| x4", "|EEVEE - ref| x4")
    fig, axes = plt.subplots(len(results), len(columns), figsize=(2.6 * len(columns), 1.7 * len(results)), dpi=110)
    axes = np.atleast_2d(axes)
    for r, (name, images, rows) in enumerate(results):
        ref = images["reference"]
        tiles = (ref, images["PENUMBRA"], images["EEVEE"])
        tiles += (np.abs(images["PENUMBRA"] - ref) * 4, np.abs(images["EEVEE"] - ref) * 4)
        for c, tile in enumerate(tiles):
            ax = axes[r, c]
            ax.imshow(np.clip(tile, 0.0, 1.0), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(columns[c], fontsize=9)
        by = {row["engine"]: row for row in rows}
        axes[r, 0].set_ylabel(name, fontsize=9)
        axes[r, 1].set_xlabel(f"MAE {by['Penumbra']['mae']:.4f}", fontsize=8)
        axes[r, 2].set_xlabel(f"MAE {by['EEVEE']['mae']:.4f}", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def run(args):
    runs = args.runs or (1 if args.quick else 3)
    spp = args.reference_spp or (256 if args.quick else 1024)
    names = [n for n in args.only.split(",") if n] or list(assets.GLTF_ASSETS)
    unknown = sorted(set(names) - set(assets.GLTF_ASSETS))
    if unknown:
        raise SystemExit(f"unknown asset(s) {', '.join(unknown)}; known: {', '.join(assets.GLTF_ASSETS)}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    session.load_penumbra().register()

    results, rows = [], []
    for name in names:
        log(f"{name}: Cycles reference ({spp} spp, {WIDTH}x{HEIGHT})")
        with session.stdout_to_stderr():
            ref = reference(name, spp)
            scene = assets.gltf_scene(name, WIDTH, HEIGHT)
        images, asset_rows = {"reference": ref}, []
        for engine in COMPARED:
            log(f"{name}: {engines.LABELS[engine]}")
            images[engine], error, seconds, warnings = measure(scene, engine, ref, runs)
            settings = SETTINGS[engine]
            samples = settings.get("render_samples") or settings.get("samples") or engines.EEVEE_SAMPLES
            asset_rows.append(
                {
                    "asset": name,
                    "engine": engines.LABELS[engine],
                    "samples": samples,
                    "mae": error,
                    "time_s": seconds,
                    "warnings": " | ".join(warnings) if engine == "PENUMBRA" else "",
                }
            )
        results.append((name, images, asset_rows))
        rows += asset_rows

    report.write_csv(out / "assets.csv", rows, FIELDS)
    sheet = Path(args.sheet) if args.sheet else out / "assets.png"
    sheet.parent.mkdir(parents=True, exist_ok=True)
    draw_sheet(sheet, results, spp)
    log(f"wrote {out / 'assets.csv'} and {sheet}")

    table = []
    for name, _images, asset_rows in results:
        by = {row["engine"]: row for row in asset_rows}
        pen, eevee, cycles = by["Penumbra"], by["EEVEE"], by["Cycles"]
        table.append(
            [
                name,
                f"{pen['mae']:.4f}",
                f"{eevee['mae']:.4f}",
                f"{cycles['mae']:.4f}",
                f"{pen['time_s']:.2f}",
                f"{eevee['time_s']:.2f}",
                f"{cycles['time_s']:.2f}",
                pen["warnings"] or "none",
            ]
        )
    header = [
        "Asset",
        "Penumbra MAE",
        "EEVEE MAE",
        "Cycles 16 spp MAE",
        "Penumbra (s)",
        "EEVEE (s)",
        "Cycles (s)",
        "Penumbra's warnings",
    ]
    print(report.markdown_table(header, table, "l" + "r" * 6 + "l"))
    print(
        f"\n{bpy.app.version_string}; {WIDTH}x{HEIGHT}; MAE of display RGB (0..1) against Cycles {spp} spp; "
        f"median of {runs} F12 render(s). {engines.SUMMARY}"
    )
    return 0
