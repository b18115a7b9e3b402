"""Settings and enums declared once: the declarations are consistent, the generated Blender
properties mirror them, unknown ids are errors, and stored settings upgrade across renames."""

from types import SimpleNamespace

import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine import enums, settings  # noqa: E402
from penumbra.engine.post import EFFECT_ENUM, EFFECTS, REGISTRY  # noqa: E402

ALL_ENUMS = [getattr(enums, n) for n in dir(enums) if isinstance(getattr(enums, n), enums.Enum)] + [EFFECT_ENUM]
ALL_PARAMS = [("scene", p) for p in settings.SCENE_PARAMS] + [("light", p) for p in settings.LIGHT_PARAMS]
ALL_PARAMS += [("view_layer", p) for p in settings.VIEW_LAYER_PARAMS]
ALL_PARAMS += [(eid, p) for eid, cls in EFFECTS.items() for p in cls.params]


@pytest.mark.parametrize("owner,param", ALL_PARAMS, ids=[f"{o}.{p.name}" for o, p in ALL_PARAMS])
def test_every_declared_default_is_inside_its_own_range(owner, param):
    if param.type in {"FLOAT", "INT"}:
        assert param.clamp(param.default) == param.default
        if param.min is not None and param.max is not None:
            assert param.min < param.max
        if param.soft_max is not None and param.max is not None:
            assert param.soft_max <= param.max
    elif param.type == "ENUM":
        assert param.default in param.enum.ids


@pytest.mark.parametrize("enum", ALL_ENUMS, ids=[e.name for e in ALL_ENUMS])
def test_enum_ids_numbers_and_defines_are_unique_and_consistent(enum):
    ids = enum.ids
    assert len(set(ids)) == len(ids)
    numbers = [item.value for item in enum]
    assert len(set(numbers)) == len(numbers)
    defines = enum.defines()
    assert set(defines) == {f"{enum.prefix}_{i}" for i in ids}
    assert [row[4] for row in enum.blender_items()] == numbers
    with pytest.raises(ValueError, match=f"unknown {enum.name}"):
        enum["NO_SUCH_ID"]


def test_effect_numbers_are_the_ones_saved_files_use():
    """A .blend stores a layer's effect as its number: these must never change."""
    saved = {"BLUR": 0, "GLOW": 1, "SCANLINES": 2, "VIGNETTE": 3, "COLORIZER": 4,
             "FISHEYE": 5, "PIXELATE": 6, "SEPIA": 7, "NOISE": 8, "LENS_FLARE": 9}  # fmt: skip
    assert {cls.id: number for number, cls in REGISTRY} == saved
    assert {i: EFFECT_ENUM.value(i) for i in saved} == saved


def test_filter_facts_say_which_settings_each_filter_reads():
    f = enums.SHADOW_FILTER
    assert f.with_fact("pcf_taps") == {"PCF"}
    assert f.with_fact("disk") == {"JITTER", "PCSS"}
    assert f.with_fact("fixed_radius") == {"JITTER"}
    with pytest.raises(AttributeError):
        f["PCF"].no_such_fact  # noqa: B018


def test_param_clamp_applies_hard_limits_only():
    p = settings.Param("x", "FLOAT", 1.0, min=0.0, max=2.0, soft_max=1.5)
    assert p.clamp(-5) == 0.0 and p.clamp(1.75) == 1.75 and p.clamp(9) == 2.0
    q = settings.Param("n", "INT", 3, min=1)
    assert q.clamp(0) == 1 and q.clamp(10**9) == 10**9
    e = settings.Param("f", "ENUM", "PCF", enum=enums.SHADOW_FILTER)
    assert e.clamp("PCSS") == "PCSS"
    with pytest.raises(ValueError, match="unknown shadow filter 'SOFT'"):
        e.clamp("SOFT")
    with pytest.raises(ValueError):
        settings.Param("bad", "ENUM", "NOPE", enum=enums.SHADOW_FILTER)


def test_render_settings_come_from_the_declarations_and_reject_unknown_ids():
    source = SimpleNamespace(**{p.name: p.default for p in settings.SCENE_PARAMS})
    source.pcf_kernel_size = 99  # above its max of 15
    rs = settings.render_settings(source, frame=7)
    assert rs.pcf_kernel_size == 15 and rs.frame == 7
    extra = {"frame", "layers", "film_transparent", "pixel_scale", "use_simplify"}
    fields = [f for f in vars(rs) if f not in extra]
    assert fields == [p.name for p in settings.SCENE_PARAMS]
    source.shadow_filter = "SOFT"
    with pytest.raises(ValueError, match="unknown shadow filter"):
        settings.render_settings(source)


def test_active_when_follows_the_filter_facts():
    params = settings.SCENE_PARAMS
    by_name = {p.name: p for p in params}
    for filt in enums.SHADOW_FILTER:
        group = SimpleNamespace(shadow_filter=filt.id)
        assert by_name["pcf_kernel_size"].is_active(group, params) == filt.pcf_taps
        assert by_name["shadow_samples"].is_active(group, params) == filt.disk
        assert by_name["shadow_filter_radius"].is_active(group, params) == filt.fixed_radius
        assert by_name["shadow_bias"].is_active(group, params)


def test_every_scene_setting_is_drawn_by_a_panel_section():
    sections = {
        settings.SAMPLING,
        settings.SAMPLING_VIEWPORT,
        settings.SAMPLING_RENDER,
        settings.SHADOWS,
        settings.LIGHTING,
        settings.LIGHT_PATHS,
        settings.VOLUMES,
        settings.WORLD,
        settings.VIEWPORT,
        settings.SIMPLIFY,
        settings.DEBUG,
    }
    assert {p.section for p in settings.SCENE_PARAMS} <= sections
    assert all(p.section is not None for p in settings.SCENE_PARAMS + settings.LIGHT_PARAMS)
    assert {p.section for p in settings.VIEW_LAYER_PARAMS} == {settings.PASSES}


def test_generated_properties_mirror_the_declarations(penumbra):
    props = penumbra.properties
    groups = [(props.PENUMBRA_PG_scene, settings.SCENE_PARAMS), (props.PENUMBRA_PG_light, settings.LIGHT_PARAMS)]
    groups += [(props.PENUMBRA_PG_view_layer, settings.VIEW_LAYER_PARAMS)]
    groups += [(props.EFFECT_GROUPS[eid], cls.params) for eid, cls in EFFECTS.items()]
    for group, params in groups:
        rna = group.bl_rna.properties
        for p in params:
            prop = rna[p.name]
            assert prop.description == p.description and prop.name == p.ui_label
            if p.type in {"FLOAT", "INT"}:
                assert prop.default == pytest.approx(p.default)
                if p.min is not None:
                    assert prop.hard_min == pytest.approx(p.min)
                if p.max is not None:
                    assert prop.hard_max == pytest.approx(p.max)
            elif p.type == "ENUM":
                assert prop.default == p.default
                assert [(i.identifier, i.value) for i in prop.enum_items] == [(i.id, i.value) for i in p.enum]
            elif p.type == "BOOL":
                assert prop.default == p.default
    layer_effect = props.PENUMBRA_PG_layer.bl_rna.properties["effect"]
    assert [(i.identifier, i.value) for i in layer_effect.enum_items] == [(i.id, i.value) for i in EFFECT_ENUM]


# --- upgrades of stored settings ------------------------------------------------------------


def test_upgrade_renames_top_level_and_nested_settings_in_order():
    stored = {
        "shadow_bias": 0.7,
        "layers": [{"blur": {"radius": 9}}, {"glow": {"radius": 3}}, {"blur": {"sigma": 2.0}}],
    }
    upgrades = {
        1: (),
        2: (settings.Rename("shadow_bias", "shadow_constant_bias"),),
        3: (
            settings.Rename("shadow_constant_bias", "depth_bias"),
            settings.Rename("radius", "size", path=("layers", "*", "blur")),
        ),
    }
    saved, changes = settings.upgrade(stored, upgrades, current=3)
    assert (saved, changes) == (0, 3)
    assert stored["depth_bias"] == 0.7 and "shadow_bias" not in stored
    assert stored["layers"][0]["blur"] == {"size": 9}
    assert stored["layers"][1]["glow"] == {"radius": 3}  # other effects untouched
    assert stored["layers"][2]["blur"] == {"sigma": 2.0}
    assert stored["schema_version"] == 3
    # Already current: nothing happens.
    assert settings.upgrade(stored, upgrades, current=3) == (3, 0)


def test_upgrade_leaves_a_file_from_a_newer_version_alone():
    stored = {"schema_version": 9, "x": 1}
    assert settings.upgrade(stored, {1: (settings.Rename("x", "y"),)}, current=1) == (9, 0)
    assert stored == {"schema_version": 9, "x": 1}


def test_renumber_maps_stored_enum_numbers():
    stored = {"schema_version": 1, "shadow_filter": 3}
    settings.upgrade(stored, {2: (settings.Renumber("shadow_filter", ((3, 4), (4, 3))),)}, current=2)
    assert stored["shadow_filter"] == 4
