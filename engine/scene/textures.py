"""Image textures on the GPU: Blender's own (``gpu.texture.from_image``).

Blender uploads every image once for EEVEE and the viewport, colour-managed (sRGB bytes as an
sRGB texture the GPU decodes, other colour spaces converted to scene linear, Non-Color as it
is), reduced to the GPU's limit and with its mipmaps. Penumbra draws from that texture, so no
image is read into Python or hashed: the first frame that needs an image costs what Blender's
upload costs, later frames (and later F12 renders, since the texture belongs to the image
datablock) nothing. A texture is looked up once per image datablock and kept until a depsgraph
update says its image changed (``SceneCache.images_changed``: edited, reloaded, packed, a
generated image changed), when Blender has made a new one.

What Blender's texture holds that the Image Texture node does not output is undone in the
shader: a float image whose alpha mode is not Straight is stored premultiplied
(``premultiplied``), and ``shaders/lib/material.glsl`` divides by alpha after filtering. An
image without pixels (a missing file) draws as Blender's error texture, magenta, with a
message; an image larger than the GPU's textures is drawn reduced, with a message; a UDIM
image draws its first tile, with a message.

The world's Environment Texture lights the scene through order-2 spherical harmonics
(``materials.equirect_sh``); they are projected from a small mip level of the same texture,
read back from the GPU (``world_sh``), never from the image's pixels.
"""

import numpy as np

from .geometry import content_key
from .materials import SH_C0, equirect_sh

# Bytes per texel of the formats Blender gives image textures (mipmaps add a third).
FORMAT_BYTES = {"SRGB8_A8": 4, "RGBA8": 4, "RGBA16F": 8, "RGBA32F": 16, "R16F": 2, "R32F": 4, "R8": 1}

# The world's light is projected from a mip level at most this wide (and half as high): order-2
# harmonics vary slowly, so a 128x64 image holds all they can show of an environment.
SH_WIDTH = 128


def stores_premultiplied(image):
    """Whether Blender's GPU texture of ``image`` holds premultiplied colour: float buffers are
    kept premultiplied unless the image's alpha mode is Straight, byte buffers straight."""
    return bool(image.is_float) and image.alpha_mode != "STRAIGHT"


class TextureCache:
    def __init__(self, store=None):
        self.store = store  # the extension's ``store.Store`` (final renders): prefiltered worlds kept by content
        self.prefilters = 0  # prefiltered environments built (not found here or in the store) since creation
        self._textures = {}  # image name -> (GPUTexture, premultiplied)
        self._sh = {}  # image name -> its equirectangular SH (9, 3), strength 1
        self._env = {}  # image name -> the image box-filtered as the SH saw it (h, w, 3), strength 1
        self._read = {}  # image name -> digest of that read-back, as read (``_content``)
        self._prefiltered = {}  # (image name, clamp) -> (its prefiltered atlas, bytes) (``world_prefiltered``)
        self.uploads = 0  # images taken from Blender since creation (tests and the benchmark read it)
        self.upload_bytes = 0  # bytes of those Blender made a texture of for them (``_first_take``)
        self.bytes = 0
        self._messages = {}  # image name -> what the user must be told of it (``messages``)

    def forget(self, names):
        for name in names:
            _TAKEN.difference_update([k for k in _TAKEN if k[1] == name])
            entry = self._textures.pop(name, None)
            self._sh.pop(name, None)
            self._env.pop(name, None)
            self._read.pop(name, None)
            for key in [k for k in self._prefiltered if k[0] == name]:
                self.bytes -= self._prefiltered.pop(key)[1]
            self._messages.pop(name, None)
            if entry is not None:
                self.bytes -= _texture_bytes(entry[0])

    def clear(self):
        self._textures.clear()
        self._sh.clear()
        self._env.clear()
        self._read.clear()
        self._prefiltered.clear()
        self._messages.clear()
        self.bytes = 0

    def get(self, name):
        """The GPU texture of image ``name``."""
        return self._entry(name)[0]

    def premultiplied(self, name):
        """Whether the texture of image ``name`` holds premultiplied colour."""
        return self._entry(name)[1]

    def _entry(self, name):
        entry = self._textures.get(name)
        if entry is None:
            entry = self._textures[name] = self._take(name)
            self.bytes += _texture_bytes(entry[0])
        return entry

    def _take(self, name):
        import bpy
        import gpu

        image = bpy.data.images.get(name)
        if image is None:
            self._messages[name] = f"Penumbra: image '{name}' not found: drawn magenta"
            return _missing_texture(), False
        made = _first_take(image)
        texture = gpu.texture.from_image(image)
        self.uploads += 1
        if not image.has_data:
            # Blender's error texture (a file it could not read): magenta, as in its own engines.
            self._messages[name] = f"Penumbra: image '{name}' has no pixels (missing file?): drawn magenta"
            return _missing_texture(), False
        w, h = image.size
        if texture.width < w or texture.height < h:
            self._messages[name] = (
                f"Penumbra: image '{name}' ({w}x{h}) is larger than this GPU's textures: drawn at "
                f"{texture.width}x{texture.height}"
            )
        if image.source == "TILED" and len(image.tiles) > 1:
            self._messages[name] = (
                f"Penumbra: image '{name}' has UDIM tiles: only tile {image.tiles[0].number} is drawn"
            )
        if made:
            self.upload_bytes += _texture_bytes(texture)
        return texture, stores_premultiplied(image)

    def world_sh(self, name, reduce):
        """The SH (9, 3) of image ``name`` as an equirectangular environment of strength 1:
        ``reduce(texture, premultiplied, width, height)`` draws the texture at most
        ``SH_WIDTH`` wide on the GPU and returns it (height, width, 4); kept until the image
        changes."""
        sh = self._sh.get(name)
        if sh is None:
            texture, premultiplied = self._entry(name)
            width = max(1, min(SH_WIDTH, texture.width))
            height = max(1, min(SH_WIDTH // 2, texture.height))
            rgba = np.nan_to_num(np.asarray(reduce(texture, premultiplied, width, height), np.float64))
            self._read[name] = content_key(np.ascontiguousarray(rgba, np.float32))
            env = self._env[name] = np.clip(rgba[..., :3], 0.0, None)
            sh = self._sh[name] = equirect_sh(env)
        return sh

    def world_prefiltered(self, name, clamp, build, size):
        """The prefiltered environment of image ``name`` (``world/prefilter.py``), its source
        clamped to ``clamp``: ``build(texture, premultiplied)`` makes it, ``size`` its bytes;
        kept until the image changes. At most two clamps an image are kept."""
        key = (name, float(clamp))
        entry = self._prefiltered.get(key)
        if entry is None:
            for old in [k for k in self._prefiltered if k[0] == name][1:]:
                self.bytes -= self._prefiltered.pop(old)[1]
            texture, premultiplied = self._entry(name)
            content = self._content(name, texture, premultiplied, clamp)
            atlas = None if content is None else self.store.get("world", content)
            if atlas is None:
                atlas = build(texture, premultiplied)
                self.prefilters += 1
                if content is not None:
                    self.store.put("world", content, atlas, int(size))
            entry = self._prefiltered[key] = (atlas, int(size))
            self.bytes += entry[1]
        return entry[0]

    def _content(self, name, texture, premultiplied, clamp):
        """What a prefiltered environment of image ``name`` is kept by in the store (final
        renders), or None: the digest of the image as ``world_sh`` read it back from Blender's
        texture (box-filtered to at most SH_WIDTH x SH_WIDTH/2, float32 RGBA: an edit of the
        pixels changes some box's sum), with the texture's size and format and the clamp. Every
        F12 reads that back for the world's SH light anyway; the prefilter (a GPU pass over
        every level) is not made again for the same image."""
        read = self._read.get(name)
        if self.store is None or read is None:
            return None
        header = repr((name, read, texture.width, texture.height, texture.format, bool(premultiplied), float(clamp)))
        return content_key(np.frombuffer(header.encode(), np.uint8))

    def world_env(self, name):
        """The image ``name`` box-filtered as ``world_sh`` projected it (h, w, 3), row 0 at the
        bottom, strength 1: what the world's directions are drawn from
        (``frame/world/directions.py``). None before ``world_sh``."""
        return self._env.get(name)

    def messages(self):
        """What the user must be told of the images taken so far (until they change)."""
        return list(self._messages.values())


# (session uid, name) of the images whose texture this session has taken, until they change:
# Blender keeps an image's texture on the datablock, so only a first take uploads its pixels.
_TAKEN = set()


def _first_take(image):
    """Whether Blender makes ``image``'s texture for this take: its first in this session, or
    the first since a depsgraph update said the image changed (``TextureCache.forget``).
    Blender 4.5 tells directly (``Image.bindcode`` 0: no texture yet); 5.x does not say."""
    key = (getattr(image, "session_uid", 0), image.name_full)
    first = key not in _TAKEN
    _TAKEN.add(key)
    bindcode = getattr(image, "bindcode", None)
    return first if bindcode is None else bindcode == 0


def world_background(sh):
    """The colour behind the scene of a world whose light is ``sh``: its mean."""
    return sh[0] * SH_C0


def _texture_bytes(texture):
    return texture.width * texture.height * FORMAT_BYTES.get(texture.format, 16) * 4 // 3


def _missing_texture():
    import gpu

    data = gpu.types.Buffer("FLOAT", 4, [1.0, 0.0, 1.0, 1.0])
    return gpu.types.GPUTexture((1, 1), format="RGBA16F", data=data)
