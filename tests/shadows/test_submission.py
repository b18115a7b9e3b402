"""Shadow-map submission (``ShadowAtlas.render``): each opaque caster batch is drawn once for
every map of the sample it is in (instanced, each instance confined to its tile), so a
frame's draw calls do not grow with its maps: more lights, more world directions, the same
calls per caster batch."""

import math

import numpy as np

from devkit import scenes
from devkit import world_scenes as ws

WIDTH, HEIGHT = 64, 36
BOXES = 6


def _scene(spots=0, sun=True):
    scene = scenes.empty_scene(WIDTH, HEIGHT)
    scenes.set_world(scene, (0.0, 0.0, 0.0))
    scenes.plane(scene, "Ground", size=20.0)
    for k in range(BOXES):
        angle = 2.0 * math.pi * k / BOXES
        scenes.box(scene, f"Box{k}", center=(2.0 * math.cos(angle), 2.0 * math.sin(angle), 0.5), size=(0.6, 0.6, 1.0))
    if sun:
        scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.5, 0.2, 0.3))
    for k in range(spots):
        angle = 2.0 * math.pi * (k + 0.5) / max(spots, 1)
        spot = scenes.light(
            scene, f"Spot{k}", "SPOT", 200.0, location=(4.0 * math.cos(angle), 4.0 * math.sin(angle), 4.0)
        )
        spot.data.spot_size = math.radians(70.0)
        scenes.aim(spot, (0.0, 0.0, 0.0))
    scenes.look_at(scene, (0.0, -8.0, 6.0), (0.0, 0.0, 0.0))
    return scene


def _frame_stats(gpu_call, scene, samples=1):
    from penumbra.engine.scene.extract import camera_from_scene

    def job(engine, depsgraph):
        cam = camera_from_scene(depsgraph, scene, WIDTH, HEIGHT)
        out = engine.render_frame(depsgraph, cam, WIDTH, HEIGHT, samples=(0, samples), sample_count=samples, aux=False)
        return out.stats, out.color_array().copy()

    return gpu_call(job)


def test_more_spot_lights_add_maps_but_no_draw_calls(penumbra, gpu_call):
    """One spot light and eight: eight times the maps, the same shadow draw calls (one per
    caster batch), and each spot's light still shadowed (the boxes' shadows differ)."""
    one, one_image = _frame_stats(gpu_call, _scene(spots=1, sun=False))
    eight, eight_image = _frame_stats(gpu_call, _scene(spots=8, sun=False))
    assert eight.shadow_maps >= 8 * one.shadow_maps >= 8, (one.shadow_maps, eight.shadow_maps)
    assert eight.shadow_draws == one.shadow_draws <= BOXES + 1, (one.shadow_draws, eight.shadow_draws)
    assert not np.allclose(one_image, eight_image)


def test_world_directions_add_maps_but_no_draw_calls_per_map(penumbra, gpu_call):
    """A sky-lit frame of 4 samples with 1 and with 4 world directions per sample: four times
    the world's maps, and at most one more call per caster batch and sample for all of them
    (orthographic maps a caster crosses the near plane of take the program that writes each
    fragment's depth: two groups at most), never one per map."""
    stats = {}
    for directions in (1, 4):
        scene = _scene(sun=False)  # lit by the sky alone: it takes every direction it is given
        ws.uniform_sky(scene, ws.SKY_COLOR, 0.5)
        scene.penumbra.world_samples = directions
        scene.penumbra.world_ao = False
        scene.penumbra.use_adaptive_sampling = False
        stats[directions] = _frame_stats(gpu_call, scene, samples=4)[0]
    batches = BOXES + 1
    assert stats[4].world_directions == 4 * stats[1].world_directions == 16
    assert stats[4].shadow_maps >= stats[1].shadow_maps + 3 * 4 - 1, (stats[1].shadow_maps, stats[4].shadow_maps)
    assert stats[4].shadow_draws <= stats[1].shadow_draws + batches * 4, (stats[1].shadow_draws, stats[4].shadow_draws)
    assert stats[4].shadow_draws <= 2 * batches * 4, stats[4].shadow_draws


def test_world_directions_follow_the_worlds_share_of_the_light(penumbra, gpu_call):
    """A sky alone takes the 4 directions per sample it is given; under a sun 20 times its
    irradiance, one (its shadows are still all that lights the sun's shadows); a black world
    none (``world.directions.light_share``)."""
    counts = {}
    for name, sky, sun in (("sky", 0.5, False), ("sun", 0.05, True), ("black", 0.0, True)):
        scene = _scene(sun=sun)
        ws.uniform_sky(scene, (1.0, 1.0, 1.0), sky)
        scene.penumbra.world_samples = 4
        scene.penumbra.world_ao = False
        scene.penumbra.use_adaptive_sampling = False
        counts[name] = _frame_stats(gpu_call, scene, samples=4)[0].world_directions
    assert counts == {"sky": 16, "sun": 4, "black": 0}, counts


def test_sixteen_samples_issue_at_most_sixteen_times_one_samples_calls(penumbra, gpu_call):
    scene = _scene(spots=2)
    scene.penumbra.use_adaptive_sampling = False
    one = _frame_stats(gpu_call, scene, samples=1)[0]
    sixteen = _frame_stats(gpu_call, scene, samples=16)[0]
    assert sixteen.draws <= 16 * one.draws, (one.draws, sixteen.draws)


def test_a_world_under_the_noise_threshold_takes_no_directions_nor_occlusion(penumbra, gpu_call):
    """A world whose whole light is under the frame's Noise Threshold (``world_negligible``:
    radiance 2e-5, sqrt 0.0045 < 0.01) costs no shadow map and no ambient occlusion prepass,
    and still lights every surface (unshadowed); one twenty times brighter pays for both, and
    so does the dim one in a frame without adaptive sampling (its threshold then 0.001)."""
    from penumbra.engine.frame.sampling import Adaptive
    from penumbra.engine.scene.extract import camera_from_scene

    counts = {}
    for radiance, threshold in ((2e-5, 0.01), (4e-4, 0.01), (2e-5, 0.0), (0.0, 0.01)):
        scene = _scene(sun=True)
        ws.uniform_sky(scene, (1.0, 1.0, 1.0), radiance)
        scene.penumbra.world_samples = 4
        scene.penumbra.world_ao = True

        def job(engine, depsgraph, scene=scene, threshold=threshold):
            cam = camera_from_scene(depsgraph, scene, WIDTH, HEIGHT)
            adaptive = Adaptive(threshold=threshold, min_samples=64) if threshold else None
            out = engine.render_frame(depsgraph, cam, WIDTH, HEIGHT, samples=(0, 4), sample_count=4, aux=False,
                                      adaptive=adaptive)  # fmt: skip
            return out.stats.world_directions, out.stats.ao_prepasses, out.color_array().copy()

        counts[(radiance, threshold)] = job_result = gpu_call(job)
        assert np.all(np.isfinite(job_result[2]))
    directions, prepasses, image = counts[(2e-5, 0.01)]
    assert (directions, prepasses) == (0, 0), counts
    bright = counts[(4e-4, 0.01)]
    assert bright[0] > 0 and bright[1] > 0, bright[:2]
    unthresholded = counts[(2e-5, 0.0)]
    assert unthresholded[0] > 0 and unthresholded[1] > 0, unthresholded[:2]
    # The negligible world still lights every surface, unshadowed: over the same frame with a
    # black world it adds about its radiance times the surfaces' albedo, nowhere more than it
    # (diffuse and specular each at most 2e-5).
    added = image[..., :3] - counts[(0.0, 0.01)][2][..., :3]
    assert added.min() > 0.2 * 2e-5 and added.max() <= 4e-5, (added.min(), added.max())
