"""Contact sheet of the material test scenes, Penumbra against EEVEE and Cycles: docs/materials.png.

    .venv/blender-5.2/bin/python -m tools.material_sheet --out docs [--csv out/materials.csv]

One row per builder of ``devkit.material_scenes`` (at its own size unless --width/--height or
--scale say otherwise), columns Penumbra | EEVEE | Cycles. Penumbra renders at its defaults with
16 samples; EEVEE and Cycles as ``devkit.engines`` sets them up, Cycles with 32 samples and
transparent bounces (so alpha shows and lets light through; other bounces stay off). Each
render is saved through Blender's colour management (the scenes' 'Standard' view) as PNG, and
the tiles are laid out with matplotlib. For every builder the tool prints, and --csv writes, the
mean absolute difference of the scene-linear Combined RGB: Penumbra against EEVEE and against
Cycles, and EEVEE against Cycles (how far the two references are apart). A render that fails
is a tile saying so and an empty number; the sheet is still written.
"""

import argparse
import inspect
import tempfile
import time
from pathlib import Path

import numpy as np

from devkit import engines, imageio, material_scenes, render, report, session

ENGINES = ("PENUMBRA", "EEVEE", "CYCLES")
SETTINGS = {
    "PENUMBRA": {"render_samples": 16},
    "EEVEE": {},
    "CYCLES": {"samples": 32, "transparent_max_bounces": 8},
}
PAIRS = (("PENUMBRA", "EEVEE"), ("PENUMBRA", "CYCLES"), ("EEVEE", "CYCLES"))
FIELDS = ["builder", "width", "height", "penumbra_vs_eevee", "penumbra_vs_cycles", "eevee_vs_cycles", "seconds"]


def pair_key(a, b):
    return f"{a.lower()}_vs_{b.lower()}"


def builder_size(build, width=None, height=None, scale=1.0):
    """The size a builder renders at: its own defaults times ``scale``, or the overrides."""
    params = inspect.signature(build).parameters
    w = width or max(1, round(params["width"].default * scale))
    h = height or max(1, round(params["height"].default * scale))
    return w, h


def render_tile(scene, engine, png_path):
    """Render ``scene`` with ``engine``: (scene-linear Combined, display-referred PNG pixels),
    both top row first, or (None, error text) when the render fails."""
    engines.configure(scene, engine, **SETTINGS[engine])
    try:
        with session.stdout_to_stderr():
            linear = render.render(scene)["Combined"][::-1]
            imageio.save_render(scene, png_path, "PNG", "8")
        return linear, imageio.read_image(png_path)
    except Exception as exc:  # a failing engine makes a tile, not a failed sheet
        return None, f"{type(exc).__name__}: {exc}"


def mean_abs_diff(a, b):
    """Mean absolute difference of the RGB of two scene-linear images (None if either is)."""
    if a is None or b is None:
        return None
    a, b = (np.nan_to_num(x[..., :3], nan=0.0, posinf=0.0, neginf=0.0) for x in (a, b))
    return float(np.mean(np.abs(a - b)))


def render_builder(name, size, tmp):
    """Render one builder with every engine: (tiles {engine: pixels or error text}, row dict)."""
    t = time.perf_counter()
    scene = material_scenes.BUILDERS[name](*size)
    linear, tiles = {}, {}
    for engine in ENGINES:
        linear[engine], tiles[engine] = render_tile(scene, engine, Path(tmp) / f"{name}_{engine}.png")
    row = {"builder": name, "width": size[0], "height": size[1]}
    for a, b in PAIRS:
        row[pair_key(a, b)] = mean_abs_diff(linear[a], linear[b])
    row["seconds"] = time.perf_counter() - t
    return tiles, row


def over_black(pixels):
    """Display pixels (straight alpha, as a PNG holds them) over black: holdouts show black."""
    rgb = pixels[..., :3].clip(0.0, 1.0)
    return rgb * pixels[..., 3:4].clip(0.0, 1.0) if pixels.shape[-1] == 4 else rgb


def diff_text(row):
    return " ".join(
        f"{engines.LABELS[b]} {report.cell(row[pair_key('PENUMBRA', b)], 3) or '-'}" for b in ("EEVEE", "CYCLES")
    )


def draw_sheet(path, results):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = len(results)
    fig, axes = plt.subplots(rows, len(ENGINES), figsize=(2.3 * len(ENGINES) + 1.2, 2.4 * rows), dpi=110, squeeze=False)
    for r, (tiles, row) in enumerate(results):
        for c, engine in enumerate(ENGINES):
            ax = axes[r, c]
            ax.set_xticks([])
            ax.set_yticks([])
            tile = tiles[engine]
            if isinstance(tile, str):
                ax.text(0.5, 0.5, "render failed\n" + tile[:120], ha="center", va="center", wrap=True, fontsize=6)
            else:
                ax.imshow(over_black(tile), interpolation="nearest")
            if r == 0:
                ax.set_title(engines.LABELS[engine], fontsize=10)
        axes[r, 0].set_ylabel(row["builder"], fontsize=9)
        axes[r, 0].set_xlabel("Δ " + diff_text(row), fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs")
    ap.add_argument("--only", default="", help="comma-separated builder names (default: all)")
    ap.add_argument("--width", type=int, default=None, help="override every builder's width")
    ap.add_argument("--height", type=int, default=None, help="override every builder's height")
    ap.add_argument("--scale", type=float, default=1.0, help="scale the builders' own sizes")
    ap.add_argument("--csv", default=None, help="write the difference numbers to this CSV file")
    args = ap.parse_args(argv)
    names = [n for n in args.only.split(",") if n] or list(material_scenes.BUILDERS)
    unknown = [n for n in names if n not in material_scenes.BUILDERS]
    if unknown:
        raise SystemExit(f"unknown builder(s) {', '.join(unknown)}; known: {', '.join(material_scenes.BUILDERS)}")
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)

    session.load_penumbra().register()
    start = time.perf_counter()
    results = []
    print(f"{'builder':22s} {'size':>9s}  mean |Δ| linear RGB: Penumbra-EEVEE  Penumbra-Cycles  EEVEE-Cycles")
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            size = builder_size(material_scenes.BUILDERS[name], args.width, args.height, args.scale)
            tiles, row = render_builder(name, size, tmp)
            results.append((tiles, row))
            numbers = "  ".join(f"{report.cell(row[pair_key(a, b)], 4) or 'failed':>15s}" for a, b in PAIRS)
            print(f"{name:22s} {size[0]:>4d}x{size[1]:<4d}  {numbers}  ({row['seconds']:.1f} s)", flush=True)
            for engine, tile in tiles.items():
                if isinstance(tile, str):
                    print(f"  {engines.LABELS[engine]} failed: {tile}", flush=True)

    sheet = out / "materials.png"
    draw_sheet(sheet, results)
    print(f"wrote {sheet} ({len(results)} rows) in {time.perf_counter() - start:.1f} s")
    if args.csv:
        Path(args.csv).resolve().parent.mkdir(parents=True, exist_ok=True)
        report.write_csv(args.csv, [row for _, row in results], FIELDS)
        print(f"wrote {args.csv}")


if __name__ == "__main__":
    session.run(main)
