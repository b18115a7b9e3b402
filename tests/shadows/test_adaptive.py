"""Adaptive sampling and the time limit: a converged pixel is not shaded again (counted by the
lit pass itself), a frame whose pixels all converged stops early, the time limit stops within
one sample of its budget, and with the Noise Threshold at 0 (or adaptive sampling off) every
pass is bit-identical to the frame without adaptive sampling."""

import math

import numpy as np

from devkit import scenes
from devkit.render import render


def _soft_demo(width, height):
    scene = scenes.demo_scene(width, height)
    scene.objects["Spot"].data.shadow_soft_size = 0.5
    return scene


def _hard_scene(size=32):
    """Only hard lights, no pixel filter and no map jitter: every sample is the same image, so
    every pixel converges at the first check."""
    scene = scenes.empty_scene(size, size)
    scenes.box_over_plane(scene)
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.3, 0.2, 0), angle=0.0)
    scenes.top_camera(scene)
    scene.penumbra.filter_size = 0.0
    scene.penumbra.shadow_map_jitter = False
    return scene


def test_a_converged_pixel_is_never_shaded_again(penumbra, gpu_call):
    """The lit pass's counting variant writes 1 for every pixel it shades in a sample, summed
    over the frame. A pixel that converged after k samples, whose neighbours within the
    gathering film's reach converged by then too, is shaded exactly as often as in the first k
    samples of the frame without adaptive sampling (the same samples: a surface may cover it
    in some and not others), and never again."""
    from penumbra.engine.frame.film import texture_array
    from penumbra.engine.frame.renderer import Renderer
    from penumbra.engine.frame.sampling import Adaptive
    from penumbra.engine.scene.extract import camera_from_scene

    scene = _soft_demo(96, 54)
    total = 32

    def job(engine, depsgraph):
        engine.renderer = Renderer()
        film = engine.renderer.film
        film.count_shaded = True
        cam = camera_from_scene(depsgraph, scene, 96, 54)

        def frame(stop, adaptive=None):
            out = engine.render_frame(
                depsgraph, cam, 96, 54, aux=False, samples=(0, stop), sample_count=total, adaptive=adaptive
            )
            return out.stats, texture_array(film.shaded_total, 1)[..., 0].copy()

        stats, shaded = frame(total, Adaptive(threshold=0.01, min_samples=8))
        mask = texture_array(film.mask, 1)[..., 0].copy()
        samples = film.samples_array().copy()
        plain = {int(k): frame(int(k))[1] for k in np.unique(samples)}
        return stats, shaded, samples, mask, plain

    stats, shaded, samples, mask, plain = gpu_call(job)
    converged = mask > 0.5
    assert stats.samples == total and not stats.stopped
    assert 0.2 * mask.size < converged.sum() < mask.size, converged.mean()  # some pixels stopped, not all
    assert stats.pixels_converged == converged.sum()
    np.testing.assert_array_equal(samples[~converged], total)  # the others took every sample
    assert samples[converged].max() < total and samples[converged].min() >= 8
    assert len(plain) >= 3  # pixels stopped at several checks
    # A pixel is shaded until it and every pixel within the gathering film's reach converged
    # (``sampling.film_reach``: they gather its samples), as often as the plain frame shades
    # it in that many samples.
    from penumbra.engine.frame.sampling import film_reach

    r = film_reach(scene.penumbra.filter_size)
    padded = np.pad(samples, r)
    needed = np.zeros_like(samples)
    for dy in range(2 * r + 1):
        for dx in range(2 * r + 1):
            needed = np.maximum(needed, padded[dy : dy + samples.shape[0], dx : dx + samples.shape[1]])
    for k, counts in plain.items():
        here = needed == k
        np.testing.assert_array_equal(shaded[here], counts[here], err_msg=f"pixels needed for {k} samples")
    assert (plain[total] > shaded).sum() > 0.2 * mask.size  # the plain frame does shade them on
    assert stats.pixel_samples_skipped == int((total - samples).sum())


def test_a_fully_converged_frame_stops_early(penumbra, gpu_call):
    from penumbra.engine.frame.sampling import adaptive_settings
    from penumbra.engine.scene.extract import camera_from_scene

    scene = _hard_scene()
    scene.penumbra.render_samples = 64
    scene.penumbra.adaptive_min_samples = 4

    def job(engine, depsgraph):
        p = scene.penumbra
        cam = camera_from_scene(depsgraph, scene, 32, 32)
        adaptive = adaptive_settings(p.use_adaptive_sampling, p.adaptive_threshold, p.adaptive_min_samples, 0.0, 64)
        done = []
        out = engine.render_frame(
            depsgraph, cam, 32, 32, samples=(0, 64), sample_count=64, adaptive=adaptive, on_sample=done.append
        )
        return out.stats, done, out.color_array().copy()

    stats, done, image = gpu_call(job)
    assert stats.stopped == "converged" and stats.samples == 4 and done == [1, 2, 3, 4]
    assert stats.pixels_converged == 32 * 32
    # Every sample was the same image: the four give the 64-sample frame (float rounding).
    scene.penumbra.use_adaptive_sampling = False
    full = render(scene)["Combined"]
    scene.penumbra.use_adaptive_sampling = True
    np.testing.assert_allclose(image, full, rtol=1e-5, atol=1e-6)
    assert np.isfinite(image).all() and image[..., :3].max() > 0.1


def test_the_viewport_stops_refining_a_converged_frame_and_says_so(penumbra, gpu_call):
    scene = _hard_scene()
    scene.penumbra.viewport_samples = 64
    scene.penumbra.preview_adaptive_min_samples = 4

    def job(engine, depsgraph):
        cam = scene.camera.evaluated_get(depsgraph)
        view = cam.matrix_world.inverted()
        window = cam.calc_matrix_camera(depsgraph, x=32, y=32, scale_x=1.0, scale_y=1.0)
        rendered, statuses = [], []
        for _ in range(6):
            _out, r = engine.viewport_frame(depsgraph, view, window, 32, 32)
            rendered.append(r)
            statuses.append(engine.viewport_status())
        return rendered, statuses, engine.refining()

    rendered, statuses, refining = gpu_call(job)
    assert rendered == [True] * 4 + [False] * 2
    assert statuses[2] == "Sample 3/64"
    assert statuses[-1] == "Sample 4/64 | Noise Threshold reached" and not refining


class _Clock:
    """``sampling.clock`` driven by the test: each reading is ``step`` seconds after the last, so
    the samples a time limit allows do not depend on how fast this machine is."""

    def __init__(self, step):
        self.now, self.step = 0.0, step

    def __call__(self):
        now = self.now
        self.now += self.step
        return now


def test_the_viewports_time_limit_ends_endless_refinement(penumbra, gpu_call, monkeypatch):
    """The clock starts with the first sample and is read after each sample's GPU work: with
    a reading 0.125 s after the last and a 0.45 s limit, the fourth sample (at 0.5 s) is the last,
    and the viewport says so."""
    from penumbra.engine.frame import sampling

    scene = _soft_demo(48, 27)
    scene.penumbra.viewport_samples = 0  # refine without end
    scene.penumbra.use_preview_adaptive_sampling = False
    scene.penumbra.preview_time_limit = 0.45
    monkeypatch.setattr(sampling, "clock", _Clock(0.125))

    def job(engine, depsgraph):
        cam = scene.camera.evaluated_get(depsgraph)
        view = cam.matrix_world.inverted()
        window = cam.calc_matrix_camera(depsgraph, x=48, y=27, scale_x=1.0, scale_y=1.0)
        redraws = 0
        while engine.viewport_frame(depsgraph, view, window, 48, 27)[1]:
            redraws += 1
            assert redraws < 100
        return redraws, engine.viewport_status(), engine.refining()

    redraws, status, refining = gpu_call(job)
    assert redraws == 4
    assert status == "Sample 4 | Time Limit reached" and not refining


def test_time_limit_stops_within_one_sample_of_the_budget(penumbra, gpu_call, monkeypatch):
    """The clock starts with the samples (the scene is extracted and planned before it); the
    frame ends after the first sample that finds the budget spent: the samples take at least
    the budget and at most the budget plus one sample. With 0.125 s a sample (exact in binary)
    and a 0.4375 s budget that is 4 samples; 0.5 s gives 4 as well (the check is >=), 0.5625 s 5."""
    from penumbra.engine.frame import sampling
    from penumbra.engine.frame.sampling import adaptive_settings
    from penumbra.engine.scene.extract import camera_from_scene

    scene = _soft_demo(64, 36)

    def samples_within(limit):
        monkeypatch.setattr(sampling, "clock", _Clock(0.125))

        def job(engine, depsgraph):
            cam = camera_from_scene(depsgraph, scene, 64, 36)
            adaptive = adaptive_settings(False, 0.0, 0, limit, 4096)
            done = []
            out = engine.render_frame(
                depsgraph, cam, 64, 36, samples=(0, 4096), sample_count=4096, adaptive=adaptive, on_sample=done.append
            )
            return out.stats, done

        stats, done = gpu_call(job)
        assert stats.stopped == "time limit" and done == list(range(1, stats.samples + 1))
        return stats.samples

    assert [samples_within(limit) for limit in (0.4375, 0.5, 0.5625)] == [4, 4, 5]


def test_threshold_zero_or_off_is_bit_identical_to_the_plain_frame(penumbra, gpu_call):
    """The plain frame (no ``adaptive``) is the code path without adaptive sampling; Noise
    Threshold 0 and adaptive sampling off give its passes to the bit, through F12. With the
    threshold on, pixels stop and the image moves a little: measured on 5.2 and 4.5 with the
    pixel filter reaching 1.5 px (Cycles' width), mean |difference| 0.0016, max 0.041, mean
    brightness +0.21 %, Shadow pass 0.0012 (half as wide: 0.00091, 0.042, -0.045 %, 0.00081)."""
    from penumbra.engine.scene.extract import camera_from_scene

    scene = _soft_demo(64, 36)
    p = scene.penumbra
    p.render_samples = 32
    p.adaptive_min_samples = 8

    def job(engine, depsgraph):
        cam = camera_from_scene(depsgraph, scene, 64, 36)
        return engine.render_frame(depsgraph, cam, 64, 36, samples=(0, 32), sample_count=32).color_array().copy()

    passes = ("Combined", "Shadow", "Depth", "Emission")
    p.adaptive_threshold = 0.0
    zero = render(scene, passes)
    p.adaptive_threshold = 0.01
    p.use_adaptive_sampling = False
    off = render(scene, passes)
    plain = gpu_call(job)
    for name in passes:
        np.testing.assert_array_equal(zero[name], off[name], err_msg=name)
    p.use_adaptive_sampling = True
    on = render(scene, passes)
    # The engine core's plain frame is the same image (the post stack included).
    np.testing.assert_array_equal(plain, off["Combined"])
    np.testing.assert_array_equal(on["Depth"], off["Depth"])  # the centred sample's, always taken
    diff = np.abs(on["Combined"] - off["Combined"])[..., :3]
    assert 0.0 < diff.mean() < 0.0025 and diff.max() < 0.08, (diff.mean(), diff.max())
    assert math.isclose(on["Combined"][..., :3].mean(), off["Combined"][..., :3].mean(), rel_tol=0.003)
    assert np.abs(on["Shadow"] - off["Shadow"]).mean() < 0.002
