"""Developer scripts on the ``devkit`` library, run as modules from the repository root, e.g.
``.venv/blender-5.2/bin/python -m tools.demo --out out`` (tools/setup.sh makes the venvs).

Importing the package filters Blender's harmless EGL start-up lines out of stderr
(``devkit.session.quiet_gpu_start``) before any tool starts Blender."""

from devkit import session

session.quiet_gpu_start()
