"""Session fixtures. Tests run inside the bpy module with the repository loaded as the
``penumbra`` package, and draw through the real gpu module (Mesa llvmpipe via EGL); nothing is
mocked. Shared code lives in ``devkit`` (tests never import each other)."""

from devkit import session

# Before Blender starts: presets and preferences go to a throw-away HOME, never a real user's.
HOME = session.isolate()

import bpy  # noqa: E402
import pytest  # noqa: E402


@pytest.fixture(scope="session")
def penumbra():
    module = session.load_penumbra()
    module.register()
    yield module
    module.unregister()


@pytest.fixture(scope="session")
def gpu_call(penumbra):
    """``gpu_call(fn)``: run ``fn(engine, depsgraph)`` in a GPU context, on the current scene
    (see ``devkit.session.GpuRunner``: the production engine core, a real GPU context)."""
    runner = session.GpuRunner()
    runner.register()
    yield runner
    runner.unregister()


@pytest.fixture(scope="session")
def user_home():
    """The throw-away HOME of this test session."""
    return HOME


_exit_status = 0


def pytest_runtest_logreport(report):
    """A failing test's captured stderr without Blender's EGL_BAD_MATCH start-up lines (pytest
    captures file descriptor 2 itself during a test; ``session.quiet_gpu_start`` covers the
    tools)."""
    noise = session.EGL_NOISE.decode()
    report.sections = [
        (name, "".join(line for line in text.splitlines(keepends=True) if not line.startswith(noise)))
        for name, text in report.sections
    ]


def pytest_sessionfinish(exitstatus):
    global _exit_status
    _exit_status = int(exitstatus)


def pytest_unconfigure(config):
    """bpy 4.5 as a module can hang in its own shutdown after GPU work (seen here on
    llvmpipe); once pytest has reported everything, leave with its exit status."""
    if bpy.app.version < (5, 0, 0):
        session.hard_exit(_exit_status)
