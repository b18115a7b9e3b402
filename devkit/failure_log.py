"""A pytest plugin that writes each failure's message to a file the moment it fails.

pytest prints a failure's traceback only when the session ends, so a run killed by a time
limit (the GPU machine's: ``tools/gpu_bundle_run.sh``, ``TEST_TIMEOUT``) loses every message.
With ``PENUMBRA_FAILURES`` naming a file, each failed or errored test appends its id and its
message there at once (the file grows by at most ``LIMIT`` bytes in all), so what failed, and
why, survives the kill. Loaded by ``tests/conftest.py``; ``-p devkit.failure_log`` elsewhere.
"""

import os

ENV = "PENUMBRA_FAILURES"
LIMIT = 4 << 20  # bytes the file may reach (the GPU machine returns files under 16 MiB)
PER_FAILURE = 6000  # characters of one failure's message kept (its end: the assertion)


def pytest_runtest_logreport(report):
    path = os.environ.get(ENV)
    if not path or not report.failed:
        return
    try:
        size = os.path.getsize(path)
    except OSError:
        size = 0
    if size >= LIMIT:
        return
    text = report.longreprtext or ""
    if len(text) > PER_FAILURE:
        text = "[...]\n" + text[-PER_FAILURE:]
    stage = "" if report.when == "call" else f" (in {report.when})"
    entry = f"FAILED {report.nodeid}{stage} [{report.duration:.1f} s]\n{text}\n\n"
    with open(path, "a", encoding="utf-8", errors="replace") as out:
        out.write(entry[: LIMIT - size])
