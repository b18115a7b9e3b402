"""The packaged extension: the zip Blender's own tool builds from the manifest, installed into
a fresh user profile the way a user installs it, then rendering a small scene.

These tests deliberately do not use the ``penumbra`` fixture (which registers the source tree
in-process): the installed copy must work on its own, as ``bl_ext.user_default.penumbra``.
"""

import math
import os
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from build_extension import build_zip

ROOT = Path(__file__).resolve().parents[1]

# Folders and files that exist only for development and must stay out of the zip.
DEV_ONLY_DIRS = ("tests/", "tools/", ".venv/", ".ci/", ".git/")
DEV_ONLY_FILES = ("Makefile", "pytest.ini", ".gitignore")

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


    def mesh_object(scene, name, verts, faces, location=(0.0, 0.0, 0.0), material=None):
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata(verts, [], faces)
        mesh.update()
        if material is not None:
            mesh.materials.append(material)
        ob = bpy.data.objects.new(name, mesh)
        ob.location = location
        scene.collection.objects.link(ob)
        return ob


    def lambert_material(name, albedo):
        # A purely diffuse Principled BSDF: no specular reflection on top of albedo / pi.
        mat = bpy.data.materials.new(name)
        if mat.node_tree is None:  # Blender 4.x; 5.x materials always have a node tree
            mat.use_nodes = True
        bsdf = next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        bsdf.inputs["Base Color"].default_value = (albedo, albedo, albedo, 1.0)
        bsdf.inputs["Roughness"].default_value = 1.0
        bsdf.inputs["Metallic"].default_value = 0.0
        for socket in ("Specular IOR Level", "Specular"):  # Blender 4.0+ name, then the older one
            if socket in bsdf.inputs:
                bsdf.inputs[socket].default_value = 0.0
        return mat


    def build_scene():
        scene = bpy.context.scene
        try:
            scene.render.engine = "PENUMBRA"
        except TypeError as exc:
            fail(f"'PENUMBRA' is not a valid render engine: {exc}")
        scene.render.resolution_x = scene.render.resolution_y = RESOLUTION
        scene.render.resolution_percentage = 100
        scene.render.film_transparent = False
        scene.view_settings.view_transform = "Standard"
        scene.world = None  # no ambient light: the sun is the only light

        # Ground plane of size 10 at z=0 and a unit box floating above the origin.
        h = 5.0
        plane = [(-h, -h, 0.0), (h, -h, 0.0), (h, h, 0.0), (-h, h, 0.0)]
        mesh_object(scene, "Ground", plane, [(0, 1, 2, 3)], material=lambert_material("Ground", ALBEDO))
        box = [(x, y, z) for z in (-0.5, 0.5) for y in (-0.5, 0.5) for x in (-0.5, 0.5)]
        faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
        mesh_object(scene, "Box", box, faces, location=(0.0, 0.0, 1.5))

        # A sun with no rotation shines straight down (-Z).
        sun = bpy.data.lights.new("Sun", "SUN")
        sun.energy = SUN_ENERGY
        sun_ob = bpy.data.objects.new("Sun", sun)
        sun_ob.location = (0.0, 0.0, 5.0)
        scene.collection.objects.link(sun_ob)

        # Orthographic camera looking straight down, framing [-4, 4]^2 of the ground.
        cam = bpy.data.cameras.new("Camera")
        cam.type = "ORTHO"
        cam.ortho_scale = ORTHO_SCALE
        cam.clip_start, cam.clip_end = 0.1, 20.0
        cam_ob = bpy.data.objects.new("Camera", cam)
        cam_ob.location = (0.0, 0.0, 10.0)
        scene.collection.objects.link(cam_ob)
        scene.camera = cam_ob
        return scene


    def render(scene, out_path):
        # Single-layer 32-bit float EXR: scene-linear values, same settings on 4.5 and 5.x.
        settings = scene.render.image_settings
        if hasattr(settings, "media_type"):  # Blender 5.x
            settings.media_type = "IMAGE"
        settings.file_format = "OPEN_EXR"
        settings.color_mode = "RGBA"
        settings.color_depth = "32"
        settings.exr_codec = "ZIP"
        scene.render.filepath = out_path
        scene.render.use_file_extension = False
        bpy.ops.render.render(write_still=True)
        if not Path(out_path).is_file():
            fail(f"the render did not write {out_path}")


    def main():
        zip_path, out_path = sys.argv[1:3]
        # Reset first: loading factory settings disables add-ons, including one just installed.
        bpy.ops.wm.read_factory_settings(use_empty=True)
        install(zip_path)
        render(build_scene(), out_path)
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


def isolated_env(home):
    """The current environment with every Blender user folder inside ``home``."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("BLENDER_USER_")}
    for key in ("XDG_CONFIG_HOME", "XDG_DATA_HOME", "XDG_CACHE_HOME"):
        env.pop(key, None)
    env["HOME"] = str(home)
    env["PYTHONUNBUFFERED"] = "1"  # keep the script's output even if Blender aborts
    env["BLENDER_USER_RESOURCES"] = str(home / "blender")
    return env


def read_rgba(path):
    """RGBA float32 array (h, w, 4) of a single-part EXR, top row first."""
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise RuntimeError(oiio.geterror())
    try:
        spec = inp.spec()
        pixels = np.asarray(inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT), np.float32)
        names = list(spec.channelnames)
    finally:
        inp.close()
    return pixels[:, :, [names.index(c) for c in "RGBA"]]


def test_zip_contents(extension_zip):
    with zipfile.ZipFile(extension_zip) as archive:
        names = set(archive.namelist())

    assert {"__init__.py", "blender_manifest.toml", "engine/renderer.py", "shaders/lit.frag.glsl"} <= names
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
        env=isolated_env(home),
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    log = f"--- stdout ---\n{proc.stdout}\n--- stderr ---\n{proc.stderr}"
    assert proc.returncode == 0, log
    assert "Traceback" not in proc.stderr, log
    assert (home / "blender" / "extensions" / "user_default" / "penumbra" / "__init__.py").is_file()

    rgba = read_rgba(exr)
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
