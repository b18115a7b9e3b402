"""Render the demo scene with Penumbra: out/demo.png (display-referred, through Blender's colour
management), out/demo.exr (scene-linear Combined + Depth), and out/demo.blend to open in Blender.

    .venv/blender-5.2/bin/python tools/demo.py --out out
"""

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tools"), str(ROOT / "tests")]

import bpy  # noqa: E402

from devkit import load_penumbra  # noqa: E402
import scenes  # noqa: E402


def save(scene, path, fmt, depth):
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = "MULTI_LAYER_IMAGE" if fmt == "OPEN_EXR_MULTILAYER" else "IMAGE"
    settings.file_format = fmt
    settings.color_depth = depth
    bpy.data.images["Render Result"].save_render(str(path), scene=scene)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out")
    ap.add_argument("--width", type=int, default=960)
    ap.add_argument("--height", type=int, default=540)
    args = ap.parse_args()
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)

    load_penumbra().register()
    scene = scenes.demo_scene(args.width, args.height)
    scene.view_settings.view_transform = "AgX"
    scene.view_layers[0].use_pass_z = True
    t = time.perf_counter()
    bpy.ops.render.render()
    elapsed = time.perf_counter() - t
    save(scene, out / "demo.png", "PNG", "8")
    save(scene, out / "demo.exr", "OPEN_EXR_MULTILAYER", "32")
    bpy.ops.wm.save_as_mainfile(filepath=str(out / "demo.blend"))
    print(f"Penumbra demo: {args.width}x{args.height} in {elapsed:.2f} s (first frame, shaders compiled)")
    print(f"wrote {out / 'demo.png'}, {out / 'demo.exr'}, {out / 'demo.blend'}")


if __name__ == "__main__":
    main()
    # bpy 4.5 as a module can hang in its own shutdown after GPU work; everything is written.
    sys.stdout.flush()
    sys.stderr.flush()
    import os

    os._exit(0)
