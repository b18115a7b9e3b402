"""Post-stack presets: save, reload, and the shipped looks."""

import bpy
import numpy as np
import pytest

from devkit import scenes
from devkit.render import render
from devkit.session import ROOT


def stack(settings):
    """Every layer's effect, name, switches and parameter values, comparable with ==."""
    from penumbra.engine.post import EFFECTS

    out = []
    for layer in settings.layers:
        group = layer.params()
        values = []
        for p in EFFECTS[layer.effect].params:
            v = getattr(group, p.name)
            if p.type == "COLOR":
                v = tuple(round(x, 5) for x in v)
            elif p.type == "FLOAT":
                v = round(v, 5)
            elif p.type == "IMAGE":
                v = v.name if v is not None else None
            values.append((p.name, v))
        out.append((layer.effect, layer.name, layer.enabled, layer.solo, round(layer.mix, 5), tuple(values)))
    return out


def load(path):
    return bpy.ops.script.execute_preset(filepath=str(path), menu_idname="PENUMBRA_MT_post_presets")


def test_save_and_load_round_trip(penumbra, user_home):
    from penumbra.operators.presets import user_preset_dir

    scene = scenes.demo_scene(32, 32)
    s = scene.penumbra
    s.layers[0].blur.radius, s.layers[0].mix, s.layers[1].enabled = 9, 0.4, False
    s.layers[1].vignette.color = (0.2, 0.1, 0.05)
    s.layers[1].solo = True
    before = stack(s)
    assert bpy.ops.penumbra.post_preset_add(name="My Look") == {"FINISHED"}
    path = user_preset_dir() / "My_Look.py"
    assert path.is_file()
    assert path.resolve().is_relative_to(user_home.resolve())  # the test HOME, never a real user's config
    bpy.ops.penumbra.layer_remove()
    s.layers[0].blur.radius = 1
    load(path)
    assert stack(s) == before
    # Removing the active user preset deletes its file.
    assert bpy.ops.penumbra.post_preset_add(remove_active=True) == {"FINISHED"}
    assert not path.exists()


def test_preset_add_needs_a_name(penumbra):
    scenes.demo_scene(32, 32)
    with pytest.raises(RuntimeError, match="needs a name"):
        bpy.ops.penumbra.post_preset_add(name="  ")


def shipped():
    return sorted((ROOT / "presets" / "post_stack").glob("*.py"))


@pytest.mark.parametrize("path", shipped(), ids=lambda p: p.stem)
def test_shipped_presets_load_and_change_the_image(penumbra, path):
    scene = scenes.demo_scene(96, 54)
    scene.penumbra.layers.clear()
    plain = render(scene)["Combined"]
    load(path)
    assert len(scene.penumbra.layers) >= 2
    styled = render(scene)["Combined"]
    assert np.all(np.isfinite(styled))
    assert np.abs(styled - plain).mean() > 0.01


def _write_preset(tmp_path, layers):
    import json

    path = tmp_path / "preset.py"
    data = json.dumps({"format": 1, "layers": layers})
    path.write_text(f"import bpy\nbpy.ops.penumbra.post_stack_apply(stack={data!r})\n", encoding="utf-8")
    return path


def test_a_preset_with_an_unknown_effect_changes_nothing(penumbra, tmp_path):
    scene = scenes.demo_scene(32, 32)
    before = stack(scene.penumbra)
    path = _write_preset(tmp_path, [{"effect": "BLUR", "params": {"radius": 2}}, {"effect": "BLOOM_X"}])
    with pytest.raises(RuntimeError, match="unknown effect 'BLOOM_X'.*stack is unchanged|stack is unchanged.*BLOOM_X"):
        load(path)
    assert stack(scene.penumbra) == before


def test_a_preset_with_a_malformed_value_changes_nothing(penumbra, tmp_path):
    scene = scenes.demo_scene(32, 32)
    before = stack(scene.penumbra)
    path = _write_preset(
        tmp_path, [{"effect": "GLOW", "mix": "half"}, {"effect": "FISHEYE", "params": {"edge": "WRAP"}}]
    )
    with pytest.raises(RuntimeError) as info:
        load(path)
    assert "mix must be a number" in str(info.value) and "unknown fisheye edge 'WRAP'" in str(info.value)
    assert stack(scene.penumbra) == before


def test_unknown_fields_are_reported_and_the_rest_applied(penumbra, tmp_path, capfd):
    scene = scenes.demo_scene(32, 32)
    layers = [{"effect": "BLUR", "name": "Soft", "mix": 0.5, "glare": 1, "params": {"radius": 7, "shape": "star"}}]
    load(_write_preset(tmp_path, layers))
    captured = capfd.readouterr()
    messages = captured.out + captured.err
    assert "unknown field 'glare' skipped" in messages and "unknown parameter 'shape' skipped" in messages
    (layer,) = scene.penumbra.layers
    assert (layer.effect, layer.name, layer.mix, layer.blur.radius) == ("BLUR", "Soft", 0.5, 7)
