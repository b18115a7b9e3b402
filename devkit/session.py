"""The process a tool or a test runs in: throw-away user folders, the repository loaded as the
``penumbra`` package, code run inside a GPU context, and a safe way out.

Nothing here imports ``bpy`` at import time: ``isolate()`` must run before Blender starts.
"""

import atexit
import contextlib
import importlib.util
import os
import sys
import tempfile
import threading
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# Environment variables that could point Blender at a real user's configuration.
_XDG = ("XDG_CONFIG_HOME", "XDG_DATA_HOME", "XDG_CACHE_HOME")


def isolated_env(home, base=None):
    """A copy of ``base`` (default: this process's environment) whose HOME and Blender user
    folders all lie inside ``home``: for child processes."""
    base = os.environ if base is None else base
    env = {k: v for k, v in base.items() if not k.startswith("BLENDER_USER_") and k not in _XDG}
    env["HOME"] = str(home)
    env["BLENDER_USER_RESOURCES"] = str(Path(home) / "blender")
    return env


def isolate(home=None):
    """Point this process's HOME and Blender user folders at ``home`` (default: a new temporary
    folder) so presets and preferences never touch a real user's config. Call it before ``bpy``
    is imported; returns the HOME path."""
    if "bpy" in sys.modules:
        raise RuntimeError("isolate() must run before bpy is imported")
    home = Path(home) if home is not None else Path(tempfile.mkdtemp(prefix="penumbra-home-"))
    env = isolated_env(home)
    for key in [k for k in os.environ if k not in env]:
        del os.environ[key]
    os.environ.update(env)
    return home


def child_env(base=None):
    """A copy of ``base`` (default: this process's environment) with the repository root first
    on PYTHONPATH, so a child Python started in any folder can ``import devkit``."""
    env = dict(os.environ if base is None else base)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    return env


def run_result(script, timeout=300):
    """Run ``script`` in a child Python (this interpreter, so the same bpy line; the repository
    importable) and return (the dict it printed as its ``RESULT <json>`` line, everything it
    printed). The child must exit 0 without a traceback: a crash there fails the caller, not its
    process."""
    import json
    import subprocess

    env = dict(os.environ)
    env[LIGHT_CHECK_ENV] = "child"  # the child checks its frames too (``load_penumbra``)
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=timeout, cwd=ROOT, env=env
    )
    log = proc.stderr[-3000:]
    assert proc.returncode == 0, log
    assert "Traceback" not in proc.stderr, log
    assert LIGHT_CHECK_MARK not in proc.stderr, log
    line = next((ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")), None)
    assert line is not None, proc.stdout[-2000:] + log
    return json.loads(line[len("RESULT ") :]), proc.stdout + proc.stderr


# Light is never negative and never NaN: the suite checks every frame Penumbra renders (its
# Combined, the image after the post stack) once, here, rather than in each test.
LIGHT_CHECK_ENV = "PENUMBRA_LIGHT_CHECK"
LIGHT_CHECK_MARK = "PENUMBRA LIGHT CHECK FAILED"
light_check_failures = []  # one line per frame that broke it since the last ``take_light_failures``


def light_check_failure(color):
    """Why ``color`` (an RGBA array of a frame's Combined) breaks the invariant, or None: any
    value not finite, or any colour channel below zero by more than float rounding (a
    millionth of the frame's largest value, at least 1e-6)."""
    import numpy as np

    a = np.asarray(color, np.float32)
    if a.size == 0:
        return None
    finite = np.isfinite(a)
    if not finite.all():
        return f"{int((~finite).any(axis=-1).sum())} pixels not finite"
    rgb = a[..., :3]
    tolerance = 1e-6 * max(1.0, float(np.abs(rgb).max()))
    low = rgb < -tolerance
    if low.any():
        return f"{int(low.any(axis=-1).sum())} pixels below zero (lowest {float(rgb.min()):.4g})"
    return None


def install_light_check():
    """Check the Combined of every frame Penumbra's renderer makes from now on
    (``Renderer.render``, which the viewport, F12, batch renders and the engine core all go
    through): a frame that breaks it adds a line to ``light_check_failures`` (and, in a child
    process, prints LIGHT_CHECK_MARK on stderr, which ``run_result`` fails on). Idempotent."""
    module = load_penumbra()
    from penumbra.engine.frame import renderer as renderer_module
    from penumbra.engine.frame.film import texture_array

    cls = renderer_module.Renderer
    if getattr(cls.render, "_light_checked", False):
        return
    render = cls.render

    def checked_render(self, *args, **kwargs):
        out = render(self, *args, **kwargs)
        if getattr(out, "debug", None) is None and out.color is not None:
            why = light_check_failure(texture_array(out.color, 4))
            if why is not None:
                line = f"a {out.width}x{out.height} frame: {why}"
                light_check_failures.append(line)
                if os.environ.get(LIGHT_CHECK_ENV) == "child":
                    print(f"{LIGHT_CHECK_MARK}: {line}", file=sys.stderr)
        return out

    checked_render._light_checked = True
    checked_render.__doc__ = render.__doc__
    cls.render = checked_render
    return module


def take_light_failures():
    """The failures recorded since the last call, and forget them."""
    taken = list(light_check_failures)
    light_check_failures.clear()
    return taken


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
    if os.environ.get(LIGHT_CHECK_ENV) == "child":
        install_light_check()
    return module


class GpuRunner:
    """Runs ``fn(engine, depsgraph)`` inside a RenderEngine.render() call, where Blender's gpu
    module can draw in background mode. The engine class is built on Penumbra's engine core,
    so ``engine.render_frame`` and ``engine.draw_display`` are the production code paths.

    Use as ``runner = GpuRunner(); runner.register(); runner(fn); runner.unregister()``. The
    current scene needs a camera (Blender refuses to render without one)."""

    def __init__(self):
        import bpy

        load_penumbra()
        from penumbra.engine.render_engine import PenumbraEngineCore

        runner = self

        class PENUMBRA_GPU_RUNNER(PenumbraEngineCore, bpy.types.RenderEngine):
            bl_idname = "PENUMBRA_GPU_RUNNER"
            bl_label = "Penumbra GPU runner"
            bl_use_gpu_context = True

            def render(self, depsgraph):
                try:
                    runner._result = runner._job(self, depsgraph)
                except Exception as exc:  # handed back to the caller
                    runner._error = exc
                finally:
                    self.free_gpu()  # while the GPU context is active

            def update_render_passes(self, scene=None, renderlayer=None):
                self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")

        self.engine_class = PENUMBRA_GPU_RUNNER
        self._job = self._result = self._error = None

    def register(self):
        import bpy

        bpy.utils.register_class(self.engine_class)

    def unregister(self):
        import bpy

        bpy.utils.unregister_class(self.engine_class)

    def __call__(self, fn):
        import bpy

        scene = bpy.context.scene
        old = scene.render.engine
        scene.render.engine = self.engine_class.bl_idname
        self._job, self._result, self._error = fn, None, None
        try:
            bpy.ops.render.render(write_still=False)
        finally:
            scene.render.engine = old
        if self._error is not None:
            raise self._error
        return self._result


def gpu_renderer():
    """The GPU renderer string, or None: the gpu module only answers once a GPU context exists
    (after a GPU engine has rendered), and not at all on some Blender versions in background mode."""
    try:
        import gpu

        return gpu.platform.renderer_get()
    except Exception:
        return None


@contextlib.contextmanager
def stdout_to_stderr():
    """Send file descriptor 1 to stderr for the duration: Blender's render progress and reports
    ("Fra:1 Mem:..." lines) are printed by C code straight to it, and stdout is kept for results."""
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


# Blender prints these three lines to stderr when it first makes its headless GPU context (Mesa's
# EGL refuses one configuration, and Blender goes on with another): harmless, but they read as
# failures. ``quiet_gpu_start`` drops exactly these lines.
EGL_NOISE = b"EGL Error (0x3009): EGL_BAD_MATCH"
_quiet = {}  # the running filter: original stderr descriptor and pump thread


def quiet_gpu_start():
    """From here on, file descriptor 2 (C code's stderr as well as Python's) passes through a
    filter that drops Blender's ``EGL_BAD_MATCH`` start-up lines (``EGL_NOISE``); every other
    byte, warnings included, reaches the original stderr unchanged and at once (a partial line
    waits only while it could still become a noise line). Tools call this first (``tools``
    package); ``hard_exit`` and interpreter exit flush it. Child processes inherit it."""
    if _quiet:
        return
    sys.stderr.flush()
    original = os.dup(2)
    read, write = os.pipe()
    os.dup2(write, 2)
    os.close(write)

    def forward(data):
        while data:
            data = data[os.write(original, data) :]

    def pump():
        pending = b""
        while chunk := os.read(read, 65536):
            pending += chunk
            *lines, pending = pending.split(b"\n")
            forward(b"".join(line + b"\n" for line in lines if not line.startswith(EGL_NOISE)))
            if pending and not (EGL_NOISE.startswith(pending) or pending.startswith(EGL_NOISE)):
                forward(pending)
                pending = b""
        if pending and not pending.startswith(EGL_NOISE):
            forward(pending)
        os.close(read)

    thread = threading.Thread(target=pump, name="stderr-filter", daemon=True)
    thread.start()
    _quiet.update(original=original, thread=thread)
    atexit.register(_quiet_stop)


def _quiet_stop():
    """Put the original stderr back and let the filter pass on what it still holds."""
    if not _quiet:
        return
    with contextlib.suppress(Exception):
        sys.stderr.flush()
    os.dup2(_quiet["original"], 2)  # the pipe's last writer here: the pump sees its end
    _quiet["thread"].join(timeout=2.0)  # a child still writing to it keeps it open: do not wait on it
    os.close(_quiet.pop("original"))
    _quiet.clear()


def hard_exit(status=0):
    """Flush stdout and stderr, then leave the process with ``status`` without running the
    interpreter's and bpy's exit handlers: with Blender 4.5 as a module, a static destructor can
    wait forever on a GPU or file worker thread at exit. Every tool ends here, and so does the
    pytest session on Blender 4.5, once everything has been reported."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    _quiet_stop()
    os._exit(status)


def run(main, argv=None):
    """Run a tool's ``main(argv)`` and leave through ``hard_exit``: with its return value (None
    is 0), 1 after an uncaught exception (traceback on stderr), or the code of a SystemExit."""
    try:
        status = main(argv)
    except SystemExit as exc:
        if exc.code is None or isinstance(exc.code, int):
            status = exc.code
        else:
            print(exc.code, file=sys.stderr)
            status = 1
    except BaseException:
        traceback.print_exc()
        status = 1
    hard_exit(status or 0)
