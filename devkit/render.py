"""Rendering to numpy arrays: through Blender's own output path (what a batch render writes),
or one frame of Penumbra's engine core inside a GPU context."""

import hashlib
import os
import tempfile
from pathlib import Path

import bpy
import numpy as np

from devkit import engines, scenes
from devkit.imageio import read_exr, set_format


def render(scene=None, passes=("Combined",)):
    """Render ``scene`` with its engine through Blender's own output path (the same file a
    batch render writes); return {pass: array (h, w, c)} flipped so row 0 is the bottom of the
    image (the orientation of GPU textures and Blender's pixel buffers)."""
    scene = scene or bpy.context.scene
    scene.view_layers[0].use_pass_z = "Depth" in passes
    scene.view_layers[0].use_pass_emit = "Emission" in passes
    if hasattr(scene.view_layers[0], "penumbra"):
        scene.view_layers[0].penumbra.use_pass_shadow = "Shadow" in passes
        scene.view_layers[0].penumbra.use_pass_lit = "Lit" in passes
    set_format(scene.render.image_settings, "OPEN_EXR_MULTILAYER", color_depth="32", exr_codec="ZIP")
    old = scene.render.filepath
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "frame.exr")
        scene.render.filepath = path
        scene.render.use_file_extension = False
        try:
            bpy.ops.render.render(write_still=True)
            data = read_exr(path)
        finally:
            scene.render.filepath = old
    # The Emission pass is "Emit" up to Blender 4.5: one name for callers on every line.
    return {("Emission" if k == "Emit" else k): v[::-1] for k, v in data.items()}


def engine_frame(runner, scene, width, height):
    """One frame of ``scene``'s camera through the engine core (``devkit.session.GpuRunner``
    ``runner``): (FrameStats, scene-linear RGBA array (height, width, 4), row 0 at the bottom)."""
    from penumbra.engine.scene.extract import camera_from_scene

    def job(engine, depsgraph):
        out = engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, width, height), width, height)
        return out.stats, out.color_array().copy()

    return runner(job)


def technique_frame(runner, scene, width, height, samples, without=()):
    """A frame of ``samples`` samples of ``scene``'s camera through the engine core, with the
    frame's techniques named in ``without`` left out of its renderer's registry
    (``engine/frame/features``): (scene-linear RGBA array, row 0 at the bottom, FrameStats, the
    samples' filter weights)."""
    from penumbra.engine.frame.features import REGISTRY
    from penumbra.engine.frame.renderer import Renderer
    from penumbra.engine.scene.extract import camera_from_scene

    def job(engine, depsgraph):
        engine.renderer = Renderer(features=tuple(f for f in REGISTRY if f.name not in without))
        cam = camera_from_scene(depsgraph, scene, width, height)
        out = engine.render_frame(depsgraph, cam, width, height, samples=(0, samples), sample_count=samples)
        return out.color_array().copy(), out.stats, list(engine.renderer.film.sample_weights)

    return runner(job)


def viewport_calls(runner, scene, width, height, calls):
    """``calls`` redraws of the viewport through ``scene``'s camera (the engine's
    ``viewport_frame``, one more sample a call while it refines): (the last call's
    scene-linear RGBA array, row 0 at the bottom, each call's FrameStats)."""

    def job(engine, depsgraph):
        cam = scene.camera.evaluated_get(depsgraph)
        view = cam.matrix_world.inverted()
        window = cam.calc_matrix_camera(depsgraph, x=width, y=height, scale_x=1.0, scale_y=1.0)
        stats = []
        for _ in range(calls):
            out, _rendered = engine.viewport_frame(depsgraph, view, window, width, height)
            stats.append(out.stats)
        return out.color_array().copy(), stats

    return runner(job)


REFERENCE_CACHE = Path("out") / "reference_cache"


def cached_image(tag, source, key, make, cache_dir=REFERENCE_CACHE):
    """``make()``'s image (an array), cached per clone under ``cache_dir`` by ``tag``, the content
    of the file ``source`` (the benchmark that defines the scene), Blender's version and
    ``key``: a reference rendered once (Cycles at many samples) and read back after."""
    own = hashlib.sha256(Path(source).read_bytes()).hexdigest()[:10]
    name = f"{tag}-{own}-{bpy.app.version_string}-{key}"
    path = Path(cache_dir) / f"{hashlib.sha256(name.encode()).hexdigest()[:16]}.npy"
    if path.exists():
        return np.load(path)
    image = make()
    path.parent.mkdir(parents=True, exist_ok=True)
    np.save(path, image)
    return image


def group_off_and_on(gpu_call, off_inputs, on_inputs, define, width=48, height=32, samples=2):
    """A Principled input group at weight 0 and above it, on the demo scene's first material:
    its frame as it is, with ``off_inputs`` set (the group's other inputs, its weight still 0)
    and with ``on_inputs`` set too. Returns (plain, zero, on) images and, for the frames with
    ``off_inputs`` and with ``on_inputs``, whether any lit variant drawn had ``define``."""
    scene = scenes.demo_scene(width, height)
    mat = next(m for m in (s.material for o in scene.objects for s in o.material_slots) if m is not None)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    plain, _stats, _ = technique_frame(gpu_call, scene, width, height, samples)
    compiled = []
    images = [plain]
    for inputs in (off_inputs, on_inputs):
        for name, value in inputs.items():
            bsdf.inputs[name].default_value = value
        image, stats, _ = technique_frame(gpu_call, scene, width, height, samples)
        images.append(image)
        compiled.append(any(dict(k.program().defines).get(define) for k in stats.lit_keys))
    return images, compiled


def debug_view_mean(scene, view, samples=2):
    """``scene``'s F12 image with debug view ``view`` (``"NONE"``: the image itself; a debug
    image is the Combined pass), its mean RGB above the legend strip; the view is reset after."""
    scene.penumbra.debug_view = view
    engines.configure(scene, "PENUMBRA", render_samples=samples)
    try:
        image = render(scene)["Combined"][..., :3]
    finally:
        scene.penumbra.debug_view = "NONE"
    return image[6:].mean(axis=(0, 1))
