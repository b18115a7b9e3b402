"""Builds GPU shaders from the .glsl files in this folder.

Blender's gpu module has no ``#include``: a program is described as data (``Program``), the
loader concatenates its ordered list of library files in front of each stage, turns the
interface into a ``GPUShaderCreateInfo`` and compiles. Variants differ only by their defines
and are compiled the first time a frame needs them, then cached by (program, defines).
"""

from dataclasses import dataclass
from pathlib import Path

SHADER_DIR = Path(__file__).resolve().parent

# Uniform-block structs shared by Python and GLSL. Each is a tuple of (GLSL type, name); only
# vec4/mat4 members are used so std140 and a packed float32 array agree without padding rules.
_FLOATS = {"VEC4": 4, "MAT4": 16}


@dataclass(frozen=True)
class Struct:
    name: str
    fields: tuple

    @property
    def floats(self):
        return sum(_FLOATS[t] for t, _ in self.fields)

    def glsl(self):
        body = "".join(f"  {t.lower()} {n};\n" for t, n in self.fields)
        return f"struct {self.name} {{\n{body}}};\n"

    def offset(self, field):
        """Float offset of ``field`` inside one packed struct."""
        off = 0
        for t, n in self.fields:
            if n == field:
                return off
            off += _FLOATS[t]
        raise KeyError(field)


@dataclass(frozen=True)
class Program:
    """A shader program described as data. Stage files and libs are paths relative to here."""

    name: str
    vertex: str
    fragment: str
    libs: tuple = ()  # fragment-stage libraries
    vertex_libs: tuple = ()
    vertex_in: tuple = ()  # (type, name)
    varyings: tuple = ()  # (qualifier 'smooth'|'flat'|'no_perspective', type, name)
    push_constants: tuple = ()  # (type, name) or (type, name, array size)
    samplers: tuple = ()  # (type, name)
    uniform_blocks: tuple = ()  # (Struct, name, array length)
    outputs: tuple = (("VEC4", "out_color"),)


def _read(rel):
    return (SHADER_DIR / rel).read_text(encoding="utf-8")


def program_sources(program):
    """The (vertex, fragment) GLSL text, libraries first, in the order the program lists them."""
    vlibs = "".join(_read(p) + "\n" for p in program.vertex_libs)
    flibs = "".join(_read(p) + "\n" for p in program.libs)
    return vlibs + _read(program.vertex), flibs + _read(program.fragment)


def _format_define(value):
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return repr(float(value))
    return str(value)


class ShaderCache:
    """Compiled variants, owned by one engine instance (GPU objects never live in globals)."""

    def __init__(self):
        self._cache = {}
        self.compiled = 0

    def __len__(self):
        return len(self._cache)

    def get(self, program, defines=None):
        defines = tuple(sorted((defines or {}).items()))
        key = (program.name, defines)
        shader = self._cache.get(key)
        if shader is None:
            shader = self._compile(program, defines)
            self._cache[key] = shader
            self.compiled += 1
        return shader

    @staticmethod
    def _compile(program, defines):
        import gpu

        info = gpu.types.GPUShaderCreateInfo()
        for name, value in defines:
            info.define(name, _format_define(value))
        typedefs = []
        for struct, _name, _count in program.uniform_blocks:
            if struct.glsl() not in typedefs:
                typedefs.append(struct.glsl())
        if typedefs:
            info.typedef_source("".join(typedefs))
        for slot, (typ, name) in enumerate(program.vertex_in):
            info.vertex_in(slot, typ, name)
        if program.varyings:
            iface = gpu.types.GPUStageInterfaceInfo(f"{program.name}_iface")
            for qualifier, typ, name in program.varyings:
                getattr(iface, qualifier)(typ, name)
            info.vertex_out(iface)
        for pc in program.push_constants:
            info.push_constant(*pc)
        for slot, (typ, name) in enumerate(program.samplers):
            info.sampler(slot, typ, name)
        for slot, (struct, name, count) in enumerate(program.uniform_blocks):
            info.uniform_buf(slot, struct.name, f"{name}[{count}]" if count else name)
        for slot, (typ, name) in enumerate(program.outputs):
            info.fragment_out(slot, typ, name)
        vert, frag = program_sources(program)
        info.vertex_source(vert)
        info.fragment_source(frag)
        return gpu.shader.create_from_info(info)


def set_uniforms(shader, uniforms):
    """Set push constants by name; ones the compiler optimised away are skipped."""
    for name, value in uniforms.items():
        try:
            shader.uniform_from_name(name)
        except ValueError:
            continue
        if isinstance(value, int) and not isinstance(value, bool):
            shader.uniform_int(name, value)
        else:
            shader.uniform_float(name, value)
