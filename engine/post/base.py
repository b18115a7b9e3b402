"""The post stack's shared machinery: the effect interface, render targets, the stack."""

import hashlib
from collections import namedtuple
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from ...shaders.loader import Program, Struct, set_uniforms
from ..gpu_pool import new_texture
from ..settings import scale_pixels, values
from ..shadows import kernels

# One layer of a frame's stack, as the renderer receives it (``params``: a namespace of the
# effect's parameter values, or None for a disabled layer).
Layer = namedtuple("Layer", ("effect", "enabled", "mix", "params"))


def post_program(name, fragment, push_constants=(), samplers=(), uniform_blocks=(), defines=()):
    """A full-screen program; every post fragment shader gets ``source_tex``, ``mix_factor``
    and ``target_size``. ``defines``: constants every variant gets (e.g. an enum's values)."""
    return Program(
        name=name,
        vertex="fullscreen.vert.glsl",
        fragment=fragment,
        libs=("lib/common.glsl", "lib/post_common.glsl"),
        vertex_in=(("VEC2", "pos"),),
        push_constants=(("FLOAT", "mix_factor"), ("VEC2", "target_size")) + tuple(push_constants),
        samplers=(("FLOAT_2D", "source_tex"),) + tuple(samplers),
        uniform_blocks=tuple(uniform_blocks),
        defines=tuple(dict(defines).items()),
    )


class PostEffect:
    """Base of every effect. Subclasses set the class attributes and implement ``execute``.

    ``execute`` receives parameters already clamped to their declared ranges (``values``), so
    an effect never repeats a ``Param``'s limits."""

    id = ""
    label = ""
    icon = "NONE"
    description = ""
    params = ()

    def is_identity(self, params):
        """True when these parameters leave the image unchanged, so the layer costs no pass."""
        return False

    def execute(self, ctx, src, params, mix):
        raise NotImplementedError

    @classmethod
    def defaults(cls):
        return SimpleNamespace(**{p.name: p.default for p in cls.params})

    @classmethod
    def values(cls, source):
        """The parameters read from ``source`` (a layer's PropertyGroup or a namespace),
        clamped to their declared ranges, enum ids validated."""
        return SimpleNamespace(**values(cls.params, source))


# Per-pixel layers (``PointEffect``): a run of consecutive ones shares one full-screen pass.
# Each layer has POINT_SLOTS vec4s of a uniform block; the last one's w is the layer's mix.
FUSE_POINT_LAYERS = True  # False: one pass per layer (tests and the benchmark compare the two)
MAX_POINT_LAYERS = 8  # layers one pass takes; a longer run is split
POINT_SLOTS = 4
POINT_DATA = Struct("PointData", (("VEC4", "v"),))
POINT_PROGRAM = post_program(
    "post_point",
    "post/point.frag.glsl",
    uniform_blocks=((POINT_DATA, "point", MAX_POINT_LAYERS * POINT_SLOTS),),
)  # its libraries (every point effect's function) are added by ``point_program``


def point_program(effects):
    """POINT_PROGRAM with the GLSL libraries of ``effects`` (PointEffect subclasses)."""
    from dataclasses import replace

    libs = tuple(dict.fromkeys(cls.point_glsl for cls in effects))
    return replace(POINT_PROGRAM, libs=POINT_PROGRAM.libs + libs)


def point_words(*values):
    """A layer's data: up to POINT_SLOTS * 4 - 1 words (the last is its mix), float32 or, for
    a Python int (not a bool), the int32 bit pattern the shader reads with floatBitsToInt."""
    if len(values) > POINT_SLOTS * 4 - 1:
        raise ValueError(f"{len(values)} words: a point layer has {POINT_SLOTS * 4 - 1}")
    data = np.zeros(POINT_SLOTS * 4, np.float32)
    ints = data.view(np.int32)
    for i, v in enumerate(values):
        if isinstance(v, int | np.integer) and not isinstance(v, bool | np.bool_):
            ints[i] = int(v)
        else:
            data[i] = float(v)
    return data


class PointEffect(PostEffect):
    """A layer whose output at a pixel depends only on its input there (and the pixel's
    position, the frame's size and number): consecutive ones run in one pass.

    ``point_glsl`` declares ``vec4 <point_function>(vec4 c, int o)``: the effect of the layer
    on the sanitised colour ``c``, its data at ``point[o] ... point[o + POINT_SLOTS - 1]``
    (written by ``point_data``, which returns ``point_words(...)``). The mix is applied around
    it exactly as ``post_mix`` does."""

    point_glsl = ""
    point_function = ""

    def point_data(self, ctx, params):
        raise NotImplementedError

    def execute(self, ctx, src, params, mix):
        return ctx.point_pass(src, [(self, params, mix)])


# Normalised 1-D Gaussian weights as a uniform block, shared by the blurring effects.
GAUSSIAN_MAX_RADIUS = 256
GAUSSIAN_WEIGHTS = Struct("GaussianWeights", (("VEC4", "w"),))
GAUSSIAN_VEC4S = (2 * GAUSSIAN_MAX_RADIUS + 1 + 3) // 4


class GaussianWeights:
    """The uniform buffer of ``kernels.gaussian_1d(radius, sigma)``, re-uploaded only when the
    kernel changes. Owned by one effect instance."""

    def __init__(self):
        self._ubo = None
        self._key = None

    def get(self, radius, sigma=None):
        import gpu

        radius = min(int(radius), GAUSSIAN_MAX_RADIUS)
        key = (radius, sigma)
        if key != self._key:
            packed = np.zeros(GAUSSIAN_VEC4S * 4, np.float32)
            w = kernels.gaussian_1d(radius, sigma)
            packed[: len(w)] = w
            if self._ubo is None:
                self._ubo = gpu.types.GPUUniformBuf(packed.tobytes())
            else:
                self._ubo.update(packed.tobytes())
            self._key = key
        return self._ubo


def half_size_mean(img):
    """Reference of a half-size pass, numpy-ready: each pixel of the ((h + 1) // 2,
    (w + 1) // 2) image is the mean of the 2x2 pixels of ``img`` (h, w, c) it covers that
    exist (one or two at odd edges), in float64."""
    img = np.asarray(img, np.float64)
    h, w, c = img.shape
    hh, hw = (h + 1) // 2, (w + 1) // 2
    sums = np.zeros((2 * hh, 2 * hw, c))
    counts = np.zeros((2 * hh, 2 * hw, 1))
    sums[:h, :w], counts[:h, :w] = img, 1.0
    return sums.reshape(hh, 2, hw, 2, c).sum(axis=(1, 3)) / counts.reshape(hh, 2, hw, 2, 1).sum(axis=(1, 3))


def bilinear_up(small, h, w):
    """Reference of reading a half-size image back at full size, numpy-ready: ``small``
    bilinearly at each of the (h, w) pixel centres, clamped to its edge texels, in float64."""
    small = np.asarray(small, np.float64)
    hh, hw = small.shape[:2]
    ty = np.clip((np.arange(h) + 0.5) * 0.5 - 0.5, 0.0, hh - 1)
    tx = np.clip((np.arange(w) + 0.5) * 0.5 - 0.5, 0.0, hw - 1)
    y0, x0 = np.floor(ty).astype(int), np.floor(tx).astype(int)
    y1, x1 = np.minimum(y0 + 1, hh - 1), np.minimum(x0 + 1, hw - 1)
    fy, fx = (ty - y0)[:, None, None], (tx - x0)[None, :, None]
    rows0 = small[y0][:, x0] * (1 - fx) + small[y0][:, x1] * fx
    rows1 = small[y1][:, x0] * (1 - fx) + small[y1][:, x1] * fx
    return rows0 * (1 - fy) + rows1 * fy


def table_texture(rgb):
    """An RGBA32F texture of a built-in table: ``rgb`` is (height, width, 3), or (width, 3) for
    one row; alpha is 1."""
    rgb = np.asarray(rgb, np.float32)
    if rgb.ndim == 2:
        rgb = rgb[None]
    h, w = rgb.shape[:2]
    return rgba_texture(np.concatenate([rgb, np.ones((h, w, 1), np.float32)], axis=-1))


# A user's lookup image (COLORIZER's LUT, LENS_FLARE's dirt) of at most this many texels is
# drawn from a float table of its pixels, read and hashed each frame (about a millisecond at
# 512 x 512); a larger one from Blender's own texture of it.
IMAGE_TABLE_TEXELS = 1 << 18


def srgb_to_linear(c):
    """The sRGB transfer function decoded (IEC 61966-2-1), as Blender's sRGB textures decode."""
    c = np.asarray(c, np.float32)
    return np.where(c <= 0.04045, c / 12.92, ((np.maximum(c, 0.04045) + 0.055) / 1.055) ** 2.4).astype(np.float32)


def image_pixels(image):
    """``image``'s pixels as Blender's GPU texture of it holds them: (height, width, 4) float32,
    row 0 at the bottom. Float images as stored (scene linear), byte images in sRGB decoded,
    Non-Color and linear byte images as they are. None where numpy cannot give that (another
    colour space, no pixels, more than IMAGE_TABLE_TEXELS texels)."""
    w, h = image.size
    if not image.has_data or w * h == 0 or w * h > IMAGE_TABLE_TEXELS:
        return None
    space = image.colorspace_settings
    linear = space.is_data or space.name.startswith("Linear Rec.709") or space.name in ("Non-Color", "Raw")
    decode = not image.is_float and space.name == "sRGB"
    if not (linear or decode):
        return None
    pixels = np.empty(w * h * 4, np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(h, w, 4)
    if decode:
        pixels[..., :3] = srgb_to_linear(pixels[..., :3])
    return pixels


def image_or_table(image, cache, table):
    """The texture of a user's Image, or of the built-in ``table`` when there is none; ``cache``
    is a dict owned by the effect instance. A user's image becomes Penumbra's own RGBA32F table
    of its pixels (``image_pixels``), uploaded again only when they change: the lookup reads
    the same values on every GPU, whatever format and filtering Blender's own texture of the
    image takes there. An image numpy cannot convert is drawn from Blender's texture."""
    import gpu

    if image is None:
        if "table" not in cache:
            cache["table"] = table_texture(table)
        return cache["table"]
    pixels = image_pixels(image)
    if pixels is None:
        return gpu.texture.from_image(image)
    key = (image.name, pixels.shape, hashlib.sha256(np.ascontiguousarray(pixels).data).digest())
    if cache.get("image", (None,))[0] != key:
        cache["image"] = (key, rgba_texture(pixels))
    return cache["image"][1]


def rgba_texture(rgba):
    """An RGBA32F texture of (height, width, 4) float32 ``rgba``, row 0 at the bottom."""
    import gpu

    rgba = np.ascontiguousarray(rgba, np.float32)
    h, w = rgba.shape[:2]
    buf = gpu.types.Buffer("FLOAT", rgba.size, rgba.ravel())
    return gpu.types.GPUTexture((w, h), format="RGBA32F", data=buf)


@dataclass
class Target:
    texture: object
    framebuffer: object


@dataclass
class PostContext:
    """Render targets, shaders and counters shared by the layers of one frame."""

    shaders: object
    width: int
    height: int
    frame: int = 0
    stats: object = None
    pixel_scale: float = 1.0  # sizes in pixels are scaled by this (the resolution %)
    texture_pool: object = None  # gpu_pool.TexturePool the targets' textures come from (final renders)
    _pool: list = field(default_factory=list)
    _batch: object = None
    _point_ubos: list = field(default_factory=list)  # one per point pass of a frame
    _point_next: int = 0

    def acquire(self, *busy, size=None):
        """A float target of the frame's size (or ``size``, (width, height)) whose texture is
        none of ``busy``."""
        import gpu

        size = (self.width, self.height) if size is None else (max(1, int(size[0])), max(1, int(size[1])))
        busy_ids = {id(t) for t in busy}
        for target in self._pool:
            if id(target.texture) not in busy_ids and (target.texture.width, target.texture.height) == size:
                return target
        tex = new_texture(self.texture_pool, size, "RGBA32F")
        target = Target(tex, gpu.types.GPUFrameBuffer(color_slots=(tex,)))
        self._pool.append(target)
        return target

    @property
    def memory_bytes(self):
        return sum(t.texture.width * t.texture.height * 16 for t in self._pool)

    def release(self):
        """Give the targets' textures to ``texture_pool`` and free the point passes' uniform
        buffers (inside the GPU context)."""
        self._point_ubos.clear()
        if self.texture_pool is not None:
            textures = [t.texture for t in self._pool]
            self._pool.clear()
            self.texture_pool.give(textures)

    def single_pass(self, program, src, mix, uniforms=None, samplers=None, blocks=None, defines=None):
        """The common one-pass layer: read ``src``, blend by ``mix``, write a fresh target."""
        return self.fullscreen(
            program,
            self.acquire(src),
            defines=defines,
            samplers={"source_tex": src, **(samplers or {})},
            uniforms={"mix_factor": mix, **(uniforms or {})},
            blocks=blocks,
        )

    def point_pass(self, src, layers):
        """One pass of consecutive point layers ``layers`` ([(PointEffect, params, mix)], at
        most MAX_POINT_LAYERS) over ``src``; returns the new texture."""
        import gpu

        data = np.zeros((MAX_POINT_LAYERS * POINT_SLOTS, 4), np.float32)
        defines = {"POINT_COUNT": len(layers)}
        for i, (effect, params, mix) in enumerate(layers):
            words = effect.point_data(self, params)
            words[-1] = min(float(mix), 1.0)
            data[i * POINT_SLOTS : (i + 1) * POINT_SLOTS] = words.reshape(POINT_SLOTS, 4)
            defines[f"POINT_FN_{i}"] = effect.point_function
        index = self._point_next
        self._point_next += 1
        if index < len(self._point_ubos):
            self._point_ubos[index].update(data.tobytes())
        else:
            self._point_ubos.append(gpu.types.GPUUniformBuf(data.tobytes()))
        program = point_program(type(e) for e, _p, _m in layers)
        return self.fullscreen(
            program,
            self.acquire(src),
            defines=defines,
            samplers={"source_tex": src},
            blocks={"point": self._point_ubos[index]},
        )

    def half_size(self, program, src, mix, steps, up, blocks=None):
        """A layer drawn at half size: each of ``steps`` ([(defines, uniforms)]) a pass into a
        half-size target reading the one before (``input_tex``; the first reads ``src``),
        then ``up`` (defines, uniforms) back at full size, blended by ``mix``. Every pass also
        sees ``src`` as ``source_tex``."""
        half = ((src.width + 1) // 2, (src.height + 1) // 2)
        image = src
        for defines, uniforms in steps:
            target = self.acquire(image, size=half)  # two half-size targets in turn
            image = self.fullscreen(
                program,
                target,
                defines=defines,
                samplers={"source_tex": src, "input_tex": image},
                uniforms={**uniforms, "mix_factor": 1.0},
                blocks=blocks,
            )
        defines, uniforms = up
        return self.fullscreen(
            program,
            self.acquire(src),
            defines=defines,
            samplers={"source_tex": src, "input_tex": image},
            uniforms={**uniforms, "mix_factor": mix},
            blocks=blocks,
        )

    def fullscreen(self, program, target, defines=None, samplers=None, uniforms=None, blocks=None):
        """Draw one full-screen pass of ``program`` into ``target`` (over all of it, whatever
        its size)."""
        import gpu
        from gpu_extras.batch import batch_for_shader

        shader = self.shaders.get(program, defines)
        if self._batch is None:
            self._batch = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
        width, height = target.texture.width, target.texture.height
        with target.framebuffer.bind():
            gpu.state.viewport_set(0, 0, width, height)
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set("NONE")
            shader.bind()
            set_uniforms(shader, {"target_size": (float(width), float(height)), **(uniforms or {})})
            for name, tex in (samplers or {}).items():
                shader.uniform_sampler(name, tex)
            for name, ubo in (blocks or {}).items():
                shader.uniform_block(name, ubo)
            self._batch.draw(shader)
        if self.stats is not None:
            self.stats.passes += 1
            self.stats.post_passes += 1
        return target.texture


class PostStack:
    """Runs the enabled layers top to bottom; owns one effect instance per layer slot."""

    def __init__(self, effects):
        self._classes = effects  # id -> PostEffect subclass (``post.EFFECTS``; ``post.post_stack()``)
        self._effects = {}

    def effect(self, slot, effect_id):
        key = (slot, effect_id)
        eff = self._effects.get(key)
        if eff is None:
            if effect_id not in self._classes:
                raise ValueError(f"unknown post effect {effect_id!r}; expected one of {', '.join(self._classes)}")
            eff = self._classes[effect_id]()
            self._effects[key] = eff
        return eff

    def run(self, ctx, src, layers):
        """``layers``: [Layer] (or equal tuples) in stack order. Consecutive point layers
        share a pass (``FUSE_POINT_LAYERS``)."""
        ctx._point_next = 0
        run = []  # consecutive point layers not drawn yet
        for slot, (effect_id, enabled, mix, params) in enumerate(layers):
            if not enabled or mix <= 0.0:
                continue
            eff = self.effect(slot, effect_id)
            params = scale_pixels(eff.params, eff.values(params), ctx.pixel_scale)
            if eff.is_identity(params):
                continue
            mix = min(float(mix), 1.0)
            if ctx.stats is not None:
                ctx.stats.post_layers += 1
            if FUSE_POINT_LAYERS and isinstance(eff, PointEffect):
                run.append((eff, params, mix))
                if len(run) == MAX_POINT_LAYERS:
                    src = ctx.point_pass(src, run)
                    run = []
                continue
            if run:
                src = ctx.point_pass(src, run)
                run = []
            src = eff.execute(ctx, src, params, mix)
        if run:
            src = ctx.point_pass(src, run)
        return src
