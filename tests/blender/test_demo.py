"""The README's demo command works, and a batch render of the saved .blend (as
``blender -b demo.blend -E PENUMBRA -a`` does) gives the same pixels as the F12 render.
Each runs in a child process, so a crash fails the test, not the session."""

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np

from devkit.imageio import read_exr, read_image
from devkit.session import ROOT


def run(args):
    """Run this interpreter with ``args`` from the repository root (``devkit`` and ``tools``
    importable there); fail on a non-zero exit or a traceback."""
    proc = subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    return proc


def test_demo_then_batch_animation_matches(tmp_path):
    run(["-m", "tools.demo", "--out", str(tmp_path), "--width", "320", "--height", "180"])
    png = read_image(tmp_path / "demo.png")
    exr = read_exr(tmp_path / "demo.exr")
    assert png.shape == (180, 320, 4) and exr["Combined"].shape == (180, 320, 4)
    assert np.all(np.isfinite(exr["Combined"])) and png[..., :3].std() > 0.05
    depth = exr["Depth"][..., 0]
    assert 5.0 < depth[90, 160] < 30.0  # the camera sees the ground ~10-15 m away

    # Batch: open the saved file and render frames 1-2 as an animation.
    script = textwrap.dedent(
        f"""
        import bpy
        from devkit import imageio, session
        session.load_penumbra().register()
        bpy.ops.wm.open_mainfile(filepath={str(tmp_path / "demo.blend")!r})
        scene = bpy.context.scene
        scene.render.engine = "PENUMBRA"
        scene.frame_start, scene.frame_end = 1, 2
        imageio.set_format(scene.render.image_settings, "OPEN_EXR_MULTILAYER", color_depth="32")
        scene.render.filepath = {str(tmp_path / "frame_####")!r}
        bpy.ops.render.render(animation=True)
        session.hard_exit(0)
        """
    )
    run(["-c", script])
    frames = sorted(Path(tmp_path).glob("frame_*.exr"))
    assert [f.name for f in frames] == ["frame_0001.exr", "frame_0002.exr"]
    batch = read_exr(frames[0])
    np.testing.assert_array_equal(batch["Combined"], exr["Combined"])


ANIMATED = """
import numpy as np
from devkit import scenes, session
from devkit.render import render
session.load_penumbra().register()
scene = scenes.demo_scene(96, 54)
for effect in ("NOISE", "SCANLINES", "LENS_FLARE"):
    if effect in {{e.identifier for e in scene.penumbra.layers.add().bl_rna.properties["effect"].enum_items}}:
        scene.penumbra.layers[-1].effect = effect
    else:
        scene.penumbra.layers.remove(len(scene.penumbra.layers) - 1)
out = {{}}
for frame in (5, 6):
    scene.frame_set(frame)
    out[frame] = render(scene)["Combined"]
np.savez({path!r}, **{{str(k): v for k, v in out.items()}})
session.hard_exit(0)
"""


def test_animated_layers_are_a_pure_function_of_the_frame(tmp_path):
    """Two separate processes render frames 5 and 6 of a stack with animated layers (noise,
    scrolling scanlines): the same frame is bit-identical across runs, different frames differ."""
    runs = []
    for i in range(2):
        path = tmp_path / f"run{i}.npz"
        run(["-c", ANIMATED.format(path=str(path))])
        runs.append(np.load(path))
    np.testing.assert_array_equal(runs[0]["5"], runs[1]["5"])
    np.testing.assert_array_equal(runs[0]["6"], runs[1]["6"])
    assert np.abs(runs[0]["5"] - runs[0]["6"]).mean() > 1e-3
