"""The README's demo command works, and a batch render of the saved .blend (as
``blender -b demo.blend -E PENUMBRA -a`` does) gives the same pixels as the F12 render."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from conftest import ROOT
from helpers import read_exr


def run(args, **kw):
    proc = subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=300, **kw)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    return proc


def test_demo_then_batch_animation_matches(tmp_path):
    run([str(ROOT / "tools" / "demo.py"), "--out", str(tmp_path), "--width", "320", "--height", "180"])
    png = np.asarray(oiio.ImageBuf(str(tmp_path / "demo.png")).get_pixels(oiio.FLOAT))
    exr = read_exr(tmp_path / "demo.exr")
    assert png.shape == (180, 320, 4) and exr["Combined"].shape == (180, 320, 4)
    assert np.all(np.isfinite(exr["Combined"])) and png[..., :3].std() > 0.05
    depth = exr["Depth"][..., 0]
    assert 5.0 < depth[90, 160] < 30.0  # the camera sees the ground ~10-15 m away

    # Batch: open the saved file and render frames 1-2 as an animation.
    script = textwrap.dedent(
        f"""
        import sys
        sys.path[:0] = [{str(ROOT / 'tests')!r}, {str(ROOT / 'tools')!r}]
        from devkit import load_penumbra
        import bpy
        load_penumbra().register()
        bpy.ops.wm.open_mainfile(filepath={str(tmp_path / 'demo.blend')!r})
        scene = bpy.context.scene
        scene.render.engine = "PENUMBRA"
        scene.frame_start, scene.frame_end = 1, 2
        from helpers import set_multilayer_exr
        set_multilayer_exr(scene.render.image_settings)
        scene.render.image_settings.color_depth = "32"
        scene.render.filepath = {str(tmp_path / 'frame_####')!r}
        bpy.ops.render.render(animation=True)
        import os
        sys.stdout.flush()
        os._exit(0)  # bpy 4.5 can hang in its own shutdown after GPU work
        """
    )
    run(["-c", script], env={**os.environ})
    frames = sorted(Path(tmp_path).glob("frame_*.exr"))
    assert [f.name for f in frames] == ["frame_0001.exr", "frame_0002.exr"]
    batch = read_exr(frames[0])
    np.testing.assert_array_equal(batch["Combined"], exr["Combined"])
