"""Material › Settings › Backface Culling, as EEVEE reads it: Camera hides the faces turned
away from the camera, Shadow keeps them out of the shadow maps. Checked on pixels: a card seen
from behind, a mirrored card, and a card over a ground under a sun."""

import math

import numpy as np

from devkit import scenes
from devkit.render import engine_frame

WORLD = (0.2, 0.3, 0.4)


def _card_scene(facing_camera, mirrored=False):
    """A 4 m card 5 m in front of the camera, its normal towards the camera or away from it."""
    scene = scenes.empty_scene(64, 48)
    scenes.set_world(scene, WORLD)
    mat = scenes.material("Card", (0.8, 0.1, 0.1))
    card = scenes.plane(scene, "Card", size=4.0, mat=mat)
    card.rotation_euler = (math.radians(90.0 if facing_camera else -90.0), 0.0, 0.0)  # normal -Y or +Y
    if mirrored:
        card.scale = (-1.0, 1.0, 1.0)  # mirrors the winding, not the side it faces
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(60), 0.0, 0.0))
    scenes.look_at(scene, (0.0, -5.0, 0.0), (0.0, 0.0, 0.0))
    return scene, mat


def _centre(image):
    h, w = image.shape[:2]
    return image[h // 2 - 4 : h // 2 + 4, w // 2 - 4 : w // 2 + 4, :3]


def test_camera_culling_hides_only_faces_turned_away(penumbra, gpu_call):
    for facing, mirrored in ((True, False), (False, False), (True, True)):
        scene, mat = _card_scene(facing, mirrored)
        _stats, drawn = engine_frame(gpu_call, scene, 64, 48)
        assert np.abs(_centre(drawn) - WORLD).max() > 0.05  # two-sided by default: the card covers it
        mat.use_backface_culling = True
        _stats, culled = engine_frame(gpu_call, scene, 64, 48)
        if facing:  # its front is towards the camera, mirrored or not: still drawn, unchanged
            np.testing.assert_allclose(culled, drawn, atol=1e-6)
        else:  # seen from behind: the world shows through
            np.testing.assert_allclose(_centre(culled), np.broadcast_to(WORLD, (8, 8, 3)), atol=1e-5)


def _shadow_scene(card_faces_light):
    """A sun straight above; a 2 m card 1 m over a ground, its normal up (towards the light) or
    down (away from it)."""
    scene = scenes.empty_scene(64, 48)
    scenes.set_world(scene, (0.0, 0.0, 0.0))
    ground = scenes.material("Ground", (0.8, 0.8, 0.8))
    scenes.plane(scene, "Ground", size=12.0, mat=ground)
    mat = scenes.material("Card", (0.8, 0.8, 0.8))
    card = scenes.plane(scene, "Card", size=2.0, mat=mat)
    card.location.z = 1.0
    if not card_faces_light:
        card.rotation_euler = (math.pi, 0.0, 0.0)
    scenes.light(scene, "Sun", "SUN", 3.0)
    scenes.look_at(scene, (0.0, -6.0, 6.0), (0.0, 0.0, 0.0))
    return scene, mat, card


def _shadowed_fraction(image):
    return float((image[..., :3].sum(axis=-1) < 0.05).mean())


def test_shadow_culling_drops_the_shadow_of_faces_turned_away_from_the_light(penumbra, gpu_call):
    for faces_light in (True, False):
        scene, mat, card = _shadow_scene(faces_light)
        card.hide_render = True
        _stats, image = engine_frame(gpu_call, scene, 64, 48)
        no_card = _shadowed_fraction(image)  # the black background beyond the ground
        card.hide_render = False
        _stats, image = engine_frame(gpu_call, scene, 64, 48)
        shadowed = _shadowed_fraction(image)
        assert shadowed > no_card + 0.01  # both sides cast by default
        mat.use_backface_culling_shadow = True
        _stats, culled = engine_frame(gpu_call, scene, 64, 48)
        if faces_light:
            assert _shadowed_fraction(culled) == shadowed
        else:
            assert _shadowed_fraction(culled) == no_card


def _closed_scene():
    """Closed meshes over a ground: the Spot cow, a box and a mirrored box, under a sun and a
    spot light (an orthographic and a perspective map)."""
    import bpy

    from devkit import assets

    scene = scenes.empty_scene(96, 64)
    scenes.set_world(scene, WORLD)
    white = scenes.material("White", (0.8, 0.8, 0.8))
    scenes.plane(scene, "Ground", size=12.0, mat=white)
    cow = assets.import_mesh(scene, assets.SPOT, height=1.2, name="Cow")
    cow.data.materials.append(scenes.material("Cow", (0.7, 0.5, 0.3)))
    scenes.box(scene, "Box", center=(1.6, 0.5, 0.5), size=(0.8, 0.8, 1.0), mat=white)
    mirrored = scenes.box(scene, "Mirrored", center=(0.0, 0.0, 0.0), size=(0.6, 0.6, 0.6), mat=white)
    mirrored.location, mirrored.scale = (-1.6, 0.3, 0.4), (-1.0, 1.0, 1.0)
    scenes.light(scene, "Sun", "SUN", 2.0, rotation=(math.radians(40), 0.0, math.radians(30)))
    scenes.light(scene, "Spot", "SPOT", 600.0, location=(1.0, -2.5, 4.0), rotation=(math.radians(30), 0.0, 0.0))
    scenes.look_at(scene, (0.5, -5.0, 3.0), (0.0, 0.0, 0.5))
    bpy.context.view_layer.update()
    return scene


def test_closed_meshes_seen_from_outside_draw_no_back_faces_and_look_the_same(penumbra, gpu_call, monkeypatch):
    """A closed, outward-facing mesh wholly beyond the camera's near plane (and in front of a
    light) hides its back faces behind its own front faces: drawing it without them changes
    nothing, in the image or in the shadows, mirrored or not."""
    from penumbra.engine.frame import draw_list

    scene = _closed_scene()
    stats, culled = engine_frame(gpu_call, scene, 96, 64)
    # Lit pass: cow, box, mirrored box; the sun's map and the spot's map: each caster it holds.
    assert stats.closed_culled >= 3 + 3 + 1
    monkeypatch.setattr(draw_list, "CULL_CLOSED", False)
    whole_stats, whole = engine_frame(gpu_call, scene, 96, 64)
    assert whole_stats.closed_culled == 0
    np.testing.assert_allclose(culled, whole, rtol=0, atol=1e-5)
    assert np.abs(whole[..., :3] - WORLD).max(axis=-1).mean() > 0.3  # the scene covers the frame


def test_a_camera_inside_a_closed_mesh_sees_its_back_faces(penumbra, gpu_call, monkeypatch):
    """A room modelled as an outward-facing box, seen from inside: its walls are back faces,
    and the camera's view is not culled."""
    from penumbra.engine.frame import draw_list

    scene = scenes.empty_scene(64, 48)
    scenes.set_world(scene, WORLD)
    wall = scenes.material("Wall", (0.9, 0.2, 0.2))
    scenes.box(scene, "Room", center=(0.0, 0.0, 1.5), size=(6.0, 6.0, 3.0), mat=wall)
    scenes.light(scene, "Lamp", "POINT", 200.0, location=(0.0, 0.0, 2.5))
    scenes.look_at(scene, (0.0, -2.0, 1.5), (0.0, 2.0, 1.2))
    _stats, inside = engine_frame(gpu_call, scene, 64, 48)
    assert np.abs(_centre(inside) - WORLD).max() > 0.1  # the wall, not the world
    monkeypatch.setattr(draw_list, "CULL_CLOSED", False)
    _stats, whole = engine_frame(gpu_call, scene, 64, 48)
    np.testing.assert_allclose(inside, whole, rtol=0, atol=1e-6)
