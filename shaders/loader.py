"""Builds GPU shaders from the .glsl files in this folder.

Blender's gpu module has no ``#include``: a program is described as data (``Program``), the
loader concatenates the library files it names in front of each stage, turns the interface
into a ``GPUShaderCreateInfo`` and compiles. Each library's first line names the libraries it
uses directly (``// requires: lib/a.glsl lib/b.glsl``, empty when none); a program lists only
the libraries its own stage (or generated code) uses, and ``resolve_libs`` brings in the rest,
each before what needs it and once. Variants differ only by their defines and are compiled the
first time a frame needs them, then cached by (program, defines).
"""

import time
from dataclasses import dataclass, replace
from functools import cached_property, lru_cache
from operator import itemgetter
from pathlib import Path

import numpy as np

SHADER_DIR = Path(__file__).resolve().parent

# Uniform-block member types: (std140 base alignment, size) in bytes, and the numpy kind the
# packer writes them as.
_STD140 = {
    "FLOAT": (4, 4, "f"),
    "INT": (4, 4, "i"),
    "VEC2": (8, 8, "f"),
    "IVEC2": (8, 8, "i"),
    "VEC3": (16, 12, "f"),
    "VEC4": (16, 16, "f"),
    "IVEC4": (16, 16, "i"),
    "MAT4": (16, 64, "f"),
}


@dataclass(frozen=True)
class Struct:
    """A uniform-block struct shared by Python and GLSL: ``fields`` is a tuple of (GLSL type,
    name). The GLSL declaration and the std140 packing both come from it, so the two agree by
    construction."""

    name: str
    fields: tuple

    def __post_init__(self):
        for typ, name in self.fields:
            if typ not in _STD140:
                raise ValueError(f"{self.name}.{name}: unsupported uniform type {typ}")

    @cached_property
    def layout(self):
        """{field: (byte offset, GLSL type)} under std140."""
        out, off = {}, 0
        for typ, name in self.fields:
            align, size, _kind = _STD140[typ]
            off = (off + align - 1) // align * align
            out[name] = (off, typ)
            off += size
        return out

    @cached_property
    def stride(self):
        """Bytes per element in a std140 array (rounded up to 16)."""
        end = 0
        for name, (off, typ) in self.layout.items():
            end = off + _STD140[typ][1]
        return max(16, (end + 15) // 16 * 16)

    @property
    def floats(self):
        return self.stride // 4

    def glsl(self):
        body = "".join(f"  {t.lower()} {n};\n" for t, n in self.fields)
        return f"struct {self.name} {{\n{body}}};\n"

    @cached_property
    def _plan(self):
        """The packer's plan: the field names; per field (name, first 32-bit word, words,
        integer, matrix); and the fields in groups of one shape (scalars, vectors of a size,
        matrices; floats and integers apart), each as (getter of its values from a row, their
        words in order, integer, the shape of a row's values, matrix)."""
        plan, groups = [], {}
        for name, (off, typ) in self.layout.items():
            _align, size, kind = _STD140[typ]
            words, integer, matrix = size // 4, kind == "i", typ == "MAT4"
            plan.append((name, off // 4, words, integer, matrix))
            groups.setdefault((integer, words, matrix), []).append((name, off // 4))
        packed = []
        for (integer, words, matrix), fields in groups.items():
            names = tuple(name for name, _word in fields)
            getter = itemgetter(*names) if len(names) > 1 else (lambda row, name=names[0]: (row[name],))
            index = np.array([range(word, word + words) for _name, word in fields], np.intp).ravel()
            shape = (len(fields), *((4, 4) if matrix else (() if words == 1 else (words,))))
            packed.append((getter, index, integer, shape, matrix))
        return frozenset(self.layout), tuple(plan), tuple(packed)

    def pack(self, rows, count=None):
        """``rows`` (a list of {field: value}) as std140 bytes of ``count`` elements (default:
        as many as rows, at least one); elements past the rows are zero. Every field of a
        row must be named in the struct, and every struct field set in every row. Integer
        fields take the value rounded to the nearest integer (half to even)."""
        n = max(len(rows), 1) if count is None else count
        if len(rows) > n:
            raise ValueError(f"{self.name}: {len(rows)} rows for {n} elements")
        data = np.zeros((n, self.stride // 4), np.float32)
        ints = data.view(np.int32)
        names, _plan, groups = self._plan
        for row in rows:
            if row.keys() != names:
                missing, unknown = names - set(row), set(row) - names
                raise KeyError(f"{self.name}: missing {sorted(missing)}, unknown {sorted(unknown)}")
        if not rows:
            return data
        # One numpy write a group of fields of one shape, for every row at once.
        count_rows = len(rows)
        try:
            for getter, index, integer, shape, matrix in groups:
                values = np.array([getter(row) for row in rows], dtype=np.float64)
                if values.shape[1:] != shape:
                    raise ValueError(shape)
                if matrix:
                    values = values.transpose(0, 1, 3, 2)  # GLSL matrices are column-major
                values = values.reshape(count_rows, index.size)
                if integer:
                    ints[:count_rows, index] = np.rint(values).astype(np.int32)
                else:
                    data[:count_rows, index] = values
        except (TypeError, ValueError):  # a value of another length or shape: field by field
            data[:] = 0.0
            for i, row in enumerate(rows):
                self._pack_row(data, ints, i, row)
        return data

    def _pack_row(self, data, ints, i, row):
        """Row ``i`` of ``pack`` field by field: a value of another number of words than its
        type writes as many words from the field's first."""
        for name, word, _size, integer, matrix in self._plan[1]:
            v = np.asarray(row[name], dtype=np.float64)
            if matrix:
                v = v.T
            v = v.ravel()
            if integer:
                ints[i, word : word + len(v)] = np.rint(v).astype(np.int32)
            else:
                data[i, word : word + len(v)] = v

    def unpack(self, data, index, name):
        """One field of element ``index`` of packed ``data`` (for tests)."""
        off, typ = self.layout[name]
        align, size, kind = _STD140[typ]
        row = np.asarray(data).reshape(-1, self.stride // 4)[index]
        words = row.view(np.int32) if kind == "i" else row
        v = words[off // 4 : off // 4 + size // 4].copy()
        if typ == "MAT4":
            return v.reshape(4, 4).T
        return v[0] if len(v) == 1 else v


@dataclass(frozen=True)
class Program:
    """A shader program described as data. Stage files and libs are paths relative to here."""

    name: str
    vertex: str
    fragment: str
    libs: tuple = ()  # fragment-stage libraries it uses directly (their needs: resolve_libs)
    vertex_libs: tuple = ()
    vertex_in: tuple = ()  # (type, name)
    varyings: tuple = ()  # (qualifier 'smooth'|'flat'|'no_perspective', type, name)
    push_constants: tuple = ()  # (type, name) or (type, name, array size)
    samplers: tuple = ()  # (type, name)
    uniform_blocks: tuple = ()  # (Struct, name, array length)
    outputs: tuple = (("VEC4", "out_color"),)
    defines: tuple = ()  # (name, value) every variant gets: enum values, fixed sizes
    depth_write: str = ""  # 'ANY' etc. when the fragment stage writes gl_FragDepth
    generated: str = ""  # fragment-stage GLSL written by Python (a compiled node tree), after the libs
    entry_libs: tuple = ()  # fragment-stage libraries after the generated code (what calls into it)


# The fields a ``ProgramPart`` adds to: tuples a program concatenates, each entry once.
_PART_LISTS = ("libs", "vertex_in", "varyings", "push_constants", "samplers", "uniform_blocks", "outputs", "entry_libs")


@dataclass(frozen=True)
class ProgramPart:
    """A piece of a program a technique or a pass brings, as EEVEE's create-infos combine
    through ``additional_info``: libraries, vertex inputs, varyings, push constants, samplers,
    uniform blocks and outputs (each added after the program's, once), defines (a part's own
    win over the program's), and ``fragment``: an entry stage that replaces the program's
    (the settle test's, a debug view's). ``name`` becomes a suffix of the combined program's
    name, so equal parts make one program and a program's name lists its parts.

    Frozen and made of tuples: a part is a value, hashable, so a set of parts is a key."""

    name: str
    libs: tuple = ()
    vertex_in: tuple = ()
    varyings: tuple = ()
    push_constants: tuple = ()
    samplers: tuple = ()
    uniform_blocks: tuple = ()
    outputs: tuple = ()
    defines: tuple = ()  # (name, value)
    entry_libs: tuple = ()
    fragment: str = ""
    generated: str = ""  # GLSL written by Python (a compiled node tree's code)

    def __post_init__(self):
        if isinstance(self.defines, dict):
            object.__setattr__(self, "defines", tuple(self.defines.items()))


def with_parts(program, *parts):
    """``program`` combined with ``parts``, in order (``ProgramPart``). A list field of a part
    adds its entries that the program does not have yet; a define of a part replaces the
    program's of that name; a part's ``fragment`` or ``generated`` replaces the program's."""
    if not parts:
        return program
    changes = {f: list(getattr(program, f)) for f in _PART_LISTS}
    defines = dict(program.defines)
    fragment, generated, names = program.fragment, program.generated, [program.name]
    for part in parts:
        for f in _PART_LISTS:
            changes[f] += [e for e in getattr(part, f) if e not in changes[f]]
        defines.update(part.defines)
        fragment = part.fragment or fragment
        generated = part.generated or generated
        if part.name:
            names.append(part.name)
    return replace(
        program,
        name="_".join(names),
        fragment=fragment,
        generated=generated,
        defines=tuple(defines.items()),
        **{f: tuple(v) for f, v in changes.items()},
    )


def _read(rel):
    return (SHADER_DIR / rel).read_text(encoding="utf-8")


REQUIRES = "// requires:"


@lru_cache(maxsize=None)
def _requires_at(path):
    """The libraries the file at ``path`` names on its first line (see ``lib_requires``).
    Cached by path: the files do not change while Blender runs, and a test's files in a
    temporary folder have paths of their own."""
    with open(path, encoding="utf-8") as f:
        first = f.readline().rstrip("\r\n")
    if not first.startswith(REQUIRES):
        raise ValueError(f"shader library {path}: its first line is not '{REQUIRES} ...'")
    return tuple(first[len(REQUIRES) :].split())


def lib_requires(rel):
    """The libraries (paths relative to SHADER_DIR) that library ``rel`` uses directly: its
    ``// requires:`` line, in its order."""
    return _requires_at(SHADER_DIR / rel)


def resolve_libs(names, exclude=()):
    """``names`` (library paths relative to SHADER_DIR) with everything they require, depth
    first: each library after the ones it requires, each once, otherwise in the order listed.
    Libraries in ``exclude`` (already in the stage's text) are left out, with what they
    require. A cycle of requirements or a missing file raises ValueError naming it."""
    done, order = set(exclude), []

    def visit(rel, chain):
        if rel in done:
            return
        if rel in chain:
            cycle = chain[chain.index(rel) :] + (rel,)
            raise ValueError("shader libraries require each other in a cycle: " + " -> ".join(cycle))
        if not (SHADER_DIR / rel).is_file():
            by = f" (required by {chain[-1]})" if chain else ""
            raise ValueError(f"shader library {rel}{by} does not exist under {SHADER_DIR}")
        for need in lib_requires(rel):
            visit(need, chain + (rel,))
        done.add(rel)
        order.append(rel)

    for rel in names:
        visit(rel, ())
    return tuple(order)


def program_sources(program):
    """The (vertex, fragment) GLSL text, libraries first (``resolve_libs``). The fragment
    stage: its libs, the generated code (a compiled node tree, which calls into the libs),
    the entry libs not already included (which call into the generated code), the stage file."""
    vlibs = resolve_libs(program.vertex_libs)
    flibs = resolve_libs(program.libs)
    entry = resolve_libs(program.entry_libs, exclude=flibs)
    vert = "".join(_read(p) + "\n" for p in vlibs) + _read(program.vertex)
    frag = "".join(_read(p) + "\n" for p in flibs) + program.generated + "\n"
    frag += "".join(_read(p) + "\n" for p in entry) + _read(program.fragment)
    return vert, frag


def _format_define(value):
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return repr(float(value))
    return str(value)


class ShaderCache:
    """Compiled variants: of one engine instance (the viewport), or shared by final renders
    (``engine/gpu_pool.py``)."""

    def __init__(self):
        self._cache = {}
        self._seen = {}  # (id(program), its defines as given) -> (program, shader): ``get``'s fast path
        self.compiled = 0
        self.compile_seconds = 0.0  # spent compiling, over the cache's life

    def __len__(self):
        return len(self._cache)

    def get(self, program, defines=None):
        try:  # asked again as before (a frame asks for the same programs every sample)
            asked = (id(program), tuple(defines.items()) if defines else ())
            seen = self._seen.get(asked)
        except TypeError:  # a define's value that does not hash
            asked = seen = None
        if seen is not None and seen[0] is program:
            return seen[1]
        shader = self._get(program, defines)
        if asked is not None:
            if len(self._seen) >= 4096:
                self._seen.clear()
            self._seen[asked] = (program, shader)  # the program held: its id is not reused
        return shader

    def _get(self, program, defines):
        defines = tuple(sorted({**dict(program.defines), **(defines or {})}.items()))
        key = (program.name, defines)
        shader = self._cache.get(key)
        if shader is None:
            start = time.perf_counter()
            shader = self._compile(program, defines)
            self.compile_seconds += time.perf_counter() - start
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
        if program.depth_write:
            info.depth_write(program.depth_write)
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
