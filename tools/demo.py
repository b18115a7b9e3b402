"""Render the demo scene with Penumbra: out/demo.png (display-referred, through Blender's colour
management), out/demo.exr (scene-linear Combined + Depth), and out/demo.blend to open in Blender.

    .venv/blender-5.2/bin/python -m tools.demo --out out
"""

import argparse
import time
from pathlib import Path

import bpy

from devkit import imageio, scenes, session


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out")
    ap.add_argument("--width", type=int, default=960)
    ap.add_argument("--height", type=int, default=540)
    args = ap.parse_args(argv)
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)

    session.load_penumbra().register()
    scene = scenes.demo_scene(args.width, args.height)
    settings = scene.penumbra.bl_rna.properties
    scene.penumbra.render_samples = settings["render_samples"].default  # what a new scene renders
    scene.penumbra.viewport_samples = settings["viewport_samples"].default
    scene.view_settings.view_transform = "AgX"
    scene.view_layers[0].use_pass_z = True
    t = time.perf_counter()
    bpy.ops.render.render()
    elapsed = time.perf_counter() - t
    imageio.save_render(scene, out / "demo.png", "PNG", "8")
    imageio.save_render(scene, out / "demo.exr", "OPEN_EXR_MULTILAYER", "32")
    bpy.ops.wm.save_as_mainfile(filepath=str(out / "demo.blend"))
    print(f"Penumbra demo: {args.width}x{args.height} in {elapsed:.2f} s (first frame, shaders compiled)")
    print(f"wrote {out / 'demo.png'}, {out / 'demo.exr'}, {out / 'demo.blend'}")


if __name__ == "__main__":
    session.run(main)
