"""The farm job (``farm/penumbra-render.yaml``) and what its tests need around it: the
template's path, an animated scene saved as a .blend, and ``openjd`` of this venv.

    python -m devkit.farm scene.blend     # write the animated test scene

Scene building imports ``bpy``; run it in a child process (the module's command line).
"""

import json
import math
import os
import signal
import subprocess
import sys
from pathlib import Path

from devkit.session import ROOT

TEMPLATE = ROOT / "farm" / "penumbra-render.yaml"
INSTALL_SCRIPT = ROOT / "farm" / "install-extension.sh"

# The animated test scene: small, so a frame costs little on llvmpipe.
WIDTH, HEIGHT = 64, 36
FRAMES = (1, 8)
# Keyframed over FRAMES: the grain grows through the shot (below the sky's darkest channel,
# 0.04, so the sky takes the whole amount: grain is no stronger than the light it moves).
NOISE_AMOUNT = (0.01, 0.035)


def frame_name(frame):
    """The file the job's default OutputPattern (frame_####) and the scene's EXR output give."""
    return f"frame_{frame:04d}.exr"


def read_frames(folder, frames):
    """{frame: float32 RGBA array (top row first)} of the frames written to ``folder``."""
    from devkit.imageio import read_exr

    return {f: read_exr(Path(folder) / frame_name(f))["Combined"] for f in frames}


def start(cmd, env):
    """Start ``cmd`` (stdout and stderr together) in a process group of its own, so that
    ``finish`` can stop it with every process it started."""
    return subprocess.Popen(
        [str(c) for c in cmd],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )


def finish(proc, timeout):
    """Wait for a process from ``start``: (exit status, output). One that outlives ``timeout``
    seconds is killed with its process group; its status is then None."""
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, _ = proc.communicate()
        return None, out + f"\n[killed after {timeout} s]"
    return proc.returncode, out


def openjd():
    """The ``openjd`` command of this interpreter's venv (openjd-cli, pinned in tools/lock)."""
    return str(Path(sys.executable).with_name("openjd"))


def openjd_run(params, tasks, template=TEMPLATE, path_mapping_rules=None):
    """The ``openjd run`` command line running ``tasks`` (task parameter sets, such as
    ``[{"Frame": "1-2"}]``) of ``template`` with job parameters ``params`` in one session, as
    one worker would."""
    cmd = [openjd(), "run", str(template), "--tasks", json.dumps(tasks)]
    for name, value in params.items():
        cmd += ["--job-param", f"{name}={value}"]
    if path_mapping_rules:
        document = {"version": "pathmapping-1.0", "path_mapping_rules": path_mapping_rules}
        cmd += ["--path-mapping-rules", json.dumps(document)]
    return cmd


def chunks(params, template=TEMPLATE):
    """The task parameter sets a scheduler makes of the job (one per chunk of frames), from the
    template through openjd-model: ``[{"Frame": "1-2"}, {"Frame": "3-4"}, ...]``."""
    import yaml
    from openjd.model import StepParameterSpaceIterator, create_job, decode_job_template, preprocess_job_parameters

    job_template = decode_job_template(
        template=yaml.safe_load(Path(template).read_text()), supported_extensions=["TASK_CHUNKING"]
    )
    values = preprocess_job_parameters(
        job_template=job_template,
        job_parameter_values={k: str(v) for k, v in params.items()},
        job_template_dir=Path(template).parent.absolute(),
        current_working_dir=Path.cwd(),
    )
    (step,) = create_job(job_template=job_template, job_parameter_values=values).steps
    return [
        {name: value.value for name, value in task.items()}
        for task in StepParameterSpaceIterator(space=step.parameterSpace)
    ]


def animated_scene(width=WIDTH, height=HEIGHT, frames=FRAMES):
    """A ground, a box and a ball under a point light that moves across the set, a dim sun,
    and a post stack with an animated NOISE layer (keyframed amount; the grain follows the
    frame number). Output: 32-bit float EXR, one file per frame. The scene is saved with
    Workbench as its engine, so the farm job's ``-E PENUMBRA`` is what picks Penumbra."""
    from devkit import imageio, scenes, session

    session.load_penumbra().register()
    scene = scenes.empty_scene(width, height)
    scenes.set_world(scene, (0.04, 0.05, 0.07))
    scenes.plane(scene, "Ground", size=12.0, mat=scenes.material("Ground", (0.7, 0.7, 0.68), roughness=0.8))
    scenes.box(
        scene, "Crate", center=(-1.2, 0.3, 0.6), size=(1.2, 1.2, 1.2), mat=scenes.material("Crate", (0.8, 0.4, 0.15))
    )
    scenes.uv_sphere(scene, "Ball", center=(1.1, -0.4, 0.8), radius=0.8, segments=16, rings=8)
    scenes.light(scene, "Sun", "SUN", 0.5, rotation=(math.radians(35), 0.0, math.radians(30)))
    lamp = scenes.light(scene, "Lamp", "POINT", 400.0, location=(-4.0, -2.0, 3.0), shadow_soft_size=0.3)
    scenes.look_at(scene, (6.0, -7.0, 5.0), (0.0, 0.0, 0.5))

    first, last = frames
    scene.frame_start, scene.frame_end = first, last
    for frame, x in ((first, -4.0), (last, 4.0)):
        lamp.location.x = x
        lamp.keyframe_insert("location", index=0, frame=frame)

    layers = scene.penumbra.layers
    layers.clear()
    noise = layers.add()
    noise.effect, noise.name = "NOISE", "Grain"
    noise.noise.monochrome = False
    for frame, amount in zip(frames, NOISE_AMOUNT):
        noise.noise.amount = amount
        noise.noise.keyframe_insert("amount", frame=frame)

    settings = scene.render.image_settings
    imageio.set_format(settings, "OPEN_EXR", color_depth="32", exr_codec="ZIP")
    settings.color_mode = "RGBA"
    scene.render.use_file_extension = True
    scene.render.engine = "BLENDER_WORKBENCH"
    return scene


def save_scene(path):
    """Build ``animated_scene()`` and save it to ``path``."""
    import bpy

    animated_scene()
    bpy.ops.wm.save_as_mainfile(filepath=str(Path(path).absolute()))


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m devkit.farm SCENE.blend", file=sys.stderr)
        return 2
    save_scene(argv[0])
    return 0


if __name__ == "__main__":
    from devkit.session import run

    run(main)
