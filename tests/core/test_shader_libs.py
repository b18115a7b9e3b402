"""The GLSL libraries name what they need (``// requires:`` on their first line) and the loader
(``shaders/loader.py resolve_libs``) puts each program's libraries in an order that compiles:
every library after the ones it requires, each once. Text only: nothing here compiles."""

import importlib
import pkgutil
import re
from types import SimpleNamespace

import numpy as np
import pytest

from devkit.session import ROOT, load_penumbra

load_penumbra()
import penumbra  # noqa: E402
from penumbra.engine.enums import DEPTH_FORMAT  # noqa: E402
from penumbra.engine.frame import film_programs, programs, shadow_programs  # noqa: E402
from penumbra.engine.frame.features import bounce, passes, settling, world_occlusion, world_ratio  # noqa: E402
from penumbra.engine.post.base import PointEffect, point_program  # noqa: E402
from penumbra.shaders import loader  # noqa: E402
from penumbra.shaders.loader import Program, lib_requires, program_sources, resolve_libs  # noqa: E402

SHADERS = ROOT / "shaders"
# Every library: the shared ones, the node families, and the post point layers' functions
# (``PointEffect.point_glsl``, concatenated into one pass).
LIBS = sorted(
    p.relative_to(SHADERS).as_posix() for d in ("lib", "nodes") for p in (SHADERS / d).glob("*.glsl")
) + sorted({cls.point_glsl for cls in PointEffect.__subclasses__()})
# The lit program's libraries as they were listed by hand before the requires lines.
OLD_LIT_LIBS = (
    "lib/common.glsl",
    "lib/lights.glsl",
    "lib/depth_encoding.glsl",
    "lib/lit_debug.glsl",
    "lib/shadow_filters.glsl",
    "lib/material.glsl",
    "lib/ggx_albedo.glsl",
    "lib/gtao.glsl",
    "lib/world_ratio.glsl",
    "lib/lit_surface.glsl",
    "lib/lit_terminator.glsl",
    "lib/lit_bsdf.glsl",
    "lib/lit_world.glsl",
    "lib/lit_settle.glsl",
    "lib/lit_lights.glsl",
    "lib/lit_outputs.glsl",
)


def guard(rel):
    """The include guard of library ``rel``: PENUMBRA_LIB_ and its path without lib/ and the
    extension (nodes/common.glsl: PENUMBRA_LIB_NODES_COMMON)."""
    stem = rel.removesuffix(".glsl").removesuffix(".frag").removeprefix("lib/")
    return "PENUMBRA_LIB_" + re.sub(r"\W", "_", stem).upper()


def test_the_point_layers_are_found():
    assert len(LIBS) > 30 and "post/sepia.frag.glsl" in LIBS


@pytest.mark.parametrize("rel", LIBS)
def test_every_library_names_its_needs_and_has_a_guard(rel):
    """Line 1: ``// requires:`` and the libraries (none: nothing after the colon); then the
    guard around the whole file, so a library concatenated twice is harmless."""
    lines = (SHADERS / rel).read_text(encoding="utf-8").split("\n")
    assert re.fullmatch(r"// requires:( [a-z_]+/[a-z_.]+\.glsl)*", lines[0]), f"{rel}: {lines[0]!r}"
    g = guard(rel)
    assert lines[1:3] == [f"#ifndef {g}", f"#define {g}"], rel
    last = [line for line in lines if line.strip()][-1]
    assert last.startswith("#endif"), rel
    for need in lib_requires(rel):
        assert (SHADERS / need).is_file(), f"{rel} requires {need}, which does not exist"
        assert need != rel
    assert len(set(lib_requires(rel))) == len(lib_requires(rel)), f"{rel} names a library twice"


def _strip_comments(text):
    return re.sub(r"//[^\n]*", " ", re.sub(r"/\*.*?\*/", " ", text, flags=re.S))


def _defined_names(text):
    """The names a library defines at file scope: macros, structs, functions and globals
    (a line at column 0 starting with a type), and functions a macro writes (the noise and
    Voronoi families write theirs per dimension)."""
    text = _strip_comments(text)
    names = set(re.findall(r"^\s*#\s*define\s+(\w+)", text, re.M))
    names |= set(re.findall(r"^struct\s+(\w+)", text, re.M))
    names |= set(re.findall(r"^(?:const\s+)?\w+(?:\[\w*\])?\s+(\w+)\s*[(=;\[]", text, re.M))
    macro_body = "\n".join(line for line in text.split("\n") if line.rstrip().endswith("\\"))
    names |= set(re.findall(r"\b(?:float|int|uint|bool|void|[iu]?vec[234]|T)\s+(\w+)\s*\(", macro_body))
    return {n for n in names if not n.startswith("PENUMBRA_LIB_")}


# Calls a library makes only in variants that bring the callee some other way: lit_inputs
# resolves a compiled tree's closure (NODE_TREE), whose families include nodes/shader.glsl.
_BROUGHT_OTHERWISE = {("lib/lit_inputs.glsl", "nodes/shader.glsl")}


def test_requires_lines_cover_what_each_library_uses():
    """A library that uses a name another library defines requires it (directly or through
    what it requires): its requires line is not missing a need the hand order used to hide."""
    defined = {rel: _defined_names((SHADERS / rel).read_text(encoding="utf-8")) for rel in LIBS}
    owners = {}
    for rel, names in defined.items():
        for name in names:
            owners.setdefault(name, set()).add(rel)
    assert {n: o for n, o in owners.items() if len(o) > 1} == {}, "a name defined by two libraries"
    for rel in LIBS:
        used = set(re.findall(r"\b[A-Za-z_]\w*\b", _strip_comments((SHADERS / rel).read_text(encoding="utf-8"))))
        reach = set(resolve_libs((rel,)))
        for name in used - defined[rel]:
            for owner in owners.get(name, ()):
                if (rel, owner) not in _BROUGHT_OTHERWISE:
                    assert owner in reach, f"{rel} uses {name} from {owner} without requiring it"


@pytest.fixture
def tmp_shaders(tmp_path, monkeypatch):
    """A shader folder of hand-written libraries: write({rel: requires}) makes them."""
    monkeypatch.setattr(loader, "SHADER_DIR", tmp_path)

    def write(libs):
        for rel, needs in libs.items():
            (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
            (tmp_path / rel).write_text(f"// requires: {' '.join(needs)}\nfloat {rel[4:-5]}_fn();\n")

    return write


def test_resolve_puts_needs_first_once_and_keeps_the_listed_order(tmp_shaders):
    tmp_shaders(
        {
            "lib/a.glsl": (),
            "lib/b.glsl": ("lib/a.glsl",),
            "lib/c.glsl": ("lib/b.glsl", "lib/a.glsl"),
            "lib/d.glsl": (),
            "lib/e.glsl": ("lib/d.glsl", "lib/b.glsl"),
        }
    )
    assert resolve_libs(("lib/c.glsl",)) == ("lib/a.glsl", "lib/b.glsl", "lib/c.glsl")
    assert resolve_libs(("lib/d.glsl", "lib/c.glsl", "lib/e.glsl", "lib/a.glsl")) == (
        "lib/d.glsl",
        "lib/a.glsl",
        "lib/b.glsl",
        "lib/c.glsl",
        "lib/e.glsl",
    )
    # What a stage already has (the fragment's libs, for its entry libs) is not repeated.
    assert resolve_libs(("lib/e.glsl",), exclude=("lib/a.glsl", "lib/b.glsl")) == ("lib/d.glsl", "lib/e.glsl")
    assert resolve_libs(()) == ()


def test_resolve_names_the_cycle(tmp_shaders):
    tmp_shaders({"lib/a.glsl": ("lib/b.glsl",), "lib/b.glsl": ("lib/c.glsl",), "lib/c.glsl": ("lib/a.glsl",)})
    with pytest.raises(ValueError, match=r"cycle: lib/a\.glsl -> lib/b\.glsl -> lib/c\.glsl -> lib/a\.glsl"):
        resolve_libs(("lib/a.glsl",))
    tmp_shaders({"lib/s.glsl": ("lib/s.glsl",)})
    with pytest.raises(ValueError, match=r"cycle: lib/s\.glsl -> lib/s\.glsl"):
        resolve_libs(("lib/s.glsl",))


def test_resolve_names_a_missing_library_and_a_missing_header(tmp_shaders, tmp_path):
    tmp_shaders({"lib/a.glsl": ("lib/gone.glsl",)})
    with pytest.raises(ValueError, match=r"lib/gone\.glsl \(required by lib/a\.glsl\) does not exist"):
        resolve_libs(("lib/a.glsl",))
    with pytest.raises(ValueError, match=r"lib/nowhere\.glsl does not exist"):
        resolve_libs(("lib/nowhere.glsl",))
    (tmp_path / "lib" / "bare.glsl").write_text("float bare();\n")
    with pytest.raises(ValueError, match="first line"):
        resolve_libs(("lib/bare.glsl",))


def _fake_tree(families, images=0):
    """What with_tree reads of a ``nodetree.CompiledTree``."""
    return SimpleNamespace(
        key="x" + str(len(families)),
        families=tuple(sorted(families)),
        code="/* node tree */\n",
        constants=np.zeros((1, 4), np.float32),
        images=tuple(range(images)),
        needs=frozenset({"GENERATED"}),
        aovs=(),
    )


ALL_FAMILIES = sorted(p.stem for p in (SHADERS / "nodes").glob("*.glsl"))


def _engine_programs():
    """Every Program the engine defines at module level, and the variants its builders make."""
    found = {}
    for info in pkgutil.walk_packages(penumbra.engine.__path__, "penumbra.engine."):
        module = importlib.import_module(info.name)
        for value in vars(module).values():
            if isinstance(value, Program):
                found[value.name] = value
    trees = (_fake_tree({"common", "shader"}), _fake_tree(ALL_FAMILIES, images=1), _fake_tree({"texture_wave"}))
    variant = programs.LitVariant()
    parts = (
        bounce.gather_part(4),
        world_ratio.OPAQUE,
        world_ratio.BLENDED,
        world_occlusion._OCCLUSION,
        settling._PILOT.program,
        settling._TEST,
    )
    for aux, own in (
        (True, ()),
        (False, ()),
        (False, (programs.COUNTED_PART,)),
        (True, (programs.EMISSION_PART,)),
        (False, (programs.EMISSION_ONLY,)),
        (False, (passes.group_part(("POSITION", "DIFFUSE_COLOR", "AOV_VALUE:x"), None),)),
    ):
        for tree in (None,) + trees:
            features = frozenset({"TEX_BASE_COLOR", "TERMINATOR_OFFSET"} if tree is None else {"NODES_x"})
            combos = [(t, None) for t in ((part,) for part in parts)]
            combos += [((), entry) for entry in (None, *programs.ENTRY_PARTS.values(), passes.ENTRY)]
            combos += [(parts[:2] + parts[3:5], None)]
            for technique, entry in combos:
                p = programs.lit_key(aux, variant, own + technique, features, tree, entry).program()
                found[p.name + str(id(p))] = p
    for fmt in DEPTH_FORMAT.ids:
        for rsm in (False, True):
            for p in (
                shadow_programs.shadow_program(fmt, rsm=rsm),
                shadow_programs.shadow_cutout_program(fmt, True, rsm=rsm),
                shadow_programs.shadow_hair_program(fmt, rsm=rsm),
                shadow_programs.shadow_tree_program(fmt, trees[1], rsm=rsm),
            ):
                found[p.name + str(id(p))] = p
        if DEPTH_FORMAT[fmt].depth_only:
            p = shadow_programs.instanced_shadow_program(fmt)
            found[p.name] = p
    for error in (False, True):
        p = film_programs.convergence_program(error, (world_ratio.CONVERGENCE,))
        found[p.name] = p
    found["point_all"] = point_program(PointEffect.__subclasses__())
    return list(found.values())


PROGRAMS = _engine_programs()


def test_the_programs_are_collected():
    names = {p.name for p in PROGRAMS}
    assert {"lit", "lit_color", "shadow_depth", "ao_horizons", "background", "post_point"} <= names
    assert len(PROGRAMS) > 60


@pytest.mark.parametrize("program", PROGRAMS, ids=lambda p: p.name)
def test_every_program_includes_each_library_once_after_its_needs(program):
    for stage, libs, entry in (
        (program_sources(program)[0], program.vertex_libs, ()),
        (program_sources(program)[1], program.libs, program.entry_libs),
    ):
        resolved = resolve_libs(libs)
        every = resolved + resolve_libs(entry, exclude=resolved)
        for rel in every:
            assert stage.count(f"#define {guard(rel)}\n") == 1, f"{program.name}: {rel}"
        # Each library's text comes after the text of every library it requires.
        at = {rel: stage.index(f"#define {guard(rel)}\n") for rel in every}
        for rel in every:
            for need in lib_requires(rel):
                assert at[need] < at[rel], f"{program.name}: {need} after {rel}"
    if program.generated:
        frag = program_sources(program)[1]
        generated_at = frag.index(program.generated)
        for rel in resolve_libs(program.libs):
            assert frag.index(f"#define {guard(rel)}\n") < generated_at, f"{program.name}: {rel} after the tree"
        for rel in program.entry_libs:
            assert frag.index(f"#define {guard(rel)}\n") > generated_at, f"{program.name}: {rel} before the tree"


def test_the_lit_program_keeps_every_library_it_had():
    resolved = resolve_libs(programs.LIT.libs)
    assert set(OLD_LIT_LIBS) <= set(resolved)
    assert resolve_libs(programs.LIT.entry_libs, exclude=resolved) == ("lib/lit_inputs.glsl",)
    # With a tree: its families (with what they need) before the generated code.
    tree = _fake_tree({"texture_wave", "vector"})
    lit = programs.lit_program(frozenset({"NODES_x"}), tree=tree)
    resolved = resolve_libs(lit.libs)
    base = resolve_libs(programs.LIT.libs)
    assert resolved[: len(base)] == base
    assert set(resolved[len(base) :]) == {
        "nodes/common.glsl",
        "nodes/math.glsl",
        "nodes/vector.glsl",
        "nodes/texture_hash.glsl",
        "nodes/texture_noise.glsl",
        "nodes/texture_wave.glsl",
    }
