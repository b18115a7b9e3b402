"""Image files: reading through OpenImageIO, and Blender's output formats set the same way on
Blender 4.5 (the file format decides) and 5.x (a media type, then the file format)."""

import numpy as np
import OpenImageIO as oiio

_CHANNEL_ORDER = "RGBAVXYZ"


def read_exr(path):
    """{pass name: float32 array (h, w, channels)} of a (multilayer, multi-part) EXR, top row
    first. Blender writes each pass of a multilayer EXR as its own part (an OIIO subimage); a
    single-layer EXR is one pass, "Combined"."""
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise RuntimeError(oiio.geterror())
    passes = {}
    sub = 0
    try:
        while inp.seek_subimage(sub, 0):
            spec = inp.spec()
            pixels = np.asarray(inp.read_image(sub, 0, 0, spec.nchannels, oiio.FLOAT), np.float32)
            groups = {}
            for i, name in enumerate(spec.channelnames):
                parts = name.split(".")
                groups.setdefault(parts[-2] if len(parts) >= 2 else "Combined", []).append(i)
            for key, idx in groups.items():
                # Files may store channels alphabetically (A, B, G, R): put them in RGBA order.
                idx.sort(key=lambda i: _CHANNEL_ORDER.find(spec.channelnames[i].split(".")[-1].upper()))
                passes[key] = pixels[:, :, idx]
            sub += 1
    finally:
        inp.close()
    return passes


def write_png(path, pixels):
    """Write display-referred ``pixels`` (h, w, channels) in 0..1, top row first, as an 8-bit
    PNG."""
    pixels = np.ascontiguousarray(np.clip(pixels, 0.0, 1.0), np.float32)
    h, w, c = pixels.shape
    buf = oiio.ImageBuf(oiio.ImageSpec(w, h, c, oiio.UINT8))
    buf.set_pixels(oiio.ROI(0, w, 0, h, 0, 1, 0, c), pixels)
    if not buf.write(str(path)):
        raise RuntimeError(buf.geterror())


def read_image(path):
    """Pixels of any image file OpenImageIO reads (PNG, EXR, ...) as float32 (h, w, channels),
    top row first; 8-bit values become 0..1."""
    buf = oiio.ImageBuf(str(path))
    if buf.has_error:
        raise RuntimeError(buf.geterror())
    return np.asarray(buf.get_pixels(oiio.FLOAT), np.float32)


def set_format(settings, file_format, color_depth=None, exr_codec=None):
    """Set Blender image settings (``scene.render.image_settings``) to ``file_format``
    ('PNG', 'OPEN_EXR', 'OPEN_EXR_MULTILAYER', ...) on 4.5 and 5.x alike."""
    if hasattr(settings, "media_type"):  # Blender 5.x
        settings.media_type = "MULTI_LAYER_IMAGE" if file_format == "OPEN_EXR_MULTILAYER" else "IMAGE"
    settings.file_format = file_format
    if color_depth is not None:
        settings.color_depth = color_depth
    if exr_codec is not None:
        settings.exr_codec = exr_codec
    return settings


def set_multilayer_exr(settings):
    """Multilayer EXR output on Blender 4.5 (a file format) and 5.x (a media type)."""
    return set_format(settings, "OPEN_EXR_MULTILAYER")


def save_render(scene, path, file_format, color_depth):
    """Save the last render ("Render Result") to ``path`` through Blender's colour management
    and output settings, as F12's Image › Save does."""
    import bpy

    set_format(scene.render.image_settings, file_format, color_depth)
    bpy.data.images["Render Result"].save_render(str(path), scene=scene)


def read_exr_layers(path):
    """{(view layer, view): {pass: float32 array (h, w, channels)}} of a multilayer EXR, top row
    first; view is "" for a mono render. Blender 5.x writes one part per pass and view (the
    view in the part's "view" attribute); 4.5 one part with channels "layer.pass[.view].C"."""
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise RuntimeError(oiio.geterror())
    out = {}
    sub = 0
    try:
        while inp.seek_subimage(sub, 0):
            spec = inp.spec()
            part_view = spec.getattribute("view") or ""
            pixels = np.asarray(inp.read_image(sub, 0, 0, spec.nchannels, oiio.FLOAT), np.float32)
            groups = {}
            for i, name in enumerate(spec.channelnames):
                parts = name.split(".")
                layer, pass_name = parts[0], parts[1]
                view = parts[2] if len(parts) == 4 else part_view
                groups.setdefault((layer, view, pass_name), []).append(i)
            for (layer, view, pass_name), idx in groups.items():
                idx.sort(key=lambda i: _CHANNEL_ORDER.find(spec.channelnames[i].split(".")[-1].upper()))
                out.setdefault((layer, view), {})[pass_name] = pixels[:, :, idx]
            sub += 1
    finally:
        inp.close()
    return out
