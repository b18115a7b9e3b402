"""The ``blender`` stand-in of the farm tests (devkit/blender_cli.py) keeps to Blender's
command line: arguments in order, ``-f`` frames, script exit codes, refusals with a message."""

import pytest

from devkit import farm

TIMEOUT = 300


def blender(command, args, env):
    status, log = farm.finish(farm.start([command, *args], env), TIMEOUT)
    assert status is not None, log[-6000:]
    return status, log


@pytest.fixture(scope="module")
def installed_env(tmp_path_factory, extension_zip, blender_command, worker_env):
    user = tmp_path_factory.mktemp("stand-in-user")
    status, log = blender(
        blender_command,
        ["--command", "extension", "install-file", "-r", "user_default", "-e", extension_zip],
        {**worker_env, "BLENDER_USER_RESOURCES": str(user)},
    )
    assert status == 0, log[-6000:]
    assert (user / "extensions" / "user_default" / "penumbra" / "blender_manifest.toml").is_file(), log[-6000:]
    return {**worker_env, "BLENDER_USER_RESOURCES": str(user)}


def test_render_frame_writes_the_frames_of_an_animation_render(
    tmp_path, blender_command, scene_file, installed_env, serial_frames
):
    """``-f 3,5..6`` in a fresh process: the same pixels as those frames of a ``-a`` render (a
    frame is a function of the scene and its number), and the scene's range is left alone."""
    probe = "import bpy; s = bpy.context.scene; print('RANGE', s.frame_start, s.frame_end)"
    args = ["-b", scene_file, "-E", "PENUMBRA", "-o", tmp_path / "frame_####", "-f", "3,5..6", "--python-expr", probe]
    status, log = blender(blender_command, args, installed_env)
    assert status == 0, log[-6000:]
    assert "RANGE 1 8" in log
    assert sorted(p.name for p in tmp_path.iterdir()) == [farm.frame_name(f) for f in (3, 5, 6)]
    for f, pixels in farm.read_frames(tmp_path, (3, 5, 6)).items():
        assert pixels.tobytes() == serial_frames[f].tobytes(), f"frame {f}"


@pytest.mark.parametrize(
    "args,status,message",
    [
        (["-o", "/tmp/x", "-b", "SCENE"], 1, "Error: no blend loaded, cannot use '-o'"),
        (["-b", "SCENE", "-E", "NOPE"], 1, "Error: engine not found 'NOPE'"),
        (["-b", "SCENE", "--python-expr", "import sys; sys.exit(7)"], 7, ""),
        (["-b", "SCENE", "--python-exit-code", "4", "--python-expr", "1 / 0"], 4, "ZeroDivisionError"),
        (["-b", "SCENE", "--python-expr", "1 / 0"], 0, "ZeroDivisionError"),  # Blender goes on
        (["-b", "SCENE", "-x", "1"], 2, "'-x' is not supported by this stand-in"),
    ],
)
def test_arguments_are_processed_in_order_as_blender_does(
    args, status, message, blender_command, scene_file, installed_env
):
    args = [scene_file if a == "SCENE" else a for a in args]
    got, log = blender(blender_command, args, installed_env)
    assert got == status, log[-6000:]
    assert message in log, log[-6000:]
