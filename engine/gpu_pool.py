"""Textures and compiled programs kept from one final render to the next.

Every F12 render, and every frame of an animation render, is a new engine instance. Without a
pool each one allocates its targets and its shadow atlas anew, and on llvmpipe a new texture
costs its zero-fill: about 17 ms for the 32 MiB atlas of the demo at 960x540 (two 2048 maps).

Only textures and programs are kept: render targets (``FINAL_RENDERS``) and compiled programs
(``final_shaders``: a variant compiles once a session, not once a render, about 7 ms a render
for the demo). Image textures need no pool: they are Blender's own, kept by each image
datablock between renders (``scene/textures.py``); meshes and their batches are kept by
content in the extension's store (``engine/store.py``). Textures and programs are shared
between GPU contexts, while framebuffers belong to the context that made them and are made
again by each render. A texture taken from the pool holds the last render's pixels; the
renderer clears or redraws all of it (its shadow maps start empty, so every map is drawn
again).

The pool holds what the last frame used, and at most ``budget`` bytes, oldest textures dropped
first. A frame is one (scene, frame number, resolution): its view layers and views share it. At
the end of each render (``end_render``) the pool drops every texture the current frame did not
give back, so a large frame's targets are freed as soon as a smaller frame (or a render with
fewer passes or maps) follows, and a run of equal frames holds one frame's textures. It is
emptied when the extension is unregistered (Blender disables add-ons on exit before it shuts
its GPU module down) and when the interpreter exits, so no texture outlives the GPU module.
"""

import atexit

# Bytes per texel of the formats the renderer allocates.
TEXEL_BYTES = {
    "RGBA32F": 16,
    "RGBA16F": 8,
    "RGBA8": 4,
    "R32F": 4,
    "R16F": 2,
    "DEPTH_COMPONENT32F": 4,
}

BUDGET = 256 * 2**20


def texture_bytes(texture):
    return texture.width * texture.height * TEXEL_BYTES.get(texture.format, 16)


class TexturePool:
    def __init__(self, budget=BUDGET):
        self.budget = budget
        self._held = []  # (width, height, format, texture), oldest first
        self.taken = 0  # textures handed out again (what the pool saved)
        self._frame_key = None  # what the current frame is (``begin_render``)
        self._frame = 0  # a number per frame; each held texture's is where it was last given
        self._given = {}  # id(texture) -> the frame number it was last given in

    def __len__(self):
        return len(self._held)

    @property
    def held_bytes(self):
        return sum(texture_bytes(t) for *_key, t in self._held)

    def take(self, size, fmt):
        """A held texture of ``size`` (width, height) and ``fmt``, or None."""
        width, height = size
        for i, (w, h, f, texture) in enumerate(self._held):
            if (w, h, f) == (width, height, fmt):
                del self._held[i]
                self.taken += 1
                return texture
        return None

    def give(self, textures):
        """Keep ``textures`` (None entries skipped) for a later render, within the budget. Call
        it where the caller would otherwise free them: inside the render's GPU context."""
        for texture in textures:
            if texture is None or texture_bytes(texture) > self.budget:
                continue  # larger than the whole pool: freed by the caller now
            if all(texture is not t for *_k, t in self._held):
                self._held.append((texture.width, texture.height, texture.format, texture))
            self._given[id(texture)] = self._frame
        while self._held and self.held_bytes > self.budget:
            self._held.pop(0)
        self._forget_dropped()

    def begin_render(self, frame_key):
        """A render of ``frame_key`` (scene, frame number, resolution) starts: a key other than
        the last one's begins a new frame."""
        if frame_key != self._frame_key:
            self._frame_key = frame_key
            self._frame += 1

    def end_render(self):
        """A render ended (its textures given back): drop every held texture the current frame
        did not give, inside the render's GPU context."""
        self._held = [entry for entry in self._held if self._given.get(id(entry[3])) == self._frame]
        self._forget_dropped()

    def _forget_dropped(self):
        held = {id(t) for *_k, t in self._held}
        self._given = {key: frame for key, frame in self._given.items() if key in held}

    def clear(self):
        self._held.clear()
        self._given.clear()


def new_texture(pool, size, fmt):
    """A ``gpu.types.GPUTexture`` of ``size`` and ``fmt``: from ``pool`` when it holds one."""
    import gpu

    texture = pool.take(size, fmt) if pool is not None else None
    return texture if texture is not None else gpu.types.GPUTexture(size, format=fmt)


FINAL_RENDERS = TexturePool()  # the pool of F12 and animation renders (never the viewport's)
_final_shaders = []  # the ShaderCache final renders share, made on first use


def final_shaders():
    """The ``ShaderCache`` every final render shares."""
    if not _final_shaders:
        from ..shaders.loader import ShaderCache

        _final_shaders.append(ShaderCache())
    return _final_shaders[0]


def clear():
    """Drop every pooled texture and program (on unregister, and at exit)."""
    FINAL_RENDERS.clear()
    _final_shaders.clear()


atexit.register(clear)


class UniformBlocks:
    """Named uniform blocks of one owner (a pass), each made on first use and updated in place
    after (made anew when its size changes). Unlike textures they are not pooled: they are
    small, and each pass keeps its own between frames."""

    def __init__(self):
        self._blocks = {}  # name -> (GPUUniformBuf, its size in bytes, the bytes it holds)

    def get(self, name, raw):
        """The block ``name`` holding ``raw`` (bytes)."""
        import gpu

        block = self._blocks.get(name)
        if block is None or block[1] != len(raw):
            block = (gpu.types.GPUUniformBuf(raw), len(raw), raw)
        else:
            block[0].update(raw)
            block = (block[0], block[1], raw)
        self._blocks[name] = block
        return block[0]

    def holding(self, name, raw):
        """The block ``name`` when it holds ``raw`` already (nothing to upload), else None."""
        block = self._blocks.get(name)
        return block[0] if block is not None and block[2] == raw else None

    def peek(self, name):
        """The block ``name`` as last set, or None."""
        block = self._blocks.get(name)
        return None if block is None else block[0]

    def clear(self):
        self._blocks = {}
