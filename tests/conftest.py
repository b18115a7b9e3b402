"""Session fixtures. Tests run inside the bpy module with the repository loaded as the
``penumbra`` package, and draw through the real gpu module (Mesa llvmpipe via EGL); nothing is
mocked. Shared code lives in ``devkit`` (tests never import each other)."""

import os

from devkit import session

# Before Blender starts: presets and preferences go to a throw-away HOME, never a real user's.
HOME = session.isolate()
# On Mesa's llvmpipe, the GPU of this harness, a test's small frames cost less to draw than
# their programs cost to compile, and a fresh machine (no Mesa shader cache) compiles every
# program anew: compiled without LLVM's optimisation passes, a cold run takes about half the
# time (README). A GPU's driver ignores it; set GALLIVM_PERF yourself to choose otherwise.
os.environ.setdefault("GALLIVM_PERF", "nopt")

import bpy  # noqa: E402
import pytest  # noqa: E402

# Each failure's message written to $PENUMBRA_FAILURES the moment it fails (the GPU machine's
# runner sets it: a run its time limit kills keeps what failed, and why).
pytest_plugins = ["devkit.failure_log"]


@pytest.fixture(scope="session")
def penumbra():
    module = session.load_penumbra()
    module.register()
    yield module
    module.unregister()


def pytest_configure(config):
    config.addinivalue_line(
        "markers",
        "negative_inputs: the test's scenes have negative inputs on purpose (colours, strengths), "
        "so the light check (Combined >= 0) does not apply to its frames",
    )


@pytest.fixture(autouse=True)
def light_is_never_negative(request):
    """Every frame Penumbra renders in a test (in this process or a child of ``run_result``)
    has a finite Combined >= 0 within float rounding (``session.install_light_check``); a test
    whose scenes have negative inputs on purpose says so with ``negative_inputs``."""
    session.install_light_check()
    session.take_light_failures()
    yield
    failures = session.take_light_failures()
    if failures and request.node.get_closest_marker("negative_inputs") is None:
        pytest.fail("light check: " + "; ".join(failures[:5]), pytrace=False)


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
