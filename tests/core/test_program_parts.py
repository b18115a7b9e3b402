"""Programs from parts (``shaders.loader.ProgramPart``, ``with_parts``) and the lit program's
key (``programs.LitKey``): a part adds what the program lacks, once; its defines win; its entry
replaces the program's; each technique's part switches its technique on in the program's
defines and brings its samplers and targets, and a key is one hashable value."""

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.frame import programs  # noqa: E402
from penumbra.engine.frame.features import bounce, settling, world_occlusion, world_ratio  # noqa: E402
from penumbra.shaders.loader import Program, ProgramPart, with_parts  # noqa: E402

BASE = Program(
    name="base",
    vertex="v.glsl",
    fragment="f.glsl",
    libs=("lib/a.glsl",),
    samplers=(("FLOAT_2D", "one"),),
    defines=(("X", 0), ("Y", 1)),
)


def test_a_part_adds_what_the_program_lacks_once_and_its_defines_win():
    part = ProgramPart(
        "p", libs=("lib/a.glsl", "lib/b.glsl"), samplers=(("FLOAT_2D", "two"),), defines=(("X", 1),), fragment="g.glsl"
    )
    out = with_parts(BASE, part, ProgramPart("q", samplers=(("FLOAT_2D", "two"),)))
    assert out.name == "base_p_q"
    assert out.libs == ("lib/a.glsl", "lib/b.glsl")
    assert out.samplers == (("FLOAT_2D", "one"), ("FLOAT_2D", "two"))
    assert dict(out.defines) == {"X": 1, "Y": 1}
    assert out.fragment == "g.glsl" and out.vertex == "v.glsl"
    assert with_parts(BASE) is BASE
    assert ProgramPart("d", defines={"Z": 2}).defines == (("Z", 2),)  # a dict becomes a value
    assert hash(part) == hash(ProgramPart(**{f: getattr(part, f) for f in part.__dataclass_fields__}))


def test_the_passes_own_programs_are_the_lit_program_with_their_parts():
    assert programs.LIT_EMIT.name == "lit_emit"
    assert programs.LIT_EMIT.outputs == programs.LIT.outputs + (("VEC4", "out_emission"),)
    assert dict(programs.LIT_EMIT.defines)["EMISSION_OUTPUT"] is True
    counted = programs.LIT_COLOR_COUNTED
    assert counted.name == "lit_color_counted" and counted.outputs[-1] == ("FLOAT", "out_shaded")


def test_each_techniques_part_switches_it_on_and_brings_its_samplers_and_targets():
    variant = programs.LitVariant()
    off = programs.lit_key(True, variant)
    off_program, off_defines = off.program(), {**dict(off.program().defines), **off.defines()}
    cases = {
        "bounce": (bounce.gather_part(4), {"INDIRECT_RSM": True, "RSM_SAMPLES": 4}),
        "world_ratio": (world_ratio.OPAQUE, {"WORLD_RATIO": True, "WORLD_RATIO_OUT": 1}),
        "world_ratio blended": (world_ratio.BLENDED, {"WORLD_RATIO": True, "WORLD_RATIO_OUT": 2}),
        "world_occlusion": (world_occlusion._OCCLUSION, {"WORLD_AO": True}),
        "pilot": (settling._PILOT.program, {"PILOT_SAMPLE": True}),
        "settle test": (settling._TEST, {"SETTLE_TEST": True}),
    }
    for name, (part, switches) in cases.items():
        key = programs.lit_key(True, variant, (part,))
        program = key.program()
        defines = {**dict(program.defines), **key.defines()}
        for define, value in switches.items():
            assert defines[define] == value, name
            assert off_defines.get(define, 0) != value, f"{name}: {define} is on without its part"
        assert set(part.samplers) <= set(program.samplers) and not set(part.samplers) & set(off_program.samplers)
        assert program.outputs == off_program.outputs + part.outputs, name
        assert program.fragment == (part.fragment or off_program.fragment), name
        assert len({key, off, programs.lit_key(True, variant, (part,))}) == 2, name


def test_a_material_part_is_named_by_its_features_and_made_once():
    features = frozenset({"TEX_BASE_COLOR", "ALPHA_HASHED"})
    part = programs.material_part(features)
    assert part is programs.material_part(frozenset(features))
    assert part.name == "alpha_hashed_tex_base_color"
    key = programs.lit_key(False, programs.LitVariant(aux_outputs=False), (), features)
    assert key.program().name == "lit_color_alpha_hashed_tex_base_color"
    assert ("FLOAT_2D", "tex_base_color") in key.program().samplers
    assert key.defines()["AUX_OUTPUTS"] is False
