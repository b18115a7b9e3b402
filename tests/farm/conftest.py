"""Farm test fixtures: the extension zip (built once per test session, with Blender's own tool),
the ``blender`` stand-in, the animated scene saved as a .blend, and its frames rendered in one
Blender process. Everything Blender runs runs in child processes."""

import subprocess
import sys

import pytest

from devkit import farm
from devkit.blender_cli import stand_in_command
from devkit.extension import build_zip
from devkit.session import child_env, isolated_env

TIMEOUT = 300  # seconds for any one process: generous on a loaded 2-core machine


@pytest.fixture(scope="session")
def extension_zip(tmp_path_factory):
    return build_zip(tmp_path_factory.mktemp("dist"))


@pytest.fixture(scope="session")
def worker_home(tmp_path_factory):
    """The HOME of the farm workers of this test session: its Blender user folder
    (``blender/``, BLENDER_USER_RESOURCES) stands for a worker's own configuration."""
    return tmp_path_factory.mktemp("worker-home")


@pytest.fixture(scope="session")
def worker_env(worker_home, tmp_path_factory):
    """Environment of a worker process: the isolated HOME, the repository importable (for the
    stand-in), and TMPDIR inside the test's folder (openjd puts its session folders there)."""
    env = child_env(isolated_env(worker_home))
    env["TMPDIR"] = str(tmp_path_factory.mktemp("worker-tmp"))
    env["PYTHONUNBUFFERED"] = "1"
    return env


@pytest.fixture(scope="session")
def blender_command(tmp_path_factory):
    """An executable ``blender`` for the job: the bpy module of this venv behind Blender's command
    line (devkit/blender_cli.py). On a farm the real ``blender`` runs instead."""
    return stand_in_command(tmp_path_factory.mktemp("bin"))


@pytest.fixture(scope="session")
def scene_file(tmp_path_factory):
    """The animated test scene (devkit.farm.animated_scene) as ``share/shot/scene.blend``, made
    by an artist's Blender (a HOME of its own)."""
    path = tmp_path_factory.mktemp("share") / "shot" / "scene.blend"
    path.parent.mkdir()
    proc = subprocess.run(
        [sys.executable, "-m", "devkit.farm", str(path)],
        env=child_env(isolated_env(tmp_path_factory.mktemp("artist-home"))),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0 and path.is_file(), proc.stdout[-2000:] + proc.stderr[-3000:]
    return path


@pytest.fixture(scope="session")
def serial_frames(tmp_path_factory, extension_zip, blender_command, scene_file, worker_env):
    """The scene's frames rendered in one Blender process, on a worker provisioned by
    farm/install-extension.sh (the extension in a user folder of its own)."""
    root = tmp_path_factory.mktemp("serial")
    user, out = root / "blender-user", root / "renders"
    install = ["bash", farm.INSTALL_SCRIPT, "--blender", blender_command, extension_zip, user]
    status, log = farm.finish(farm.start(install, worker_env), TIMEOUT)
    assert status == 0, log[-6000:]
    assert f"install-extension: Penumbra installed in {user}" in log, log[-6000:]
    assert (user / "extensions" / "user_default" / "penumbra" / "__init__.py").is_file()
    first, last = farm.FRAMES
    render = [
        blender_command,
        "-b",
        scene_file,
        "-E",
        "PENUMBRA",
        "-o",
        out / "frame_####",
        "-s",
        first,
        "-e",
        last,
        "-a",
    ]
    status, log = farm.finish(farm.start(render, {**worker_env, "BLENDER_USER_RESOURCES": str(user)}), TIMEOUT)
    assert status == 0, log[-6000:]
    return farm.read_frames(out, range(first, last + 1))
