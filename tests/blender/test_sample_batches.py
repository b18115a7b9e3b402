"""A frame's samples in batches (``Renderer._batch``, ``ShadowPass.batches``): the maps of a
batch's samples are planned first, placed in one atlas and drawn together, one instanced
draw per caster batch, then each sample's lit pass reads its own. The image is the same
whatever the batch size; the draw calls into maps grow with the batches, not the samples.
A renderer let go frees its GPU objects at once, not when the cycle collector runs."""

import numpy as np
import pytest

from devkit import scenes

SIZE = (64, 36)


def _frames(gpu_call, scene, samples, batch_sizes, budget=None):
    """Per batch size: (image, FrameStats) of a ``samples``-sample frame of ``scene``, each
    from a fresh renderer (nothing kept between them); ``budget``: MAP_BATCH_BYTES then."""

    def job(engine, depsgraph):
        from penumbra.engine.frame import renderer, shadow_pass
        from penumbra.engine.frame.film import texture_array
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, scene, *SIZE)
        kept = renderer.MAP_BATCH, shadow_pass.MAP_BATCH_BYTES
        out = {}
        try:
            if budget is not None:
                shadow_pass.MAP_BATCH_BYTES = budget
            for size in batch_sizes:
                renderer.MAP_BATCH = size
                engine.renderer = None  # a fresh renderer: its atlas holds nothing yet
                frame = engine.render_frame(depsgraph, camera, *SIZE, samples=(0, samples), sample_count=samples)
                out[size] = (texture_array(frame.color, 4).copy(), frame.stats)
        finally:
            renderer.MAP_BATCH, shadow_pass.MAP_BATCH_BYTES = kept
        return out

    return gpu_call(job)


@pytest.fixture(scope="module")
def demo(penumbra):
    return scenes.bare_demo(*SIZE)


def test_the_image_does_not_depend_on_the_batch_size(demo, gpu_call):
    """The demo (a sun, a spot and an area light that move between samples, the world's
    directions with maps) at 12 samples, one sample at a time, in batches of 5 (1 + 5 + 5 +
    1: the first sample is a batch of its own) and of 8 (1 + 8 + 3): the same samples, the
    same maps (placed elsewhere in a larger atlas), so the same image within ``_close``: a
    map placed elsewhere may rasterise a texel's edge otherwise (the GL leaves a
    rasteriser's subpixel precision to the implementation; on llvmpipe here the frames are
    equal bit for bit)."""
    kept = demo.penumbra.world_shadows
    demo.penumbra.world_shadows = True
    try:
        frames = _frames(gpu_call, demo, 12, (1, 5, 8))
    finally:
        demo.penumbra.world_shadows = kept
    one, stats_one = frames[1]
    assert stats_one.world_directions > 0 and stats_one.lights_sampled >= 2
    for size in (5, 8):
        image, stats = frames[size]
        assert stats.samples == stats_one.samples == 12
        # Maps alike in two samples (the world's sun's, without jitter) are drawn once; every
        # sample's maps are drawn or reused either way.
        assert stats.shadow_maps <= stats_one.shadow_maps
        assert stats.shadow_maps + stats.shadow_maps_reused == stats_one.shadow_maps + stats_one.shadow_maps_reused
        ok, diff = _close(image, one)
        assert ok, (size, diff)
    # A batch draws its maps with as many draw calls as one sample does: 3 batches, not 12.
    assert frames[8][1].shadow_draws < stats_one.shadow_draws / 3


def test_sixteen_samples_draw_their_maps_with_three_times_one_samples_draw_calls(demo, gpu_call):
    """The draw calls into the maps of the scene's lights in a 16-sample frame (the first
    sample, then batches of 8 and 7) are at most three times those of its first sample alone,
    though every sample draws its moving lights' maps (one sample at a time: sixteen times).
    The world's directions are off here: the first sample draws none of theirs (they start at
    the second), so its count is not one sample's worth of them (the next test)."""
    kept = demo.penumbra.world_shadows
    demo.penumbra.world_shadows = False
    try:
        first, whole = _first_and_whole(gpu_call, demo)
    finally:
        demo.penumbra.world_shadows = kept
    assert whole.samples == 16 and whole.lights_sampled >= 2
    assert whole.shadow_maps >= 16 * whole.lights_sampled  # every sample's maps drawn
    assert 0 < whole.shadow_draws <= 3 * first.shadow_draws, (first.shadow_draws, whole.shadow_draws)


def test_the_worlds_directions_draw_their_maps_in_batches_too(demo, gpu_call):
    """The demo at its defaults, the world's directions drawn with maps in every sample but the
    first (new directions each sample): its 16 samples in batches of 8 draw their maps with at
    most a quarter of the draw calls the same frame takes one sample at a time, every sample's
    maps drawn either way."""
    assert demo.penumbra.world_shadows
    frames = _frames(gpu_call, demo, 16, (1, 8))
    (_, one), (_, batched) = frames[1], frames[8]
    assert batched.world_directions == one.world_directions > 0
    assert batched.shadow_maps + batched.shadow_maps_reused == one.shadow_maps + one.shadow_maps_reused
    assert 0 < 4 * batched.shadow_draws <= one.shadow_draws, (one.shadow_draws, batched.shadow_draws)


def _first_and_whole(gpu_call, demo):
    """FrameStats of the demo's first sample alone and of its 16 samples, each from a fresh
    renderer."""

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, demo, *SIZE)
        first = engine.render_frame(depsgraph, camera, *SIZE, samples=(0, 1), sample_count=16).stats
        engine.renderer = None
        whole = engine.render_frame(depsgraph, camera, *SIZE, samples=(0, 16), sample_count=16).stats
        return first, whole

    return gpu_call(job)


@pytest.mark.xfail(
    strict=True,
    reason="the lit pass is drawn once per object and sample, not once per object and batch: "
    "docs/design.md, The lit pass in batches (designed, not built)",
)
def test_sixteen_samples_submit_at_most_twice_one_samples_draw_calls(demo, gpu_call):
    """The target of the GPU frame: a 16-sample frame of the demo submits at most twice the
    draw calls of its first sample alone (maps and lit pass; the accumulations are passes of
    their own, not counted here). Its maps meet it (the test above); its lit pass does not:
    every sample draws each visible object again. Strict: the day the lit pass draws a
    batch's samples together this passes, and the mark must go."""
    assert demo.penumbra.world_shadows  # the demo at its defaults
    first, whole = _first_and_whole(gpu_call, demo)
    assert whole.samples == 16 and first.draws > first.shadow_draws > 0
    lit_first, lit_whole = first.draws - first.shadow_draws, whole.draws - whole.shadow_draws
    # What fails today: the lit pass's draws grow with the samples (one per object a sample).
    assert whole.draws <= 2 * first.draws, (first.draws, whole.draws, lit_first, lit_whole)


def test_a_batch_follows_the_map_memory_budget(demo, gpu_call):
    """With MAP_BATCH_BYTES under two samples' maps, every sample draws its maps alone (a
    batch of one sample's maps is never refused), and the image is the same."""
    frames = _frames(gpu_call, demo, 6, (1, 8), budget=1)
    (one, stats_one), (batched, stats) = frames[1], frames[8]
    assert stats.shadow_draws == stats_one.shadow_draws
    assert np.array_equal(batched, one)


def test_batches_end_where_adaptive_sampling_checks(demo, gpu_call):
    """With a Noise Threshold the frame checks the noise every few samples: batches end there,
    so the frame stops after the same samples, with the same image (within ``_close``), whatever the
    batch size."""
    demo.penumbra.adaptive_threshold = 0.05
    try:
        frames = _frames(gpu_call, demo, 24, (1, 8))
    finally:
        demo.penumbra.adaptive_threshold = 0.0
    (one, stats_one), (batched, stats) = frames[1], frames[8]
    assert stats.samples == stats_one.samples
    assert stats.pixels_converged == stats_one.pixels_converged
    ok, diff = _close(batched, one)
    assert ok, diff


@pytest.mark.parametrize(("final", "released"), [(False, True), (True, True), (False, False)])
def test_a_renderer_let_go_frees_its_gpu_objects_at_once(demo, gpu_call, final, released):
    """``free_gpu`` (the end of every render, inside its GPU context) leaves nothing of the
    renderer for Python's cycle collector: with the collector off, the renderer and its shadow
    atlas (a larger one for a batch of samples) are gone as the engine lets them go. Freed
    later, a framebuffer or a vertex array would be deleted in whatever context is current then
    (another render's, or none): the suite crashed in llvmpipe two tests after such a frame.
    ``final``: a renderer with the final renders' texture pool, whose textures go to it;
    ``released``: let go through ``free_gpu``, or merely dropped (a viewport engine freed)."""
    import gc
    import weakref

    def job(engine, depsgraph):
        from penumbra.engine import gpu_pool
        from penumbra.engine.scene.extract import camera_from_scene

        engine.texture_pool = gpu_pool.FINAL_RENDERS if final else None
        camera = camera_from_scene(depsgraph, demo, *SIZE)
        engine.render_frame(depsgraph, camera, *SIZE, samples=(0, 4), sample_count=4)
        renderer, atlas = weakref.ref(engine.renderer), weakref.ref(engine.renderer.shadows)
        gc.disable()
        try:
            if released:
                engine.free_gpu()
            else:
                engine.renderer = None
            return renderer() is None, atlas() is None
        finally:
            gc.enable()
            engine.texture_pool = None

    assert gpu_call(job) == (True, True)


def _close(image, one):
    """Two frames the same but where a map texel's edge rasterised otherwise: at most 1 % of
    the pixels differ by more than 1e-5, none by more than 1e-3, the mean difference under 1e-6."""
    d = np.abs(image - one)[..., :3].max(axis=-1)
    return d.max() <= 1e-3 and (d > 1e-5).mean() <= 0.01 and d.mean() <= 1e-6, (float(d.max()), float(d.mean()))


def test_a_scene_not_built_for_the_test_keeps_its_image_in_batches(penumbra, gpu_call):
    """Spheres under a real HDRI (its directions drawn with maps) and a 1 m area light, 16
    samples at 96x54, one at a time and in batches: the perspective maps of the area light,
    placed elsewhere in the atlas, may rasterise a texel's edge otherwise (measured: 15 of
    5184 pixels differ by more than 1e-6, the largest by 1.7e-4), so the frames agree within
    ``_close``; the calls into maps fall by more than half. (Last in the file: it loads a
    scene of its own, which ends the module's demo.)"""
    from devkit import reflection_scenes

    scene = reflection_scenes.build("hdri_spheres", 96, 54)
    scenes.light(scene, "Key", "AREA", 200.0, location=(2.0, -2.0, 4.0), size=1.0)

    def job(engine, depsgraph):
        from penumbra.engine.frame import renderer
        from penumbra.engine.frame.film import texture_array
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, scene, 96, 54)
        out, kept = {}, renderer.MAP_BATCH
        try:
            for size in (1, 8):
                renderer.MAP_BATCH = size
                engine.renderer = None
                frame = engine.render_frame(depsgraph, camera, 96, 54, samples=(0, 16), sample_count=16)
                out[size] = (texture_array(frame.color, 4).copy(), frame.stats)
        finally:
            renderer.MAP_BATCH = kept
        return out

    frames = gpu_call(job)
    (one, stats_one), (batched, stats) = frames[1], frames[8]
    assert stats_one.world_directions > 0 and stats_one.lights_sampled >= 1
    ok, diff = _close(batched, one)
    assert ok, diff
    assert stats.shadow_draws < stats_one.shadow_draws / 2, (stats.shadow_draws, stats_one.shadow_draws)
