"""The packaged extension: the zip Blender's own tool builds from the manifest, installed into
a fresh user profile the way a user installs it, then rendering a small scene.

These tests deliberately do not use the ``penumbra`` fixture (which registers the source tree
in-process): the installed copy must work on its own, as ``bl_ext.user_default.penumbra``, in a
child process whose only other import from this repository is ``devkit`` (scene and output set-up).
"""

import math
import subprocess
import sys
import textwrap
import zipfile

import numpy as np
import pytest

from devkit.extension import build_zip
from devkit.imageio import read_exr
from devkit.session import ROOT, child_env, isolated_env

# Folders and files that are not the add-on (development, the farm job) and must stay out of the zip.
DEV_ONLY_DIRS = ("devkit/", "tests/", "tools/", "farm/", ".venv/", ".ci/", ".git/")
DEV_ONLY_FILES = ("Makefile", "pytest.ini", "ruff.toml", ".gitignore")

# Scene constants shared by the render script and the assertions below.
ALBEDO = 0.8
SUN_ENERGY = 3.0
RESOLUTION = 64
ORTHO_SCALE = 8.0

# Runs in a separate Python process (the same interpreter, so the same bpy line) whose
# HOME and Blender user folders point at a throwaway directory; see render_script().
# argv: <extension zip> <output EXR>. Exits non-zero with a message on any failure.
RENDER_SCRIPT = textwrap.dedent(
    """
    import importlib
    import os
    import sys
    from pathlib import Path

    import bpy
    from devkit import imageio, scenes

    # ALBEDO, SUN_ENERGY, RESOLUTION and ORTHO_SCALE are defined by a header the test prepends.
    MODULE = "bl_ext.user_default.penumbra"


    def fail(message):
        print(f"extension test: {message}", file=sys.stderr)
        sys.exit(1)


    def is_inside(path, folder):
        return Path(path).resolve().is_relative_to(Path(folder).resolve())


    def install(zip_path):
        prefs = bpy.context.preferences
        repo = next((r for r in prefs.extensions.repos if r.module == "user_default"), None)
        if repo is None or not repo.enabled:
            fail("no enabled 'user_default' extension repository")
        if not is_inside(repo.directory, os.environ["HOME"]):
            fail(f"'user_default' repository {repo.directory} is outside the temporary HOME")

        # A local file install: works without online access and in background mode.
        result = bpy.ops.extensions.package_install_files(
            filepath=zip_path, repo="user_default", enable_on_install=True
        )
        if result != {"FINISHED"}:
            fail(f"package_install_files returned {result}")
        if MODULE not in prefs.addons:
            fail(f"{MODULE} is not enabled after the install; enabled: {sorted(prefs.addons.keys())}")
        module = importlib.import_module(MODULE)
        if not is_inside(module.__file__, repo.directory):
            fail(f"{MODULE} was imported from {module.__file__}, not from the installed copy")
        engines = [
            c for c in bpy.types.RenderEngine.__subclasses__() if getattr(c, "bl_idname", None) == "PENUMBRA"
        ]
        if not any(c.__module__.startswith(MODULE + ".") for c in engines):
            fail(f"no PENUMBRA render engine registered by {MODULE}: {engines}")


    def build_scene():
        # A white Lambertian ground of size 10 at z=0 and a unit box floating above the origin,
        # a sun shining straight down (-Z), a black world (the sun is the only light) and an
        # orthographic camera looking straight down, framing [-4, 4]^2 of the ground.
        scene = scenes.empty_scene(RESOLUTION, RESOLUTION, engine="BLENDER_WORKBENCH")
        scenes.box_over_plane(scene, plane_size=10.0, mat=scenes.white("Ground", ALBEDO))
        scenes.light(scene, "Sun", "SUN", SUN_ENERGY, location=(0.0, 0.0, 5.0))
        scenes.top_camera(scene, height=10.0, ortho_scale=ORTHO_SCALE)


    def render(scene, out_path):
        # Single-layer 32-bit float EXR: scene-linear values, same settings on 4.5 and 5.x.
        imageio.set_format(scene.render.image_settings, "OPEN_EXR", color_depth="32", exr_codec="ZIP")
        scene.render.image_settings.color_mode = "RGBA"
        scene.render.filepath = out_path
        scene.render.use_file_extension = False
        bpy.ops.render.render(write_still=True)
        if not Path(out_path).is_file():
            fail(f"the render did not write {out_path}")


    def main():
        zip_path, out_path = sys.argv[1:3]
        # The scene first: its factory reset disables add-ons, including one just installed.
        build_scene()
        install(zip_path)
        scene = bpy.context.scene
        try:
            scene.render.engine = "PENUMBRA"
        except TypeError as exc:
            fail(f"'PENUMBRA' is not a valid render engine: {exc}")
        render(scene, out_path)
        print("extension test: ok")


    main()
    """
)


def render_script():
    """RENDER_SCRIPT preceded by the scene constants it shares with the assertions."""
    constants = {"ALBEDO": ALBEDO, "SUN_ENERGY": SUN_ENERGY, "RESOLUTION": RESOLUTION, "ORTHO_SCALE": ORTHO_SCALE}
    return "".join(f"{name} = {value!r}\n" for name, value in constants.items()) + RENDER_SCRIPT


@pytest.fixture(scope="module")
def extension_zip(tmp_path_factory):
    return build_zip(tmp_path_factory.mktemp("dist"))


def test_zip_contents(extension_zip):
    with zipfile.ZipFile(extension_zip) as archive:
        names = set(archive.namelist())

    assert {
        "__init__.py",
        "blender_manifest.toml",
        "LICENSE",
        "engine/frame/renderer.py",
        "shaders/lit.frag.glsl",
    } <= names
    shaders = {p.relative_to(ROOT).as_posix() for p in (ROOT / "shaders").rglob("*.glsl")}
    assert shaders and shaders <= names, f"shaders missing from the zip: {sorted(shaders - names)}"

    leaked = sorted(n for n in names if n.startswith(DEV_ONLY_DIRS) or n in DEV_ONLY_FILES or "__pycache__/" in n)
    assert not leaked, f"dev-only files in the zip: {leaked}"


def test_installed_extension_renders(extension_zip, tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    script = tmp_path / "install_and_render.py"
    script.write_text(render_script())
    exr = tmp_path / "frame.exr"

    proc = subprocess.run(
        # faulthandler: a Python stack in the log should Blender crash rather than raise.
        [sys.executable, "-X", "faulthandler", str(script), str(extension_zip), str(exr)],
        env={**child_env(isolated_env(home)), "PYTHONUNBUFFERED": "1"},  # keep the output should Blender abort
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    log = f"--- stdout ---\n{proc.stdout}\n--- stderr ---\n{proc.stderr}"
    assert proc.returncode == 0, log
    assert "Traceback" not in proc.stderr, log
    assert (home / "blender" / "extensions" / "user_default" / "penumbra" / "__init__.py").is_file()

    rgba = read_exr(exr)["Combined"]
    assert rgba.shape == (RESOLUTION, RESOLUTION, 4)
    assert np.all(np.isfinite(rgba))

    # Lambert under a sun shining straight down on the ground: E * albedo / pi.
    expected = ALBEDO / math.pi * SUN_ENERGY
    # Pixels 1/8 of the frame in from each corner: on the ground, well clear of the box and of
    # its shadow (both within 0.5 of the origin; these pixels are about 2.9 away on each axis).
    margin = RESOLUTION // 8
    for y in (margin, RESOLUTION - 1 - margin):
        for x in (margin, RESOLUTION - 1 - margin):
            rgb = rgba[y, x, :3]
            assert np.allclose(rgb, expected, rtol=0.05), f"pixel ({x}, {y}) = {rgb}, expected {expected:.4f}"
