"""Light and shadow linking (Object > Light Linking / Shadow Linking on a light), read as
Blender's engines read them: a collection's objects set to Include are the only ones linked
when there is any; otherwise everything but the excluded ones; a child collection's state
holds for all it holds. Each case is checked against renders that need no linking."""

import numpy as np
import pytest

from devkit import scenes
from devkit.render import render

SIZE = (64, 48)


def _scene():
    scene = scenes.empty_scene(*SIZE)
    scenes.plane(scene, "Ground", size=10.0, mat=scenes.white())
    scenes.uv_sphere(scene, "A", center=(-1.2, 0.0, 0.6), radius=0.6, mat=scenes.white())
    scenes.uv_sphere(scene, "B", center=(1.2, 0.0, 0.6), radius=0.6, mat=scenes.white())
    scenes.light(scene, "L", "POINT", 500.0, location=(0.4, -2.0, 4.0), shadow_soft_size=0.0)
    scenes.look_at(scene, (0.0, -6.0, 4.0), (0.0, 0.0, 0.5))
    scene.penumbra.render_samples = 1
    return scene


def _link(scene, kind, entries):
    """Give light L a ``kind`` ('receiver' or 'blocker') collection of ``entries``: (object
    name, state), or (child collection of those object names, state)."""
    _link_light(scene, scene.objects["L"], entries, kind)


def _link_light(scene, light, entries, kind="receiver"):
    import bpy

    top = bpy.data.collections.new(f"{kind}s")
    for what, state in entries:
        if isinstance(what, tuple):
            child = bpy.data.collections.new(f"{kind} child")
            for name in what:
                child.objects.link(scene.objects[name])
            top.children.link(child)
            top.collection_children[-1].light_linking.link_state = state
        else:
            top.objects.link(scene.objects[what])
            top.collection_objects[-1].light_linking.link_state = state
    setattr(light.light_linking, f"{kind}_collection", top)


def _covers(name):
    """Pixels where object ``name`` is seen (it renders as a hole when held out)."""
    scene = _scene()
    scene.objects[name].is_holdout = True
    return render(scene)["Combined"][..., 3] < 0.5


@pytest.mark.parametrize(
    "entries, lit",
    [
        ([("A", "INCLUDE")], {"A"}),
        ([("A", "EXCLUDE")], {"B", "Ground"}),
        ([("Ground", "INCLUDE"), (("B",), "EXCLUDE")], {"Ground"}),
        ([(("A", "B"), "EXCLUDE")], {"Ground"}),
    ],
)
def test_light_linking_lights_only_the_linked_objects(penumbra, entries, lit):
    """Where a linked object is seen: the image with every object lit; elsewhere: the image
    without the light (shadows still fall: blocking is shadow linking's business)."""
    full = render(_scene())["Combined"]
    scene = _scene()
    scene.objects["L"].data.energy = 0.0
    dark = render(scene)["Combined"]
    scene = _scene()
    _link(scene, "receiver", entries)
    linked = render(scene)["Combined"]
    masks = {name: _covers(name) for name in ("A", "B")}
    masks["Ground"] = ~(masks["A"] | masks["B"]) & (full[..., 3] > 0.5)
    expected = dark.copy()
    for name in lit:
        expected[masks[name]] = full[masks[name]]
    assert np.abs(full - dark).max() > 0.1  # the light matters
    np.testing.assert_allclose(linked, expected, atol=1e-5)


@pytest.mark.parametrize("entries", [[("B", "INCLUDE")], [("A", "EXCLUDE")]])
def test_shadow_linking_lets_only_the_linked_objects_cast(penumbra, entries):
    """Only B blocks the light: the image of A with Ray Visibility > Shadow off (the map's fit
    still counts A's box, so the two agree to the shadow edges' filtering)."""
    scene = _scene()
    scene.objects["A"].visible_shadow = False
    reference = render(scene)["Combined"]
    scene = _scene()
    _link(scene, "blocker", entries)
    linked = render(scene)["Combined"]
    both = render(_scene())["Combined"]
    diff = np.abs(linked - reference).max(axis=-1)
    assert np.abs(both - reference).max(axis=-1).sum() > 20 * diff.sum() + 1.0  # A's shadow is gone
    assert diff.mean() < 2e-3 and np.mean(diff > 0.05) < 0.005, (diff.mean(), np.mean(diff > 0.05))


def test_an_instance_is_linked_through_its_instancer(penumbra):
    """A collection instance: linking its instancer (the empty) links what it instances."""
    import bpy

    scene = _scene()
    source = bpy.data.collections.new("Source")
    scene.collection.children.link(source)
    for name in ("A",):
        scene.collection.objects.unlink(scene.objects[name])
        source.objects.link(bpy.data.objects[name])
    scene.view_layers[0].layer_collection.children["Source"].exclude = True
    empty = bpy.data.objects.new("AInstance", None)
    empty.instance_type, empty.instance_collection = "COLLECTION", source
    scene.collection.objects.link(empty)
    plain = render(scene)["Combined"]
    _link(scene, "receiver", [("AInstance", "EXCLUDE")])
    excluded = render(scene)["Combined"]
    a = _covers("A")
    assert np.abs(plain[a] - excluded[a]).max() > 0.1  # the instance is no longer lit
    np.testing.assert_allclose(excluded[~a], plain[~a], atol=1e-5)


def test_masks_carry_lights_past_the_first_word(penumbra):
    """``draw_list.light_masks``: bit j of word j // 32 for the j-th light in shading order;
    bit 31 is stored as a negative int (the shader reads the words as signed)."""
    from types import SimpleNamespace

    from penumbra.engine.frame.draw_list import light_masks
    from penumbra.engine.scene.extract import Light, LinkSet

    def light(excluded=()):
        out = Light(type="POINT", color=np.ones(3), matrix=np.eye(4), radius=0.0)
        out.receivers = LinkSet(exclude=frozenset(excluded)) if excluded else None
        return out

    lights = [light() for _ in range(40)]
    lights[5], lights[33] = light({"A"}), light({"B"})
    order = list(range(40))[::-1]  # shading order: light 39 first
    draws = [SimpleNamespace(instance=SimpleNamespace(names=(n,))) for n in ("A", "B", "C")]
    masks = light_masks(draws, lights, order)
    as_bits = {
        n: [((w & 0xFFFFFFFF) >> b) & 1 for w in masks[id(d)][:2] for b in range(32)] for n, d in zip("ABC", draws)
    }
    for name, off in (("A", 5), ("B", 33)):
        bits = as_bits[name]
        assert bits[order.index(off)] == 0 and sum(bits[:40]) == 39 and sum(bits[40:]) == 0
    assert sum(as_bits["C"]) == 40 and masks[id(draws[2])][0] == -1  # all 32 bits: -1 as a signed int


def test_linking_reaches_lights_past_the_first_mask_word(penumbra):
    """40 lights (no maps), the 36th (index 35) excluded from A: A's pixels equal the render
    with that light switched off, the rest equal the render with it on."""
    import bpy

    def scene_with(energy_35, exclude):
        scene = _scene()
        bpy.data.objects.remove(scene.objects["L"])
        for k in range(40):
            light = scenes.light(scene, f"L{k:02d}", "POINT", 2.0, location=(k * 0.1 - 2.0, -2.0, 4.0))
            light.data.use_shadow = False
            if k == 35:
                light.data.energy = energy_35
                if exclude:
                    _link_light(scene, light, [("A", "EXCLUDE")])
        return scene

    on = render(scene_with(800.0, False))["Combined"]
    off = render(scene_with(0.0, False))["Combined"]
    linked = render(scene_with(800.0, True))["Combined"]
    a = _covers("A")
    assert np.abs(on[a] - off[a]).max() > 0.1
    np.testing.assert_allclose(linked[a], off[a], atol=1e-5)
    np.testing.assert_allclose(linked[~a], on[~a], atol=1e-5)
