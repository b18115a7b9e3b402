"""What a frame's CPU does (FrameStats' CPU/GPU split, ``StageClock``), and that a further
sample of a frame adds its GPU work and a small constant of Python, nothing that grows with
the scene: planning once per light per sample, no batch or material block rebuilt (that no
image is read into Python is test_materials' tracemalloc test). Counts, not seconds: the
speed itself is measured by ``tools.bench perf --sections cpu``."""

import math
from contextlib import contextmanager

import pytest

from devkit import scenes

SIZE = (64, 36)
STAGES = {"prepare", "shadow pass", "lit pass", "accumulate", "resolve", "post"}


def _render(gpu_call, scene, samples, fenced=False, before=None):
    """FrameStats of a frame of ``samples`` of ``scene`` (threshold 0: every sample in every
    pixel), and the renderer's upload counters; ``before(renderer)`` runs first."""

    def job(engine, depsgraph):
        from penumbra.engine.frame.renderer import Renderer
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, scene, *SIZE)
        engine.render_frame(depsgraph, camera, *SIZE)  # a warm engine: batches and programs made
        renderer = engine.renderer
        if before is not None:
            before(renderer)
        Renderer.fence_stages = fenced
        try:
            counters = (renderer.batches.uploaded, renderer.materials.uploaded)
            out = engine.render_frame(depsgraph, camera, *SIZE, samples=(0, samples), sample_count=samples)
            after = (renderer.batches.uploaded, renderer.materials.uploaded)
        finally:
            Renderer.fence_stages = False
        return out.stats, counters, after

    return gpu_call(job)


@contextmanager
def counting_fits(shared=False):
    """A list that collects one entry per map fitted (a spot's or a point light's face, a
    sun's cascade) or derived from the frame's plan (a sampled sun's map ``sheared``, a local
    light's ``moved``: entries named so) while the block runs; with ``shared``, also one per
    flat-caster table made (``FlatCasters``) and per cascade slicing of the view
    (``cascade_slices``)."""
    from penumbra.engine.frame import shadow_pass
    from penumbra.engine.shadows import planning

    fits = []
    lightspace = planning.lightspace
    original = planning._face_fit, lightspace.fit_sun_to_view, lightspace.sheared, lightspace.moved
    table, slices = lightspace.FlatCasters.__init__, (planning.cascade_slices, shadow_pass.cascade_slices)

    def made(self, boxes):
        if shared:
            fits.append("FlatCasters")
        table(self, boxes)

    def sliced(*args, **kwargs):
        if shared:
            fits.append("cascade_slices")
        return slices[0](*args, **kwargs)

    def counted(fn):
        def run(*args, **kwargs):
            fits.append(fn.__name__)
            return fn(*args, **kwargs)

        return run

    planning._face_fit = counted(original[0])  # a spot's map or a cube's face, fitted
    planning.lightspace.fit_sun_to_view = counted(original[1])
    lightspace.sheared = counted(original[2])
    lightspace.moved = counted(original[3])
    lightspace.FlatCasters.__init__ = made
    planning.cascade_slices = shadow_pass.cascade_slices = sliced
    try:
        yield fits
    finally:
        planning._face_fit, lightspace.fit_sun_to_view, lightspace.sheared, lightspace.moved = original
        lightspace.FlatCasters.__init__ = table
        planning.cascade_slices, shadow_pass.cascade_slices = slices


@pytest.fixture(scope="module")
def demo(penumbra):
    return scenes.bare_demo(*SIZE)


def test_a_fenced_frame_splits_python_from_gpu_time_per_stage_and_sample(demo, gpu_call):
    stats, *_ = _render(gpu_call, demo, 6, fenced=True)
    assert STAGES <= set(stats.cpu_seconds), stats.cpu_seconds
    assert set(stats.gpu_seconds) == set(stats.cpu_seconds)
    assert all(v >= 0.0 for v in (*stats.cpu_seconds.values(), *stats.gpu_seconds.values()))
    assert len(stats.sample_cpu_seconds) == stats.samples == 6
    # The samples' Python is part of the frame's: no stage is counted twice.
    assert sum(stats.sample_cpu_seconds) <= sum(stats.cpu_seconds.values()) + 1e-9
    assert stats.shadow_draws > 0 and stats.draws > stats.shadow_draws
    assert stats.upload_bytes > 0


def test_an_unfenced_frame_books_only_its_read_backs_as_gpu_time(demo, gpu_call):
    """Without fences nothing waits for the GPU but the frame's own read-backs (the centred
    sample's depth and normal, in accumulate): only those count as GPU time."""
    stats, *_ = _render(gpu_call, demo, 3)
    assert STAGES <= set(stats.cpu_seconds)
    assert set(stats.gpu_seconds) <= {"accumulate", "settle"}, stats.gpu_seconds


def test_a_further_sample_plans_no_light_and_rebuilds_nothing(demo, gpu_call):
    """Maps (a sun's and a spot's) counted over frames of 2 and 10 samples: the 8 further
    samples fit none of them, each map is derived from the frame's first plan (the sun's
    sheared to the sample's direction, the spot's moved to the sample's point of the light),
    once per sample; the world's directions are fitted once each, over the frame's one table
    of its flat boxes and one slicing of its view; no batch or material block is built again,
    and what a further sample uploads is its uniform blocks and light bins, a few KiB,
    whatever the scene's size."""

    def count(world_shadows):
        demo.penumbra.world_shadows = world_shadows
        with counting_fits(shared=True) as fits:
            results = {}
            for samples in (2, 10):
                del fits[:]
                stats, counters, after = _render(gpu_call, demo, samples)
                derived = fits.count("sheared") + fits.count("moved")
                shared = fits.count("FlatCasters") + fits.count("cascade_slices")
                results[samples] = (len(fits) - derived - shared, stats, counters, after, derived, shared)
        return results

    results = count(False)
    (fits2, stats2, *_, derived2, _), (fits10, stats10, counters, after, derived10, _) = results[2], results[10]
    maps = stats10.shadow_maps // stats10.samples  # maps drawn per sample (every light moves)
    assert maps >= 2
    assert fits10 == fits2, (fits2, fits10)  # no fit in a further sample
    assert derived10 - derived2 == 8 * maps, (derived2, derived10, maps)
    # The world's directions (World > Shadows): one fit each, no density pass.
    world = count(True)
    # (The demo's dim world gives a small share of its light: fewer directions than the most.)
    directions = (world[10][1].world_directions - world[2][1].world_directions) // 8
    assert 1 <= directions <= demo.penumbra.world_samples
    assert world[10][1].world_directions - world[2][1].world_directions == 8 * directions
    assert world[10][0] - world[2][0] == 8 * directions, (world[2][0], world[10][0])
    assert world[10][4] - world[2][4] == 8 * maps, (world[2][4], world[10][4])
    # What every sample's plan shares is made once a frame (and once more by the warm-up frame).
    assert world[10][5] == world[2][5] == results[10][5] <= 4, (world[2][5], world[10][5])
    assert after == counters  # no batch, no material block made again
    per_sample = (stats10.upload_bytes - stats2.upload_bytes) / 8
    assert 0 < per_sample < 32 * 1024, per_sample


def test_a_samples_accumulations_share_one_pass_while_they_fit_six_targets(demo, gpu_call):
    """Every accumulation a sample adds to takes its weight, mask and gathering alike: the
    colour and shadow, the Emission pass, the world ratio's three sums. They go in as few
    full-frame passes as Blender's six colour targets allow: one a sample here, where the
    colour, the Emission pass and the ratio each took a pass of their own."""
    from penumbra.engine.frame.film import Film

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, demo, *SIZE)
        engine.render_frame(depsgraph, camera, *SIZE)
        calls = []  # per sample: (full-frame passes, targets added to)
        accumulate, fullscreen, add = Film.accumulate, Film.fullscreen, Film._add_copies

        def counted_accumulate(self, *args, **kwargs):
            calls.append([0, 0])
            inside.append(True)
            try:
                return accumulate(self, *args, **kwargs)
            finally:
                inside.pop()

        def counted_add(self, program, slots, samplers, copies, weight, gather):
            calls[-1][1] += len(slots) + len(copies)
            return add(self, program, slots, samplers, copies, weight, gather)

        inside = []  # set while a sample accumulates

        def counted_fullscreen(self, *args, **kwargs):
            if inside:
                calls[-1][0] += 1
            return fullscreen(self, *args, **kwargs)

        Film.accumulate, Film._add_copies, Film.fullscreen = counted_accumulate, counted_add, counted_fullscreen
        try:
            out = engine.render_frame(depsgraph, camera, *SIZE, samples=(0, 5), sample_count=5, emission=True)
        finally:
            Film.accumulate, Film._add_copies, Film.fullscreen = accumulate, add, fullscreen
        return out.stats, calls

    stats, calls = gpu_call(job)
    assert "world_ratio" in stats.techniques, stats.techniques
    assert len(calls) == stats.samples == 5
    # Colour, shadow, Emission and the ratio's three sums: six targets, one pass.
    assert all(targets == 6 for _passes, targets in calls), calls
    assert all(passes == 1 for passes, _targets in calls), calls


def test_a_lit_pass_sends_its_frame_and_lights_blocks_once_whatever_programs_it_binds(demo, gpu_call):
    """A lit pass that switches programs (one of the demo's materials alpha-hashed, a variant
    of its own): each program it binds reads the same frame and lights blocks, which go to the
    GPU once a pass, not once a program; its light bins are made once a pass too."""
    from devkit import fuzz

    obj = next(o for o in demo.objects if o.type == "MESH" and o.active_material is not None)
    own = obj.active_material
    mat = own.copy()
    obj.active_material = mat
    fuzz._set(fuzz._principled(mat), ("Alpha",), 0.5)
    fuzz._set_render_method(mat, blended=False)

    def job(engine, depsgraph):
        from penumbra.engine.frame import lit_pass
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, demo, *SIZE)
        engine.render_frame(depsgraph, camera, *SIZE)  # warm: programs compiled
        lit = engine.renderer.lit_pass
        sends, passes, textures, bound = {}, [], [], {}
        bind = lit_pass._Submission.bind

        def counted_bind(self, *args, **kwargs):
            shader = bind(self, *args, **kwargs)
            if self.lit is lit:  # the film's pass, not a capture's
                bound.setdefault(id(self), set()).add(id(shader))
            return shader

        get, draw, bins = lit._ubos.get, lit.draw, lit._bins_texture

        def counted_get(name, raw):
            sends[name] = sends.get(name, 0) + 1
            return get(name, raw)

        def counted_draw(*args, **kwargs):
            passes.append(1)
            return draw(*args, **kwargs)

        def counted_bins(*args, **kwargs):
            textures.append(1)
            return bins(*args, **kwargs)

        lit._ubos.get, lit.draw, lit._bins_texture = counted_get, counted_draw, counted_bins
        lit_pass._Submission.bind = counted_bind
        try:
            engine.render_frame(depsgraph, camera, *SIZE, samples=(0, 4), sample_count=4)
        finally:
            del lit._ubos.get, lit.draw, lit._bins_texture
            lit_pass._Submission.bind = bind
        return sends, len(passes), len(textures), max(len(b) for b in bound.values())

    try:
        sends, passes, textures, programs = gpu_call(job)
    finally:
        obj.active_material = own
    assert programs >= 2, programs  # the pass switches programs
    assert passes >= 4, passes
    assert 1 <= sends["frame"] <= passes, (sends, passes)
    assert 1 <= sends["lights"] <= passes, (sends, passes)
    assert textures <= passes, (textures, passes)


def test_a_viewport_refinement_plans_each_map_once(demo, gpu_call):
    """The viewport renders a frame one sample per redraw (``samples=(k, k + 1)``): its first
    call plans the frame (sizes and moving lights) and its sample; every later call of the
    same frame fits each map once, for its sample alone."""

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, demo, *SIZE)
        counts = []
        for k in range(4):
            del fits[:]
            out = engine.render_frame(depsgraph, camera, *SIZE, aux=False, samples=(k, k + 1), sample_count=8)
            counts.append((len(fits), out.stats.shadow_maps))
        return counts

    with counting_fits() as fits:
        counts = gpu_call(job)
    for fitted, maps in counts[1:]:
        assert maps >= 2 and fitted == maps, counts
    assert counts[0][0] > counts[0][1]  # the first call also planned the frame


def test_frames_while_the_view_moves_keep_their_map_sizes(demo, gpu_call):
    """Navigation frames (one sample while the view moves): the first plans its maps' sizes
    (a fit at full size, then one at the size the pixels need), the next ones keep them and
    fit each map once, and every NAVIGATION_REPLAN-th plans afresh."""
    from penumbra.engine.frame.renderer import NAVIGATION_REPLAN

    def job(engine, depsgraph):
        import dataclasses

        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, demo, *SIZE)
        counts = []
        for k in range(NAVIGATION_REPLAN + 1):
            moved = camera.view.copy()
            moved[0, 3] += 0.01 * k
            del fits[:]
            out = engine.render_frame(
                depsgraph, dataclasses.replace(camera, view=moved), *SIZE, aux=False, navigating=True
            )
            counts.append((len(fits), out.stats.shadow_maps + out.stats.shadow_maps_reused))  # planned
        return counts

    with counting_fits() as fits:
        counts = gpu_call(job)
    assert counts[0][0] > counts[0][1] >= 2, counts  # planned afresh: two fits where sizes shrink
    assert all(fitted == maps for fitted, maps in counts[1:NAVIGATION_REPLAN]), counts
    assert counts[NAVIGATION_REPLAN][0] > counts[NAVIGATION_REPLAN][1], counts


def orbit_scene(penumbra):
    """A still scene lit by a spot, a point and an area light (no sun, a black world: every
    map belongs to a local light), seen by a camera that orbits it."""
    scene = scenes.empty_scene(*SIZE)
    scenes.set_world(scene, (0.0, 0.0, 0.0))
    scenes.plane(scene, "Ground", size=12.0)
    scenes.box(scene, "Crate", center=(-1.0, 0.5, 0.75), size=(1.5, 1.5, 1.5))
    scenes.uv_sphere(scene, "Ball", center=(1.2, -0.6, 1.0), radius=1.0)
    spot = scenes.light(scene, "Spot", "SPOT", 500.0, location=(-3.0, -3.0, 5.0), spot_size=math.radians(70))
    scenes.aim(spot, (0, 0, 0))
    scenes.light(scene, "Bulb", "POINT", 300.0, location=(2.5, 2.0, 3.0), shadow_soft_size=0.1)
    area = scenes.light(scene, "Panel", "AREA", 200.0, location=(0.0, 3.5, 4.0), size=1.0)
    scenes.aim(area, (0, 0, 0))
    scenes.look_at(scene, (8.0, 0.0, 5.0), (0, 0, 0.5))
    scene.penumbra.layers.clear()
    return scene


def orbit(camera, degrees):
    """``camera`` (``extract.Camera``) turned ``degrees`` about the world's z axis through the origin."""
    import dataclasses

    import numpy as np

    a = math.radians(degrees)
    turn = np.array([[math.cos(a), -math.sin(a), 0, 0], [math.sin(a), math.cos(a), 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    return dataclasses.replace(camera, view=camera.view @ np.linalg.inv(turn))


def test_an_orbit_around_a_still_scene_redraws_no_spot_point_or_area_map(penumbra, gpu_call):
    """Navigation frames (one sample while the view moves) of a camera orbiting a still scene:
    the first draws the spot's, the point light's and the area light's maps; every later one,
    through more than NAVIGATION_REPLAN frames and a quarter turn, reuses them all (each map is
    fitted with room for the view to move, and kept while what it must hold stays inside that
    room). Moving a light redraws its maps, and only its."""
    from penumbra.engine.frame.renderer import NAVIGATION_REPLAN

    scene = orbit_scene(penumbra)

    def job(engine, depsgraph):
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, scene, *SIZE)
        counts = []
        for k in range(2 * NAVIGATION_REPLAN + 2):
            out = engine.render_frame(depsgraph, orbit(camera, 6.0 * k), *SIZE, aux=False, navigating=True)
            counts.append((out.stats.shadow_maps, out.stats.shadow_maps_reused))
        return counts

    counts = gpu_call(job)
    first, later = counts[0], counts[1:]
    assert first[0] >= 1 + 1 + 3, counts  # the spot's map, and the point's and the area's faces
    assert all(drawn == 0 and reused == first[0] for drawn, reused in later), counts


def test_an_orbit_keeps_the_suns_map_until_the_view_outgrows_it(penumbra, gpu_call):
    """The demo (a sun fitted to the view and a spot) orbited 4 degrees a navigation frame for
    a third of a turn: the spot's map is drawn once, the sun's again only when what the view
    needs of it leaves the rectangle it was fitted to (a few times), not every frame as
    before; and the last frame, drawn with maps fitted frames earlier, shows what a fresh
    engine's navigation frame shows at that view (its maps fitted to that view alone)."""
    import numpy as np

    scene = scenes.demo_scene(*SIZE)
    scene.penumbra.layers.clear()

    def job(engine, depsgraph):
        from penumbra.engine.frame.film import texture_array
        from penumbra.engine.scene.extract import camera_from_scene

        camera = camera_from_scene(depsgraph, scene, *SIZE)
        drawn = []
        for k in range(30):
            view = orbit(camera, 4.0 * k)
            out = engine.render_frame(depsgraph, view, *SIZE, aux=False, navigating=True)
            drawn.append(out.stats.shadow_maps)
        kept = texture_array(out.color, 4).copy()
        engine.free_gpu()  # a fresh renderer: nothing kept, its maps fitted to this view
        out = engine.render_frame(depsgraph, view, *SIZE, aux=False, navigating=True)
        return drawn, kept, texture_array(out.color, 4)

    drawn, kept, fresh = gpu_call(job)
    assert drawn[0] == 2, drawn  # the sun's and the spot's
    assert sum(drawn[1:]) <= 6, drawn  # before: the sun's every frame (29)
    diff = np.abs(kept[..., :3].astype(np.float64) - fresh[..., :3])
    assert float(diff.mean()) < 2e-3 and float(np.quantile(diff, 0.99)) < 0.05, (diff.mean(), np.quantile(diff, 0.99))
