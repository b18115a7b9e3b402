"""Test harness: loads the repository as the ``penumbra`` package inside the bpy module and
runs code in a GPU context (``tools/devkit.py``). Tests use real Blender and the real gpu module
(Mesa llvmpipe via EGL); nothing is mocked."""

import os
import sys
import tempfile
from pathlib import Path

# Never touch a real user's Blender config: presets and preferences go to a throw-away HOME.
_HOME = tempfile.mkdtemp(prefix="penumbra-test-home-")
os.environ["HOME"] = _HOME
os.environ["BLENDER_USER_RESOURCES"] = os.path.join(_HOME, "blender")
for _var in ("BLENDER_USER_CONFIG", "BLENDER_USER_SCRIPTS", "BLENDER_USER_EXTENSIONS", "BLENDER_USER_DATAFILES"):
    os.environ.pop(_var, None)

import bpy  # noqa: E402
import pytest  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "tests"))

from devkit import GpuRunner, load_penumbra  # noqa: E402,F401  (load_penumbra: used by tests)


@pytest.fixture(scope="session")
def penumbra():
    module = load_penumbra()
    module.register()
    yield module
    module.unregister()


@pytest.fixture(scope="session")
def gpu_call(penumbra):
    """``gpu_call(fn)``: run ``fn(engine, depsgraph)`` in a GPU context, on the current scene
    (see ``devkit.GpuRunner``: the production engine core, a real GPU context)."""
    runner = GpuRunner()
    runner.register()
    yield runner
    runner.unregister()


_exit_status = 0


def pytest_sessionfinish(session, exitstatus):
    global _exit_status
    _exit_status = int(exitstatus)


def pytest_unconfigure(config):
    """bpy 4.5 as a module can hang in its own shutdown after GPU work (seen here on
    llvmpipe); once pytest has reported everything, leave with its exit status."""
    if bpy.app.version < (5, 0, 0):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_exit_status)
