"""The farm job template (farm/penumbra-render.yaml), run by the real Open Job Description
runtime: ``openjd`` of openjd-cli (pinned in tools/lock), the runtime AWS Deadline Cloud's
workers share the job format with. Each ``openjd run`` is one worker's session running its
chunks of the job's frames.

The job's ``blender`` is a stand-in here (devkit/blender_cli.py: this venv's bpy module behind
Blender's command line, taking the same arguments); on a farm the real ``blender`` runs. Every
Blender process is a child of ``openjd`` (itself a child of the test), so a crash fails a test,
not the run.
"""

import os
import shutil
import zipfile

import numpy as np
import pytest

from devkit import farm, session

FRAMES = range(farm.FRAMES[0], farm.FRAMES[1] + 1)
TIMEOUT = 300  # seconds for any one process: generous on a loaded 2-core machine


def finish(proc):
    status, log = farm.finish(proc, TIMEOUT)
    assert status is not None, f"{proc.args[:2]} did not finish in {TIMEOUT} s:\n{log[-6000:]}"
    return status, log


def run(cmd, env):
    return finish(farm.start(cmd, env))


def job_params(scene, out_dir, blender, **extra):
    return {
        "SceneFile": scene,
        "Frames": f"{FRAMES[0]}-{FRAMES[-1]}",
        "FramesPerTask": 2,
        "OutputDir": out_dir,
        "BlenderCommand": blender,
        **extra,
    }


def same_bits(a, b):
    return a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a.view(np.uint32), b.view(np.uint32))


def test_openjd_check_accepts_the_template():
    status, log = run([farm.openjd(), "check", farm.TEMPLATE], os.environ)
    assert status == 0, log
    assert "passes validation checks" in log


def test_the_job_is_one_task_per_chunk_of_frames(scene_file, tmp_path):
    params = job_params(scene_file, tmp_path / "renders", "blender")
    assert farm.chunks(params) == [{"Frame": "1-2"}, {"Frame": "3-4"}, {"Frame": "5-6"}, {"Frame": "7-8"}]
    # At most FramesPerTask frames a task, the chunks balanced; a gap in the range splits them.
    assert farm.chunks({**params, "Frames": "1-7", "FramesPerTask": 3}) == [
        {"Frame": "1-3"},
        {"Frame": "4-5"},
        {"Frame": "6-7"},
    ]
    assert farm.chunks({**params, "Frames": "1-2,5"}) == [{"Frame": "1-2"}, {"Frame": "5-5"}]


def test_two_workers_write_the_frames_of_a_serial_render_bit_for_bit(
    tmp_path, extension_zip, blender_command, scene_file, worker_env, worker_home, serial_frames
):
    out = tmp_path / "renders"
    params = job_params(scene_file, out, blender_command)
    tasks = farm.chunks(params)
    # Worker A runs the repository's template with ExtensionZip given; worker B a job bundle:
    # the template with penumbra.zip beside it (the parameter's default). Disjoint chunks, at once.
    bundle = tmp_path / "bundle"
    bundle.mkdir()
    shutil.copy(farm.TEMPLATE, bundle / "template.yaml")
    shutil.copy(extension_zip, bundle / "penumbra.zip")
    worker_a = farm.start(farm.openjd_run({**params, "ExtensionZip": extension_zip}, tasks[0::2]), worker_env)
    worker_b = farm.start(farm.openjd_run(params, tasks[1::2], template=bundle / "template.yaml"), worker_env)
    for status, log in (finish(worker_a), finish(worker_b)):
        assert status == 0, log[-8000:]
        assert "Chunks run: 2" in log, log[-8000:]
        # Installed once per session, into the session's own folder; the second chunk finds it.
        assert log.count("Penumbra job: installing") == 1, log[-8000:]
        assert "Traceback" not in log, log[-8000:]

    assert sorted(p.name for p in out.iterdir()) == [farm.frame_name(f) for f in FRAMES]
    job = farm.read_frames(out, FRAMES)
    for f in FRAMES:
        assert job[f].shape == (farm.HEIGHT, farm.WIDTH, 4)
        diff = float(np.abs(job[f] - serial_frames[f]).max())
        assert same_bits(job[f], serial_frames[f]), f"frame {f}: max |job - serial| = {diff}"
    # The workers' own Blender configuration (BLENDER_USER_RESOURCES of their HOME) was never
    # read into or written: each session had its own user folder.
    assert not (worker_home / "blender").exists()


def test_the_frames_show_the_moving_light_and_the_animated_grain(serial_frames):
    """The comparison above means something only if every frame differs: the NOISE layer's grain
    is that frame's grain (Penumbra's own numpy twin of the shader) at the keyframed amount,
    and the lamp's light moves across the picture."""
    session.load_penumbra()
    from penumbra.engine.post.noise import grain_reference

    amounts, centroids, previous = [], [], None
    for f in FRAMES:
        rgb = serial_frames[f][::-1, :, :3].astype(np.float64)  # bottom row first, like the grain
        grain = grain_reference(farm.WIDTH, farm.HEIGHT, f, monochrome=False)[..., :3]
        # Top-left 20x3 pixels: only sky (a constant world colour per channel) plus grain there.
        sky, g = rgb[-3:, :20], grain[-3:, :20]
        sky, g = sky - sky.mean(axis=(0, 1)), g - g.mean(axis=(0, 1))
        amount = float((sky * g).sum() / (g * g).sum())
        assert np.abs(sky - amount * g).max() < 1e-6, (
            f"frame {f}: the sky is not the world colour plus frame {f}'s grain"
        )
        amounts.append(amount)
        clean = (rgb - amount * grain).mean(axis=2)  # the frame without its grain
        centroids.append(float((clean * np.arange(farm.WIDTH)).sum() / clean.sum()))
        if previous is not None:
            assert np.abs(clean - previous).max() > 0.05, f"frames {f - 1} and {f} are lit alike"
        previous = clean

    first, last = farm.NOISE_AMOUNT
    assert amounts[0] == pytest.approx(first, abs=1e-5) and amounts[-1] == pytest.approx(last, abs=1e-5)
    assert all(a < b for a, b in zip(amounts, amounts[1:])), amounts  # keyframed: it grows through the shot
    assert centroids[-1] - centroids[0] > 8.0, centroids  # the lamp crosses the set: the light follows it


def test_a_task_given_a_broken_blend_fails_alone_and_the_other_tasks_write_their_frames(
    tmp_path, extension_zip, blender_command, scene_file, worker_env, serial_frames
):
    """One job, three tasks on three workers at once. The job names its files as submitted
    (/studio/...); each worker sees them through path mapping rules, as farm workers do. Worker
    2's copy of the .blend is broken (cut short, as by an interrupted sync): its task fails with
    the message in its log; the other two write their frames."""
    share, broken = tmp_path / "share", tmp_path / "worker2-copy"
    shutil.copytree(scene_file.parent, share / "shot")
    (broken / "shot").mkdir(parents=True)
    data = scene_file.read_bytes()
    (broken / "shot" / "scene.blend").write_bytes(data[: len(data) // 2])  # Blender's header intact
    out = share / "renders"
    params = job_params(
        "/studio/shot/scene.blend", "/studio/renders", blender_command, Frames="1-6", ExtensionZip=extension_zip
    )
    to_share = [{"source_path_format": "POSIX", "source_path": "/studio", "destination_path": str(share)}]
    to_broken_copy = [
        {"source_path_format": "POSIX", "source_path": "/studio/shot", "destination_path": str(broken / "shot")},
        {"source_path_format": "POSIX", "source_path": "/studio/renders", "destination_path": str(out)},
    ]
    tasks = farm.chunks(params)
    assert tasks == [{"Frame": "1-2"}, {"Frame": "3-4"}, {"Frame": "5-6"}]
    workers = [
        farm.start(farm.openjd_run(params, [task], path_mapping_rules=rules), worker_env)
        for task, rules in zip(tasks, (to_share, to_broken_copy, to_share))
    ]
    (ok_1, log_1), (failed, log_2), (ok_3, log_3) = [finish(w) for w in workers]

    assert ok_1 == 0, log_1[-8000:]
    assert ok_3 == 0, log_3[-8000:]
    assert failed != 0, log_2[-8000:]
    broken_blend = broken / "shot" / "scene.blend"
    assert f"Failed to read blend file '{broken_blend}'" in log_2, log_2[-8000:]  # Blender's own words
    assert f"Penumbra job: ERROR: Blender exited with status 1 on frames 3-4 of {broken_blend}" in log_2, log_2[-8000:]
    assert "Session ended with errors" in log_2

    assert sorted(p.name for p in out.iterdir()) == [farm.frame_name(f) for f in (1, 2, 5, 6)]
    written = farm.read_frames(out, (1, 2, 5, 6))
    for f, pixels in written.items():
        assert same_bits(pixels, serial_frames[f]), f"frame {f}"


def test_a_stereo_scene_writing_each_eye_apart_passes_the_frame_check(
    tmp_path, extension_zip, blender_command, scene_file, worker_env
):
    """After the render the task checks every file Blender should have written: with stereo
    output written per eye, that is frame_0001_L.exr and frame_0001_R.exr, not frame_0001.exr."""
    stereo = tmp_path / "stereo.blend"
    make_stereo = (
        "import bpy; r = bpy.context.scene.render; r.use_multiview = True; r.views_format = 'STEREO_3D'; "
        f"r.image_settings.views_format = 'INDIVIDUAL'; bpy.ops.wm.save_as_mainfile(filepath={str(stereo)!r})"
    )
    status, log = run(
        [blender_command, "-b", scene_file, "--python-exit-code", 1, "--python-expr", make_stereo], worker_env
    )
    assert status == 0 and stereo.is_file(), log[-6000:]
    out = tmp_path / "renders"
    params = job_params(stereo, out, blender_command, ExtensionZip=extension_zip)
    status, log = run(farm.openjd_run(params, [{"Frame": "1-2"}]), worker_env)
    assert status == 0, log[-8000:]
    assert "Penumbra job: wrote 4 files" in log, log[-8000:]
    assert sorted(p.name for p in out.iterdir()) == [f"frame_{f:04d}_{eye}.exr" for f in (1, 2) for eye in "LR"]


def fake_extension_zip(path):
    """A valid extension named penumbra that registers nothing (so no PENUMBRA engine)."""
    manifest = (session.ROOT / "blender_manifest.toml").read_text().split("[build]")[0]
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("blender_manifest.toml", manifest)
        archive.writestr("__init__.py", "def register():\n    pass\n\n\ndef unregister():\n    pass\n")
    return path


@pytest.mark.parametrize(
    "case",
    ["missing file", "not a blend", "no # in the pattern", "unwritable folder", "view layer", "engine", "blender"],
)
def test_a_wrong_input_fails_the_task_with_a_message(
    case, tmp_path, extension_zip, blender_command, scene_file, worker_env
):
    text = tmp_path / "notes.blend"
    text.write_text("not a scene\n")
    out = tmp_path / "renders"
    changes, message = {
        "missing file": (
            {"SceneFile": tmp_path / "nope.blend"},
            f"the .blend file {tmp_path / 'nope.blend'} does not exist (SceneFile)",
        ),
        "not a blend": ({"SceneFile": text}, f"{text} is not a .blend file"),
        "no # in the pattern": ({"OutputPattern": "frame"}, "OutputPattern 'frame' has no '#'"),
        "unwritable folder": (
            {"OutputDir": text / "renders"},  # below a file: it cannot be created
            f"cannot create the output folder {text / 'renders'} (OutputDir)",
        ),
        "view layer": ({"ViewLayer": "Beauty"}, "scene 'Scene' has no view layer 'Beauty' (ViewLayer)"),
        "engine": (
            {"ExtensionZip": fake_extension_zip(tmp_path / "other.zip")},
            "the PENUMBRA render engine is not available",
        ),
        "blender": (
            {"BlenderCommand": tmp_path / "blender-4.5"},
            f"the Blender command '{tmp_path / 'blender-4.5'}' was not found",
        ),
    }[case]
    params = {**job_params(scene_file, out, blender_command, ExtensionZip=extension_zip), **changes}
    status, log = run(farm.openjd_run(params, [{"Frame": "1-2"}]), worker_env)
    assert status != 0, log[-8000:]
    assert f"Penumbra job: ERROR: {message}" in log, log[-8000:]
    assert not out.exists() or not any(out.iterdir())
