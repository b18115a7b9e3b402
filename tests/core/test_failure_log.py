"""``devkit.failure_log``: a failure's message reaches $PENUMBRA_FAILURES the moment it fails, so
a run that a time limit kills (the GPU machine's runner) still tells what failed and why."""

import subprocess
import sys
import textwrap
import time

from devkit import failure_log
from devkit.session import child_env

SUITE = """
import time

def test_passes():
    assert True

def test_fails():
    value = 41
    assert value == 42, "the answer moved"

def test_hangs():
    time.sleep(600)
"""


def test_a_failure_is_written_before_the_run_is_killed(tmp_path):
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    (tmp_path / "test_suite.py").write_text(textwrap.dedent(SUITE))
    log = tmp_path / "failures.txt"
    env = child_env()
    env[failure_log.ENV] = str(log)
    child = subprocess.Popen(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "devkit.failure_log", "test_suite.py"],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
    )
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and "the answer moved" not in (log.read_text() if log.exists() else ""):
            assert child.poll() is None, child.stdout.read().decode()  # it hangs in the third test
            time.sleep(0.1)
    finally:
        child.kill()  # as the runner's time limit does: pytest's own report never comes
        out = child.communicate()[0].decode()
    text = log.read_text()
    assert text.startswith("FAILED test_suite.py::test_fails ["), text
    assert "assert 41 == 42" in text and "the answer moved" in text
    assert text.count("FAILED ") == 1  # neither the passing test nor the one still running
    assert "short test summary" not in out  # pytest itself never reported it


def test_the_log_stays_within_its_limit(tmp_path, monkeypatch):
    """Appends stop at ``LIMIT`` bytes, and a long message keeps its end (the assertion)."""
    log = tmp_path / "failures.txt"
    monkeypatch.setenv(failure_log.ENV, str(log))
    monkeypatch.setattr(failure_log, "LIMIT", 20000)

    class Report:
        failed, when, duration = True, "call", 0.5
        nodeid = "tests/x.py::test_long"
        longreprtext = "x" * 50000 + "\nE   assert 1 == 2"

    for _ in range(10):
        failure_log.pytest_runtest_logreport(Report())
    text = log.read_text()
    assert len(text.encode()) <= 20000
    assert text.count("E   assert 1 == 2") == 3  # three whole entries of about 6000 characters
    Report.failed = False
    size = len(text)
    failure_log.pytest_runtest_logreport(Report())
    assert len(log.read_text()) == size  # a passing test writes nothing
