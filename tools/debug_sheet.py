"""The debug views and Compare with Cycles on the demo scene: docs/debug_views.png and
docs/compare.png.

    .venv/blender-5.2/bin/python -m tools.debug_sheet --out docs

Each debug view is a final render of the demo scene (16 samples, adaptive sampling at a Noise
Threshold of 0.05 so that SAMPLES and NOISE have something to show, three sun cascades so that
CASCADES does) with ``scene.penumbra.debug_view`` set, saved through the Standard view
transform (the views' colours as designed); the caption is the view's legend. The comparison is
``bpy.ops.penumbra.compare_cycles`` on the same scene at 16 samples, saved as it leaves it.
"""

import argparse
import tempfile
from pathlib import Path

import bpy

from devkit import imageio, scenes, session
from tools.contact_sheet import render_png

VIEWS = ("SHADOW_MAPS", "TEXEL_DENSITY", "CASCADES", "LIGHT_COST", "SAMPLES", "NOISE")


def demo(width, height):
    scene = scenes.demo_scene(width, height)
    scene.view_settings.view_transform = "Standard"
    p = scene.penumbra
    p.render_samples = 16
    p.use_adaptive_sampling = True
    p.adaptive_threshold = 0.05
    p.adaptive_min_samples = 4
    p.shadow_cascades = 3
    return scene


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs")
    ap.add_argument("--width", type=int, default=384)
    ap.add_argument("--height", type=int, default=216)
    args = ap.parse_args(argv)
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    session.load_penumbra().register()
    from penumbra.engine.enums import DEBUG_VIEW
    from penumbra.operators.compare import IMAGE_NAME

    tiles = []
    with tempfile.TemporaryDirectory() as tmp:
        for view in VIEWS:
            scene = demo(args.width, args.height)
            scene.penumbra.debug_view = view
            pixels = render_png(scene, Path(tmp) / f"{view}.png")
            item = DEBUG_VIEW[view]
            tiles.append((f"{item.label}\n{item.legend}", pixels))
        scene = demo(args.width, args.height)
        bpy.ops.penumbra.compare_cycles(samples=16)
        image = bpy.data.images[IMAGE_NAME]
        path = Path(tmp) / "compare.png"
        image.filepath_raw = str(path)
        image.file_format = "PNG"
        image.save()
        compare = imageio.read_image(path)

    cols = 3
    rows = (len(tiles) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(cols * 4.2, rows * 2.9), dpi=110)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, (title, pixels) in zip(axes.ravel(), tiles, strict=False):
        ax.imshow(pixels[..., :3])
        ax.set_title(title, fontsize=6.5, wrap=True)
    fig.tight_layout()
    fig.savefig(out / "debug_views.png")
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(12.6, 2.9), dpi=110)
    ax.imshow(compare[..., :3])
    ax.axis("off")
    keys = ("iou", "mean_shadow_error", "mean_image_error", "penumbra_time", "cycles_time")
    numbers = ", ".join(f"{k} {image[k]:.3g}" for k in keys if k in image)
    ax.set_title(f"Penumbra | Cycles | per-pixel error (16 samples each): {numbers}", fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "compare.png")
    plt.close(fig)
    print(f"wrote {out / 'debug_views.png'} and {out / 'compare.png'}")


if __name__ == "__main__":
    session.run(main)
