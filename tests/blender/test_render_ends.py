"""Every render ends: a frame whose shader compile or draw could run without end is a bug, and so
is a render that Esc cannot stop. The scenes render in child processes with a watchdog, so a
frame that never ends fails its test, not the run."""

import json
import re
import subprocess
import sys
import time

import bpy
import numpy as np

from devkit import scenes, session
from devkit.render import render

# The suite's fuzz: 50 scenes per line, their programs drawn from 6 forms (devkit.fuzz), in two
# child processes at once (one per core; each compiles three forms' programs).
FUZZ_SEEDS = range(50)
FUZZ_FORMS = 6
SCENE_BUDGET = 90.0  # seconds a scene may take, its cold shader compiles included


def _children(commands, timeout, extra_env=None):
    """Run the ``commands`` (argument lists of this Python) at once, with ``extra_env`` added to
    their environment; their (returncode, output)."""
    env = session.child_env()
    env[session.LIGHT_CHECK_ENV] = "child"
    # A compile that never ends lives in LLVM's optimisation passes: the children compile as a
    # user's llvmpipe does, with them (tests/conftest.py turns them off for the suite).
    env.pop("GALLIVM_PERF", None)
    env.update(extra_env or {})
    procs = [
        subprocess.Popen(
            [sys.executable, *cmd],
            cwd=session.ROOT,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        for cmd in commands
    ]
    results = []
    deadline = time.monotonic() + timeout
    for proc in procs:
        try:
            out, _ = proc.communicate(timeout=max(1.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            proc.kill()
            out, _ = proc.communicate()
        results.append((proc.returncode, out))
    return results


def test_random_scenes_all_end_finite_and_non_negative():
    """50 seeded random scenes (devkit/fuzz.py: meshes at 1e-3 to 1e2, every light type and
    size, extreme node inputs, alpha hashed and blended) each end within SCENE_BUDGET with a
    finite Combined >= 0. A scene that does not is named with its description; rebuild it with
    ``python -m tools.fuzz --seeds N --forms 6 --save scene.blend``."""
    halves = [[s for s in FUZZ_SEEDS if s % 2 == k] for k in (0, 1)]
    commands = [
        [
            "-m",
            "tools.fuzz",
            "--seeds",
            ",".join(map(str, h)),
            "--forms",
            str(FUZZ_FORMS),
            "--budget",
            str(SCENE_BUDGET),
        ]
        for h in halves
    ]
    done = {}
    for returncode, out in _children(commands, timeout=SCENE_BUDGET * len(FUZZ_SEEDS) / 2):
        begun = dict(re.findall(r"^FUZZ BEGIN (\d+) (.*)$", out, re.M))
        ended = {int(s): why for s, _t, why in re.findall(r"^FUZZ END (\d+) (\S+) (.*)$", out, re.M)}
        unfinished = [s for s in begun if int(s) not in ended]
        assert not unfinished, (
            f"scene {unfinished[0]} did not end within {SCENE_BUDGET} s (exit {returncode}): "
            f"{begun[unfinished[0]]}\n{out[-3000:]}"
        )
        assert returncode == 0 and session.LIGHT_CHECK_MARK not in out, out[-3000:]
        done.update(ended)
    assert sorted(done) == list(FUZZ_SEEDS)
    failed = {s: why for s, why in done.items() if why != "ok"}
    assert not failed, f"scenes whose Combined is not finite and >= 0: {failed}"


_HANG_SCRIPT = """
import json, sys, time
from devkit import session
session.isolate()
import bpy
session.load_penumbra().register()
from devkit import fuzz
from devkit.render import render
scene = fuzz.transparent_hang_scene(64, 36, alpha_linked={linked})
start = time.perf_counter()
c = render(scene)["Combined"]
print("RESULT " + json.dumps({{"seconds": time.perf_counter() - start, "why": session.light_check_failure(c),
                              "mean": float(c[..., :3].mean())}}), flush=True)
session.hard_exit(0)
"""


def test_the_transparent_scene_that_hung_renders_like_its_opaque_twin():
    """The hashed Suzanne under three sampled lights with maps (a frame whose lit program
    once never finished compiling on llvmpipe) renders, finite, in about the time of the same
    scene with its alpha unlinked: each in a fresh process with Mesa's shader cache off, so
    both pay their whole compile. Measured on 5.2: 9.0 s against 8.7 s (before: no end)."""
    results = _children(
        [["-c", _HANG_SCRIPT.format(linked=v)] for v in (True, False)],
        timeout=240,
        extra_env={"MESA_SHADER_CACHE_DISABLE": "true"},
    )
    runs = []
    for returncode, out in results:
        line = next((ln for ln in out.splitlines() if ln.startswith("RESULT ")), None)
        assert returncode == 0 and line is not None, out[-3000:]
        runs.append(json.loads(line[len("RESULT ") :]))
    linked, unlinked = runs
    assert linked["why"] is None and unlinked["why"] is None
    assert linked["mean"] > 0.0  # the scene is lit
    assert linked["seconds"] < 2.0 * unlinked["seconds"] + 5.0, runs


LIT_ENTRIES = ("lit.frag.glsl", "lit_debug.frag.glsl", "lit_settle.frag.glsl")


def test_lit_entry_shaders_discard_only_after_their_light_loops():
    """The rule the hang taught (lib/lit_inputs.glsl coverage_discards): an entry shader of the
    lit pass decides its coverage first and discards after the world's and the lights' loops,
    never before them (on llvmpipe an early discard ahead of them made LLVM's compile run
    without end). Each of them has both, in that order."""
    for name in LIT_ENTRIES:
        text = (session.ROOT / "shaders" / name).read_text(encoding="utf-8")
        code = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
        body = code[code.index("void main()") :]
        loops = body.index("lights_on(")
        discards = [m.start() for m in re.finditer(r"\bdiscard\b", body)]
        assert discards, name
        emission_only = body.find("#if EMISSION_ONLY")
        for at in discards:
            # The Emission-only variant's own early exit has no loops after it (it returns).
            if emission_only != -1 and emission_only < at < body.index("#endif", emission_only):
                continue
            assert at > loops, f"{name}: a discard before the lights' loops"


def test_cancel_keeps_the_samples_rendered_as_the_result(penumbra):
    """Esc during a 2,000-sample F12 render: the render returns after the sample it was pressed
    in, and writes the samples it has as its result (finite, lit, the same image as a render
    of that many samples would have been up to sampling). Blender's ``test_break`` answers Esc
    only in a session with a window, so the test answers in its place, at the one method that
    asks it (``break_requested``)."""
    engine = penumbra.engine.render_engine.PenumbraRenderEngine
    scene = scenes.demo_scene(48, 27)
    scene.penumbra.render_samples = 2000
    scene.penumbra.use_adaptive_sampling = False
    scene.penumbra.time_limit = 0.0
    calls = []

    def pressed_after_four(self):
        calls.append(time.perf_counter())
        return len(calls) > 4  # the 4th sample's check says stop

    original = engine.break_requested
    engine.break_requested = pressed_after_four
    try:
        start = time.perf_counter()
        partial = render(scene)["Combined"]
        end = time.perf_counter()
    finally:
        engine.break_requested = original
    # One check before the view, then one after each sample: stopped after the 4th sample's.
    assert len(calls) == 5
    sample_time = float(np.median(np.diff(calls[1:5])))
    assert end - calls[-1] < 5.0 * sample_time + 2.0, (end - calls[-1], sample_time, end - start)
    assert np.all(np.isfinite(partial)) and partial[..., :3].mean() > 0.01
    scene.penumbra.render_samples = 4
    four = render(scene)["Combined"]
    # Four of 2,000 samples against a frame of four: the same scene up to sampling noise.
    assert abs(float(partial[..., :3].mean() - four[..., :3].mean())) < 0.05 * float(four[..., :3].mean())
    assert bpy.context.scene is scene
