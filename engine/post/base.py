"""The post stack's shared machinery: parameter declarations, render targets, the stack."""

from dataclasses import dataclass, field
from types import SimpleNamespace

from ...shaders.loader import Program, set_uniforms


@dataclass(frozen=True)
class Param:
    """One effect parameter; properties and UI are generated from these."""

    name: str
    type: str  # 'FLOAT' | 'INT' | 'BOOL' | 'COLOR' | 'ENUM' | 'IMAGE' (an Image datablock or None)
    default: object
    description: str = ""
    min: float = None
    max: float = None
    soft_max: float = None
    subtype: str = "NONE"
    items: tuple = ()  # for ENUM: (identifier, label, description)

    @property
    def label(self):
        return self.name.replace("_", " ").title()


def post_program(name, fragment, push_constants=(), samplers=(), uniform_blocks=()):
    """A full-screen program; every post fragment shader gets ``source_tex`` and ``mix_factor``."""
    return Program(
        name=name,
        vertex="fullscreen.vert.glsl",
        fragment=fragment,
        libs=("lib/common.glsl", "lib/post_common.glsl"),
        vertex_in=(("VEC2", "pos"),),
        varyings=(("smooth", "VEC2", "uv"),),
        push_constants=(("FLOAT", "mix_factor"), ("VEC2", "target_size")) + tuple(push_constants),
        samplers=(("FLOAT_2D", "source_tex"),) + tuple(samplers),
        uniform_blocks=tuple(uniform_blocks),
    )


class PostEffect:
    """Base of every effect. Subclasses set the class attributes and implement ``execute``."""

    id = ""
    label = ""
    icon = "NONE"
    description = ""
    params = ()

    def resize(self, width, height):
        """Allocate size-dependent resources (most effects use the context's pool instead)."""

    def is_identity(self, params):
        """True when these parameters leave the image unchanged, so the layer costs no pass."""
        return False

    def execute(self, ctx, src, params, mix):
        raise NotImplementedError

    @classmethod
    def defaults(cls):
        return SimpleNamespace(**{p.name: p.default for p in cls.params})


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
    _pool: list = field(default_factory=list)
    _batch: object = None

    def acquire(self, *busy):
        """A float target of the frame's size whose texture is none of ``busy``."""
        import gpu

        busy_ids = {id(t) for t in busy}
        for target in self._pool:
            if id(target.texture) not in busy_ids:
                return target
        tex = gpu.types.GPUTexture((self.width, self.height), format="RGBA32F")
        target = Target(tex, gpu.types.GPUFrameBuffer(color_slots=(tex,)))
        self._pool.append(target)
        return target

    @property
    def memory_bytes(self):
        return len(self._pool) * self.width * self.height * 16

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

    def fullscreen(self, program, target, defines=None, samplers=None, uniforms=None, blocks=None):
        """Draw one full-screen pass of ``program`` into ``target``."""
        import gpu
        from gpu_extras.batch import batch_for_shader

        shader = self.shaders.get(program, defines)
        if self._batch is None:
            self._batch = batch_for_shader(shader, "TRIS", {"pos": ((-1, -1), (3, -1), (-1, 3))})
        with target.framebuffer.bind():
            gpu.state.viewport_set(0, 0, self.width, self.height)
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set("NONE")
            shader.bind()
            set_uniforms(shader, {"target_size": (float(self.width), float(self.height)), **(uniforms or {})})
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

    def __init__(self):
        self._effects = {}

    def effect(self, slot, effect_id):
        from . import EFFECTS

        key = (slot, effect_id)
        eff = self._effects.get(key)
        if eff is None:
            eff = EFFECTS[effect_id]()
            self._effects[key] = eff
        return eff

    def run(self, ctx, src, layers):
        """``layers``: [(effect id, enabled, mix, params namespace)] in stack order."""
        for slot, (effect_id, enabled, mix, params) in enumerate(layers):
            if not enabled or mix <= 0.0:
                continue
            eff = self.effect(slot, effect_id)
            if eff.is_identity(params):
                continue
            eff.resize(ctx.width, ctx.height)
            src = eff.execute(ctx, src, params, min(float(mix), 1.0))
        return src
