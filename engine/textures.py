"""Image textures on the GPU, uploaded once per image datablock.

Pixels are read with ``foreach_get`` (``materials.image_pixels``: scene-linear, straight
alpha, as the Image Texture node outputs them) and uploaded as RGBA16F; a texture stays until
a depsgraph update says its image changed (``SceneCache.images_changed``) or it is no longer
used. A missing or unreadable image draws as magenta, Blender's own colour for a missing
texture, with a message.
"""

import sys

import numpy as np

from .materials import image_pixels

MISSING = (1.0, 0.0, 1.0, 1.0)


class TextureCache:
    def __init__(self):
        self._textures = {}  # image name -> GPUTexture
        self.uploads = 0  # images uploaded since creation (tests and the benchmark read it)
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
            tex = self._textures[name] = self._upload(name)
        return tex

    def _upload(self, name):
        import bpy
        import gpu

        image = bpy.data.images.get(name)
        pixels = None
        if image is not None:
            try:
                pixels = image_pixels(image)
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
        self.bytes += w * h * 8
        return tex
