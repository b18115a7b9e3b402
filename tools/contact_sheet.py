"""Contact sheet of every post layer on the demo scene: docs/contact_sheet.png.

    .venv/blender-5.2/bin/python -m tools.contact_sheet --out docs

Each tile is the demo scene rendered by Penumbra with one layer (default parameters, mix 1),
saved through Blender's colour management (AgX), the first tile without any layer; then one
tile per shipped preset look. Tiles are laid out with matplotlib.
"""

import argparse
import tempfile
from pathlib import Path

import bpy

from devkit import imageio, scenes, session

# Parameters that make an effect readable at thumbnail size (others keep their defaults).
SHOWCASE = {
    "BLUR": {"radius": 6},
    "PIXELATE": {"size": 12},
}


def render_png(scene, path):
    imageio.set_format(scene.render.image_settings, "PNG", color_depth="8")
    scene.render.filepath = str(path)
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True)
    return imageio.read_image(path)


def demo(width, height):
    scene = scenes.demo_scene(width, height)
    scene.view_settings.view_transform = "AgX"
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
    from penumbra.engine.post import EFFECTS
    from penumbra.operators.presets import SHIPPED_DIR

    tiles = []
    with tempfile.TemporaryDirectory() as tmp:
        for eid in [None, *EFFECTS]:
            scene = demo(args.width, args.height)
            s = scene.penumbra
            s.layers.clear()
            if eid is not None:
                layer = s.layers.add()
                layer.effect = eid
                for name, value in SHOWCASE.get(eid, {}).items():
                    setattr(layer.params(), name, value)
            pixels = render_png(scene, Path(tmp) / f"{eid or 'none'}.png")
            tiles.append((EFFECTS[eid].label if eid else "No layer", pixels))
        for preset in sorted(SHIPPED_DIR.glob("*.py")):
            scene = demo(args.width, args.height)
            bpy.ops.script.execute_preset(filepath=str(preset), menu_idname="PENUMBRA_MT_post_presets")
            pixels = render_png(scene, Path(tmp) / f"preset_{preset.stem}.png")
            tiles.append((f"Preset: {bpy.path.display_name(preset.stem)}", pixels))

    cols = 4
    rows = (len(tiles) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(cols * 3.2, rows * 2.0), dpi=120)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, (label, px) in zip(axes.ravel(), tiles):
        ax.imshow(px[..., :3].clip(0, 1))
        ax.set_title(label, fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "contact_sheet.png")
    print(f"wrote {out / 'contact_sheet.png'} ({len(tiles)} tiles)")


if __name__ == "__main__":
    session.run(main)
