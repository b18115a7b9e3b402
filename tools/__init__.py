"""Developer scripts on the ``devkit`` library, run as modules from the repository root, e.g.
``.venv/blender-5.2/bin/python -m tools.demo --out out`` (tools/setup.sh makes the venvs)."""
