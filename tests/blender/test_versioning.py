"""Saved settings survive layout changes: a .blend saved by this version (or by one from
before settings were versioned) opened by a later layout that renamed a scene setting and an
effect parameter keeps the user's values under the new names; a file from a newer version
keeps its values and says so. Each Blender session runs in a child process."""

import json
import subprocess
import sys
import textwrap

from devkit.session import ROOT

SAVE = """
import bpy
from devkit import session
pen = session.load_penumbra()
pen.register()
from penumbra.engine import settings
s = bpy.context.scene
s.penumbra.shadow_bias = 0.77
s.penumbra.shadow_filter = "PCSS"
layer = s.penumbra.layers.add()
layer.effect = "BLUR"
layer.blur.radius = 9
light = bpy.data.lights.new("Key", "SPOT")
light.penumbra.bias_scale = 3.0
s.collection.objects.link(bpy.data.objects.new("Key", light))
bpy.ops.wm.save_as_mainfile(filepath=FOLDER + "/current.blend")
assert s.penumbra.schema_version == settings.SCHEMA_VERSION == 1, s.penumbra.schema_version
# A file from a newer Penumbra.
s.penumbra.schema_version = 7
bpy.app.handlers.save_pre.remove(pen.properties._on_save_pre)
bpy.ops.wm.save_as_mainfile(filepath=FOLDER + "/newer.blend")
# A file from before settings were versioned: no version stored at all.
s.penumbra.property_unset("schema_version")
light.penumbra.property_unset("schema_version")
bpy.ops.wm.save_as_mainfile(filepath=FOLDER + "/unversioned.blend")
session.hard_exit(0)
"""

READ = """
import dataclasses, importlib, json
import bpy
from devkit import session
pen = session.load_penumbra()
from penumbra.engine import settings
from penumbra.engine.post import blur
if LATER:
    # A later layout: shadow_bias renamed, BLUR's radius renamed, one setting added.
    def renamed(params, old, new):
        return tuple(dataclasses.replace(p, name=new) if p.name == old else p for p in params)
    settings.SCENE_PARAMS = renamed(settings.SCENE_PARAMS, "shadow_bias", "shadow_constant_bias") + (
        settings.Param("added_setting", "FLOAT", 0.25, section=settings.SHADOWS),
    )
    blur.Blur.params = renamed(blur.Blur.params, "radius", "size")
    settings.SCHEMA_VERSION = 2
    settings.SCENE_UPGRADES = {
        1: (),
        2: (settings.Rename("shadow_bias", "shadow_constant_bias"),
            settings.Rename("radius", "size", path=("layers", "*", "blur"))),
    }
    importlib.reload(pen.properties)
pen.register()
out = {}
for name in ("current", "unversioned", "newer"):
    bpy.ops.wm.open_mainfile(filepath=FOLDER + "/" + name + ".blend")
    p = bpy.context.scene.penumbra
    out[name] = {
        "bias": getattr(p, "shadow_constant_bias" if LATER else "shadow_bias"),
        "added": getattr(p, "added_setting", None),
        "filter": p.shadow_filter,
        "blur": getattr(p.layers[0].blur, "size" if LATER else "radius"),
        "bias_scale": bpy.data.lights["Key"].penumbra.bias_scale,
        "version": p.schema_version,
        "light_version": bpy.data.lights["Key"].penumbra.schema_version,
    }
print("RESULT " + json.dumps(out))
session.hard_exit(0)
"""


def run(script):
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    return proc


def read(folder, later):
    proc = run(f"FOLDER = {str(folder)!r}\nLATER = {later!r}\n" + textwrap.dedent(READ))
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT "))
    return json.loads(line[len("RESULT ") :]), proc.stderr


def test_settings_survive_a_later_layout_and_older_files(tmp_path):
    run(f"FOLDER = {str(tmp_path)!r}\n" + textwrap.dedent(SAVE))
    expected = {"bias": 0.77, "filter": "PCSS", "blur": 9, "bias_scale": 3.0}

    now, stderr = read(tmp_path, later=False)
    for name in ("current", "unversioned"):
        got = now[name]
        assert {k: got[k] for k in expected} == {**expected, "bias": got["bias"]}
        assert abs(got["bias"] - 0.77) < 1e-6
        assert got["version"] == 1 and got["light_version"] == 1
    # A file from a newer version: values kept, its version left alone, a message said.
    assert abs(now["newer"]["bias"] - 0.77) < 1e-6 and now["newer"]["version"] == 7
    assert "saved by a newer Penumbra" in stderr

    later, _ = read(tmp_path, later=True)
    for name in ("current", "unversioned"):
        got = later[name]
        assert abs(got["bias"] - 0.77) < 1e-6, (name, got)  # renamed, value kept
        assert got["blur"] == 9, (name, got)  # renamed effect parameter, value kept
        assert got["added"] == 0.25 and got["filter"] == "PCSS" and got["bias_scale"] == 3.0
        assert got["version"] == 2


ADAPTIVE = """
import json
import bpy
from devkit import session
session.load_penumbra().register()
NEW = ("use_adaptive_sampling", "adaptive_threshold", "adaptive_min_samples", "time_limit",
       "use_preview_adaptive_sampling", "preview_adaptive_threshold", "preview_adaptive_min_samples",
       "preview_time_limit")
p = bpy.context.scene.penumbra
p.use_adaptive_sampling, p.adaptive_threshold, p.time_limit = False, 0.5, 9.0
p.render_samples = 48
for name in NEW:  # what a file saved before these settings existed holds: nothing
    p.property_unset(name)
path = FOLDER + "/before_adaptive.blend"
bpy.ops.wm.save_as_mainfile(filepath=path)
bpy.ops.wm.open_mainfile(filepath=path)
p = bpy.context.scene.penumbra
print("RESULT " + json.dumps({"values": {n: getattr(p, n) for n in NEW}, "samples": p.render_samples}))
session.hard_exit(0)
"""


def test_a_file_from_before_adaptive_sampling_loads_with_its_defaults(tmp_path):
    proc = run(f"FOLDER = {str(tmp_path)!r}\n" + textwrap.dedent(ADAPTIVE))
    got = json.loads(next(ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT "))[len("RESULT ") :])
    assert got["samples"] == 48
    values = got["values"]
    assert values["use_adaptive_sampling"] is True and values["use_preview_adaptive_sampling"] is True
    assert abs(values["adaptive_threshold"] - 0.01) < 1e-7 and abs(values["preview_adaptive_threshold"] - 0.1) < 1e-7
    assert values["adaptive_min_samples"] == values["preview_adaptive_min_samples"] == 0
    assert values["time_limit"] == values["preview_time_limit"] == 0.0
