"""Image textures on the GPU, uploaded once per image datablock.

Pixels are read with ``foreach_get`` (``materials.image_pixels``: scene-linear, straight
alpha, as the Image Texture node outputs them) and uploaded as RGBA16F; a texture stays until
a depsgraph update says its image changed (``SceneCache.images_changed``) or it is no longer
used. Final renders (a new engine each) also share textures between renders through
``gpu_pool.FINAL_IMAGES``, by ``content_key``: an animation render converts and uploads each
image once. A missing or unreadable image draws as magenta, Blender's own colour for a missing
texture, with a message.
"""

import hashlib
import sys

import numpy as np

from .materials import image_pixels

MISSING = (1.0, 0.0, 1.0, 1.0)


def raw_pixels(image):
    """``image.pixels`` as a float32 array (Blender's own buffer, about 2 ms a megapixel), or
    None when it has none or cannot be read."""
    w, h = image.size
    if w == 0 or h == 0 or image.channels == 0:
        return None
    data = np.empty(w * h * image.channels, np.float32)
    try:
        image.pixels.foreach_get(data)
    except (RuntimeError, ValueError):
        return None
    return data


def content_key(image, data):
    """What the texture of ``image`` with pixels ``data`` depends on: its pixels themselves
    (SHA-1, about 8 ms for a 1024x1024 RGBA image, against about 35 ms to convert and upload
    it) and how they are read (size, channels, float or byte, colour space, alpha mode). Any
    change of pixels, saved or not, makes another key; two images alike share one texture."""
    cs = image.colorspace_settings
    digest = hashlib.sha1(data.data, usedforsecurity=False).digest()
    how = (tuple(image.size), image.channels, image.is_float, cs.name, cs.is_data, image.alpha_mode)
    return (*how, digest)


class TextureCache:
    def __init__(self, shared=None):
        self._textures = {}  # image name -> GPUTexture
        self._shared = shared  # gpu_pool.ImageTextures of final renders, or None (the viewport)
        self.uploads = 0  # images read and uploaded since creation (tests and the benchmark read it)
        self.bytes = 0

    def forget(self, names):
        for name in names:
            tex = self._textures.pop(name, None)
            if tex is not None:
                self.bytes -= tex.width * tex.height * 8

    def clear(self):
        self._textures.clear()
        self.bytes = 0

    def get(self, name):
        tex = self._textures.get(name)
        if tex is None:
            key = data = None
            if self._shared is not None:
                import bpy

                image = bpy.data.images.get(name)
                data = raw_pixels(image) if image is not None else None
                key = content_key(image, data) if data is not None else None
                tex = self._shared.get(key) if key is not None else None
            if tex is None:
                tex = self._upload(name, data)
                if key is not None:
                    self._shared.put(key, tex)
            self._textures[name] = tex
            self.bytes += tex.width * tex.height * 8
        return tex

    def _upload(self, name, data=None):
        import bpy
        import gpu

        image = bpy.data.images.get(name)
        pixels = None
        if image is not None:
            try:
                pixels = image_pixels(image, data)
            except (RuntimeError, ValueError) as exc:
                print(f"Penumbra: image '{name}' could not be read: {exc}", file=sys.stderr)
        if pixels is None:
            print(f"Penumbra: image '{name}' has no pixels (missing file?): drawn magenta", file=sys.stderr)
            pixels = np.array(MISSING, np.float32).reshape(1, 1, 4)
        if image is not None and image.is_float:  # byte images cannot hold NaN/Inf
            pixels = np.nan_to_num(pixels, nan=0.0, posinf=65504.0, neginf=-65504.0)
        pixels = np.ascontiguousarray(pixels, np.float32)
        h, w = pixels.shape[:2]
        limit = gpu.capabilities.max_texture_size_get()
        if w > limit or h > limit:
            step = int(np.ceil(max(w, h) / limit))
            pixels = np.ascontiguousarray(pixels[::step, ::step])
            print(
                f"Penumbra: image '{name}' ({w}x{h}) is larger than this GPU's textures: every {step}th pixel is used",
                file=sys.stderr,
            )
            h, w = pixels.shape[:2]
        buf = gpu.types.Buffer("FLOAT", pixels.size, pixels.ravel())
        tex = gpu.types.GPUTexture((w, h), format="RGBA16F", data=buf)
        self.uploads += 1
        return tex
