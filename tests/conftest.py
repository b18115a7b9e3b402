"""Test harness: loads the repository as the ``penumbra`` package inside the bpy module and
offers helpers to render and read back images. Tests use real Blender and the real gpu module
(Mesa llvmpipe via EGL); nothing is mocked."""

import importlib.util
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
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "tests"))


def load_penumbra():
    """Import the repository root as the package ``penumbra`` (its folder name may differ)."""
    if "penumbra" in sys.modules:
        return sys.modules["penumbra"]
    spec = importlib.util.spec_from_file_location(
        "penumbra", ROOT / "__init__.py", submodule_search_locations=[str(ROOT)]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules["penumbra"] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def penumbra():
    module = load_penumbra()
    module.register()
    yield module
    module.unregister()


@pytest.fixture
def tmp(tmp_path):
    return tmp_path


class _GpuHarness:
    """Runs a callable inside a RenderEngine.render() call, where the gpu module can draw in
    background mode. ``gpu_call(fn)`` returns what ``fn(engine)`` returned."""

    engine_cls = None
    job = None
    result = None
    error = None


def _make_harness(core):
    class PENUMBRA_TEST_HARNESS(core, bpy.types.RenderEngine):
        bl_idname = "PENUMBRA_TEST_HARNESS"
        bl_label = "Penumbra test harness"
        bl_use_gpu_context = True

        def render(self, depsgraph):
            try:
                _GpuHarness.result = _GpuHarness.job(self, depsgraph)
            except Exception as exc:  # handed back to the test
                _GpuHarness.error = exc
            finally:
                self.free_gpu()

        def update_render_passes(self, scene=None, renderlayer=None):
            self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")

    return PENUMBRA_TEST_HARNESS


@pytest.fixture(scope="session")
def gpu_call(penumbra):
    """``gpu_call(fn)``: run ``fn(engine, depsgraph)`` in a GPU context, on the current scene.

    The harness engine is built on Penumbra's engine core, so ``engine.render_frame`` and
    ``engine.draw_display`` are the production code paths."""
    from penumbra.engine.render_engine import PenumbraEngineCore

    cls = _make_harness(PenumbraEngineCore)
    bpy.utils.register_class(cls)

    def call(fn):
        scene = bpy.context.scene
        old = scene.render.engine
        scene.render.engine = cls.bl_idname
        _GpuHarness.job, _GpuHarness.result, _GpuHarness.error = fn, None, None
        try:
            bpy.ops.render.render(write_still=False)
        finally:
            scene.render.engine = old
        if _GpuHarness.error is not None:
            raise _GpuHarness.error
        return _GpuHarness.result

    yield call
    bpy.utils.unregister_class(cls)


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
