"""The frame's techniques as modules (engine/frame/features/): each is registered once, and a
renderer made without one of them renders the frame without that technique and with every
other one. Checked on one scene that needs the four (the world's ratio and occlusion, the
bounce, settling): the technique's own mark is gone (the frame's ``stats.techniques``, its
prepass, settled pixels, reflective programs, the film's ratio targets), the others' marks
stay, and the picture changes where the technique changed it, finite and never negative."""

import math

import numpy as np
import pytest

from devkit import scenes

SIZE = (64, 36)
SAMPLES = 8
FOUR = ("world_ratio", "world_occlusion", "bounce", "settling")


def _scene():
    scene = scenes.empty_scene(*SIZE)
    scenes.set_world(scene, (0.4, 0.45, 0.5))
    scenes.box_over_plane(scene, mat=scenes.material("Red", (0.8, 0.2, 0.1)))
    sun = scenes.light(scene, "Sun", "SUN", 3.0, rotation=(math.radians(35), 0, math.radians(30)))
    sun.data.angle = math.radians(8)
    scenes.look_at(scene, (6.0, -6.0, 5.0), (0.0, 0.0, 0.8))
    p = scene.penumbra
    p.world_shadows = True
    p.world_ao = True
    p.indirect_bounces = 1
    return scene


def _frame(gpu_call, scene, without=None):
    """(image, stats, lit program names, the film's ratio) of an 8-sample settled frame of a
    renderer whose registry leaves out the technique named ``without``."""
    from penumbra.engine.frame.features import REGISTRY
    from penumbra.engine.frame.renderer import Renderer
    from penumbra.engine.frame.sampling import adaptive_settings
    from penumbra.engine.scene.extract import camera_from_scene

    def job(engine, depsgraph):
        engine.renderer = Renderer(features=tuple(f for f in REGISTRY if f.name != without))
        cam = camera_from_scene(depsgraph, scene, *SIZE)
        adaptive = adaptive_settings(True, 0.01, 0, 0.0, SAMPLES)
        out = engine.render_frame(
            depsgraph, cam, *SIZE, aux=False, samples=(0, SAMPLES), sample_count=SAMPLES, adaptive=adaptive
        )
        names = {key[0] for key in engine.renderer.shaders._cache if key[0].startswith("lit")}
        return (
            out.color_array().copy(),
            out.stats,
            names,
            any(p.name == "world_ratio" for p in engine.renderer.film.parts),
        )

    return gpu_call(job)


def _marks(stats, names, ratio):
    """Which of the four techniques left their mark on the frame."""
    return {
        "world_ratio": bool(ratio) and stats.world_directions > 0,
        "world_occlusion": stats.ao_prepasses > 0,
        "bounce": any("_rsm" in n for n in names),
        "settling": stats.pixels_settled > 0,
    }


@pytest.fixture(scope="module")
def whole(gpu_call, penumbra):
    scene = _scene()
    return scene, _frame(gpu_call, scene)


def test_every_technique_is_registered_once_with_its_own_name():
    from penumbra.engine.frame.features import REGISTRY

    names = [f.name for f in REGISTRY]
    assert len(set(names)) == len(names) and set(FOUR) <= set(names)
    assert {"depth_of_field", "motion_blur"} <= set(names)


def test_the_scene_takes_all_four_techniques(whole):
    _scene_, (image, stats, names, ratio) = whole
    assert set(FOUR) <= set(stats.techniques)
    assert all(_marks(stats, names, ratio).values()), _marks(stats, names, ratio)
    assert np.all(np.isfinite(image)) and image.min() >= 0.0


@pytest.mark.parametrize("name", FOUR)
def test_a_technique_left_out_of_the_registry_is_off_and_the_frame_renders(gpu_call, whole, name):
    scene, (full, *_rest) = whole
    image, stats, names, ratio = _frame(gpu_call, scene, without=name)
    marks = _marks(stats, names, ratio)
    assert name not in stats.techniques
    assert not marks[name], f"{name} still left its mark"
    assert all(marks[other] for other in FOUR if other != name), marks
    assert np.all(np.isfinite(image)) and image.min() >= 0.0
    assert image[..., 3].min() > 0.99  # every pixel drawn (the world behind the scene)
    # Without it the picture changes (settling changes it by design only within its threshold).
    if name != "settling":
        assert np.abs(image[..., :3] - full[..., :3]).max() > 1e-3


def test_a_frames_lit_programs_are_listed_as_keys_and_compile_ahead(gpu_call, whole):
    """Each lit program a frame draws with is one ``programs.LitKey`` (its techniques' parts
    among its parts), listed in the frame's ``stats.lit_keys``: compiled ahead into a fresh
    cache (``programs.precompile``), each key is one program, and the same frame rendered with
    that cache compiles no lit program of its own."""
    scene, (_image, stats, _names, _ratio) = whole
    keys = stats.lit_keys
    parts = {part.name for key in keys for part in key.parts}
    assert {"ratio1", "ao", "rsm", "pilot", "settle"} <= parts, parts
    assert len({hash(key) for key in keys}) == len(keys)

    def job(engine, depsgraph):
        from penumbra.engine.frame.programs import precompile
        from penumbra.engine.frame.renderer import Renderer
        from penumbra.engine.frame.sampling import adaptive_settings
        from penumbra.engine.scene.extract import camera_from_scene
        from penumbra.shaders.loader import ShaderCache

        cache = ShaderCache()
        ahead = precompile(cache, keys)
        lit_before = {k for k in cache._cache if k[0].startswith("lit")}
        engine.renderer = Renderer(shaders=cache)
        cam = camera_from_scene(depsgraph, scene, *SIZE)
        adaptive = adaptive_settings(True, 0.01, 0, 0.0, SAMPLES)
        out = engine.render_frame(
            depsgraph, cam, *SIZE, aux=False, samples=(0, SAMPLES), sample_count=SAMPLES, adaptive=adaptive
        )
        lit_after = {k for k in cache._cache if k[0].startswith("lit")}
        return ahead, len(lit_before), lit_after - lit_before, out.stats.lit_keys

    ahead, compiled, new, again = gpu_call(job)
    assert ahead == compiled == len(keys)
    assert not new, new
    assert again == keys
