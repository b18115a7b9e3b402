"""Rendering helpers shared by the tests."""

import os
import tempfile

import bpy
import numpy as np
import OpenImageIO as oiio


_CHANNEL_ORDER = "RGBAVXYZ"


def read_exr(path):
    """{pass name: float32 array (h, w, channels)} of a (multilayer, multi-part) EXR, top row
    first. Blender writes each pass of a multilayer EXR as its own part (an OIIO subimage)."""
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise RuntimeError(oiio.geterror())
    passes = {}
    sub = 0
    while inp.seek_subimage(sub, 0):
        spec = inp.spec()
        pixels = np.asarray(inp.read_image(sub, 0, 0, spec.nchannels, oiio.FLOAT), np.float32)
        groups = {}
        for i, name in enumerate(spec.channelnames):
            parts = name.split(".")
            groups.setdefault(parts[-2] if len(parts) >= 2 else "Combined", []).append(i)
        for key, idx in groups.items():
            # Files may store channels alphabetically (A, B, G, R): put them in RGBA order.
            idx.sort(key=lambda i: _CHANNEL_ORDER.find(spec.channelnames[i].split(".")[-1]))
            passes[key] = pixels[:, :, idx]
        sub += 1
    inp.close()
    return passes


def set_multilayer_exr(settings):
    """Multilayer EXR output on Blender 4.5 (a file format) and 5.x (a media type)."""
    if hasattr(settings, "media_type"):
        settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"


def render(scene=None, passes=("Combined",)):
    """Render ``scene`` with its engine through Blender's own output path (the same file a
    batch render writes); return {pass: array (h, w, c)} flipped so row 0 is the bottom of the
    image (the orientation of GPU textures and Blender's pixel buffers)."""
    scene = scene or bpy.context.scene
    scene.view_layers[0].use_pass_z = "Depth" in passes
    settings = scene.render.image_settings
    set_multilayer_exr(settings)
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
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
    return {k: v[::-1] for k, v in data.items()}
