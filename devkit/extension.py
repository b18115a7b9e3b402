"""The Penumbra extension zip, built with Blender's own extension tool.

The tool is ``blender_ext.py`` from the ``bl_pkg`` core add-on, which ships inside the bpy
wheel of the Python running this script. It is run twice, in a child process of the same
interpreter: ``validate`` checks the manifest of the source tree, then ``build`` writes
``{id}-{version}.zip``. Which files go into the zip is decided by the ``[build]`` table of
``blender_manifest.toml`` (dev-only folders such as devkit/, tests/ and tools/ are excluded there).
"""

import subprocess
import sys
import tomllib
from pathlib import Path

from devkit.session import ROOT

# Location of the extension tool inside a Blender version folder (``<wheel>/bpy/<major.minor>``).
BLENDER_EXT = Path("scripts", "addons_core", "bl_pkg", "cli", "blender_ext.py")


class BuildError(RuntimeError):
    """The extension tool is missing, or it rejected or failed to build the package."""


def find_blender_ext():
    """Path of ``blender_ext.py`` in the bpy wheel of this interpreter.

    ``import bpy`` replaces the compiled extension module with Blender's own ``bpy`` package,
    so ``bpy.__file__`` may be either ``<wheel>/bpy/__init__.so`` or
    ``<wheel>/bpy/<version>/scripts/modules/bpy/__init__.py``; the folders above it are
    searched for the ``<version>`` folder, after the one Blender itself reports.
    """
    try:
        import bpy
    except ImportError as exc:
        raise BuildError(
            f"cannot import bpy with {sys.executable} ({exc}); run this script with a venv "
            "made by tools/setup.sh, e.g. .venv/blender-5.2/bin/python"
        ) from exc

    version = "{}.{}".format(*bpy.app.version[:2])
    candidates = [Path(bpy.utils.resource_path("LOCAL")) / BLENDER_EXT]
    candidates += [parent / version / BLENDER_EXT for parent in Path(bpy.__file__).resolve().parents]
    for path in candidates:
        if path.is_file():
            return path
    tried = "\n  ".join(str(p) for p in dict.fromkeys(candidates))
    raise BuildError(f"Blender's extension tool was not found in the bpy {version} wheel; tried:\n  {tried}")


def package_filename(source_dir):
    """``{id}-{version}.zip``: the name ``blender_ext.py build`` gives the package."""
    manifest_path = Path(source_dir) / "blender_manifest.toml"
    try:
        with open(manifest_path, "rb") as fh:
            manifest = tomllib.load(fh)
        return f"{manifest['id']}-{manifest['version']}.zip"
    except (OSError, tomllib.TOMLDecodeError, KeyError) as exc:
        raise BuildError(f"cannot read the package id and version from {manifest_path}: {exc}") from exc


def run_tool(tool, *args):
    """Run ``blender_ext.py`` with this interpreter; echo its output, or raise with it.

    The tool is a self-contained script (standard library only; it does not import bpy). It
    reports problems such as manifest errors on stdout, so a failure carries that output.
    """
    cmd = [sys.executable, str(tool), *map(str, args)]
    result = subprocess.run(cmd, capture_output=True, text=True)
    output = (result.stdout + result.stderr).strip()
    if result.returncode != 0:
        raise BuildError(f"'blender_ext.py {args[0]}' failed (exit code {result.returncode}):\n{output}")
    if output:
        print(output)


def build_zip(out_dir, source_dir=ROOT):
    """Validate ``source_dir`` and build its extension zip into ``out_dir``; return the zip path."""
    source_dir = Path(source_dir).resolve()
    out_dir = Path(out_dir).resolve()
    tool = find_blender_ext()
    out_dir.mkdir(parents=True, exist_ok=True)  # the tool does not create it
    run_tool(tool, "validate", source_dir)
    run_tool(tool, "build", "--source-dir", source_dir, "--output-dir", out_dir)
    zip_path = out_dir / package_filename(source_dir)
    if not zip_path.is_file():
        raise BuildError(f"the build reported success but {zip_path} does not exist")
    return zip_path
