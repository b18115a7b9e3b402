"""Debug views (``scene.penumbra.debug_view``) show the numbers the engine used for the frame:
each is checked against the engine's own planning data, frame data and film, or against the
analytic projection of a map onto a plane, on a scene built for it; and each reaches the
final render (Combined pass, report) and the viewport."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.render import render


def _frame(gpu_call, scene, view, samples=1, aux=True, adaptive=None, stop=None, count_shaded=False):
    """One frame of ``scene``'s camera with debug view ``view``: (DebugImage, shown RGBA, the
    renderer, FrameStats, extras) where extras has the depth pass, the converged mask and the
    shading count when asked for."""
    from penumbra.engine.frame.film import texture_array
    from penumbra.engine.frame.renderer import Renderer
    from penumbra.engine.scene.extract import camera_from_scene

    r = scene.render
    w, h = r.resolution_x, r.resolution_y
    scene.penumbra.debug_view = view

    def job(engine, depsgraph):
        engine.renderer = Renderer()
        film = engine.renderer.film
        film.count_shaded = count_shaded
        cam = camera_from_scene(depsgraph, scene, w, h)
        out = engine.render_frame(
            depsgraph,
            cam,
            w,
            h,
            aux=aux,
            samples=(0, stop or samples),
            sample_count=samples,
            adaptive=adaptive,
        )
        extras = {}
        if aux:
            extras["depth"] = out.depth_array().reshape(h, w).copy()
        if film.mask is not None:
            extras["mask"] = texture_array(film.mask, 1)[..., 0].copy()
        if count_shaded:
            extras["shaded"] = texture_array(film.shaded_total, 1)[..., 0].copy()
        if view == "SHADOW_MAPS" and engine.renderer.shadows.texture is not None:
            extras["atlas"] = texture_array(engine.renderer.shadows.texture, 1)[..., 0].copy()
        return out.debug, out.color_array().copy(), engine.renderer, out.stats, extras

    try:
        return gpu_call(job)
    finally:
        scene.penumbra.debug_view = "NONE"


def _sun_over_plane(size=64, tilt=0.0):
    scene = scenes.empty_scene(size, size)
    scenes.plane(scene, size=10.0, mat=scenes.white())
    scenes.box(scene, center=(1.0, 1.0, 0.5), size=(1, 1, 1), mat=scenes.white())
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(tilt, 0.0, 0.0), angle=0.0)
    scenes.top_camera(scene, ortho_scale=10.0)
    scene.penumbra.shadow_texels_per_pixel = 0.0  # every map at the full Shadow Map Size
    scene.penumbra.shadow_map_size = 256
    scene.penumbra.shadow_cascades = 1
    return scene


@pytest.mark.parametrize("tilt", [0.0, math.radians(50.0)])
def test_texel_density_is_the_maps_projection_onto_the_plane(penumbra, gpu_call, tilt):
    """A sun's map seen on a plane from an orthographic top camera: one pixel is p = 10/64 world
    units on each side, and the map's texel coordinates move by size/2 * (proj @ view)[:2, :2]
    per world unit on the plane (its orthographic projection): texels per pixel
    = p * sqrt(|det|). The tilted sun stretches its texels along one axis by 1/cos(tilt)."""
    scene = _sun_over_plane(tilt=tilt)
    debug, _shown, renderer, _stats, _extras = _frame(gpu_call, scene, "TEXEL_DENSITY")
    plan = renderer.last_sample.plan
    assert len(plan.tiles) == 1
    tile = plan.tiles[0]
    jacobian = 0.5 * tile.size * (tile.fit.proj @ tile.fit.view)[:2, :2]
    expected = (10.0 / 64.0) * math.sqrt(abs(np.linalg.det(jacobian)))
    # And the closed form: size texels over the fitted width, shrunk by sqrt(cos) when tilted.
    width = 2.0 / tile.fit.proj[0, 0]
    assert expected == pytest.approx((10.0 / 64.0) * tile.size / width * math.sqrt(math.cos(tilt)), rel=1e-3)
    values = debug.values[debug.covered]
    assert debug.covered.mean() > 0.9  # the plane fills the frame
    lit = values[values > 0.0]  # (faces turned away from the sun look up no map)
    assert lit.size > 0.8 * values.size
    assert np.median(np.abs(lit / expected - 1.0)) < 1e-3
    assert np.mean(np.abs(lit / expected - 1.0) < 0.01) > 0.95  # the box's sides differ
    assert "red < 1 undersampled" in debug.legend


def test_cascades_view_is_the_cascade_each_pixel_was_shaded_from(penumbra, gpu_call):
    """A long plane seen at a grazing angle with a four-cascade sun: each pixel's cascade is
    the slice of the plan's splits its view depth (the Depth pass) falls in; pixels within a
    blend band before a split may take the next cascade, as the shader dithers there."""
    scene = scenes.empty_scene(96, 48)
    # A thick ground casts like any solid, so the maps cover all of it the camera sees.
    scenes.box(scene, "Ground", center=(0.0, 0.0, -0.5), size=(400.0, 400.0, 1.0), mat=scenes.white())
    scenes.box(scene, center=(0.0, 0.0, 0.25), size=(0.5, 0.5, 0.5), mat=scenes.white())
    scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.4, 0.3, 0.0), angle=0.0)
    scenes.look_at(scene, (1.0, -2.0, 0.6), (0.0, 10.0, 0.0))
    scene.camera.data.clip_end = 300.0
    scene.penumbra.shadow_cascades = 4
    debug, _shown, renderer, _stats, extras = _frame(gpu_call, scene, "CASCADES")
    plan = renderer.last_sample.plan
    (shadow,) = [s for s in plan.lights.values() if s.mode == "CASCADE"]
    splits = np.asarray(shadow.splits, np.float64)
    depth = extras["depth"]
    covered = debug.covered
    expected = np.searchsorted(splits[:3], depth, side="right")
    in_band = np.zeros(depth.shape, bool)
    for c in range(min(3, len(shadow.blend))):
        in_band |= (depth >= splits[c] - shadow.blend[c]) & (depth < splits[c])
    clear = covered & ~in_band
    assert clear.sum() > 0.5 * covered.sum()
    got = debug.values
    assert np.mean(got[clear] == expected[clear]) > 0.99
    band = covered & in_band
    assert np.all((got[band] == expected[band]) | (got[band] == expected[band] + 1))
    used = [t for t in shadow.tiles if t >= 0]
    assert len(used) >= 3
    shown = set(np.unique(got[covered]).astype(int))
    assert shown == set(np.unique(expected[covered])) and len(shown) >= 3  # (the last may span no pixel)


def _spots(scene, count=6):
    for i in range(count):
        x = -4.0 + 8.0 * i / (count - 1)
        scenes.light(
            scene, f"Spot{i}", "SPOT", 200.0, location=(x, 0.0, 3.0), spot_size=math.radians(40.0), spot_blend=0.1
        )


def test_light_cost_is_each_pixels_light_bin(penumbra, gpu_call):
    """Six spot lights over a plane are binned (frame_data.BIN_MIN_LOCAL_LIGHTS): the lit pass
    evaluates, at each pixel, the lights its screen bin lists, and the view shows that count."""
    from penumbra.engine.shadows.light_bins import BIN_SIZE

    scene = scenes.empty_scene(96, 64)
    scenes.plane(scene, size=20.0, mat=scenes.white())
    _spots(scene)
    scenes.top_camera(scene, ortho_scale=12.0)
    debug, _shown, renderer, stats, _extras = _frame(gpu_call, scene, "LIGHT_COST")
    assert stats.binned
    bins = renderer.last_sample.data.bins  # (rows, columns, words): light masks as exact integers
    counts = np.zeros(bins.shape[:2], np.int64)
    for word in bins.reshape(-1, bins.shape[2]).T.astype(np.uint64):
        counts += np.array([bin(int(v)).count("1") for v in word]).reshape(bins.shape[:2])
    h, w = debug.values.shape
    per_pixel = counts[np.arange(h)[:, None] // BIN_SIZE, np.arange(w)[None, :] // BIN_SIZE]
    covered = debug.covered
    assert covered.all()
    assert np.array_equal(debug.values[covered], per_pixel[covered].astype(np.float32))
    assert per_pixel.min() < per_pixel.max() < 6  # bins list only the spots that reach them


def test_light_cost_without_bins_is_every_light_in_view(penumbra, gpu_call):
    scene = _sun_over_plane()
    scenes.light(scene, "Point", "POINT", 100.0, location=(0.0, 0.0, 3.0))
    debug, _shown, _renderer, stats, _extras = _frame(gpu_call, scene, "LIGHT_COST")
    assert not stats.binned
    assert np.all(debug.values[debug.covered] == 2.0)


def _soft_demo(width, height):
    scene = scenes.demo_scene(width, height)
    scene.objects["Spot"].data.shadow_soft_size = 0.5
    return scene


def test_samples_view_is_what_each_pixel_was_shaded_in(penumbra, gpu_call):
    """With adaptive sampling, pixels stop at different samples: the view's count equals the
    lit pass's own count of the samples it shaded each surface pixel in."""
    from penumbra.engine.frame.sampling import Adaptive

    scene = _soft_demo(64, 36)
    adaptive = Adaptive(threshold=0.01, min_samples=8)
    debug, _shown, _renderer, stats, extras = _frame(
        gpu_call, scene, "SAMPLES", samples=32, aux=False, adaptive=adaptive, count_shaded=True
    )
    shaded = extras["shaded"]
    # Away from silhouettes (the pixel filter spreads samples up to 1.5 px each way, 2.1 px
    # along a diagonal), a surface covers the pixel in every sample it takes.
    surface = shaded > 0.0
    for dy in range(-3, 4):
        for dx in range(-3, 4):
            surface &= np.roll(shaded > 0.0, (dy, dx), axis=(0, 1))
    assert surface.mean() > 0.5
    # A pixel is shaded as long as it or a pixel within the gathering film's reach still takes
    # samples (``sampling.film_reach``): the most samples taken around it.
    from penumbra.engine.frame.sampling import film_reach

    r = film_reach(scene.penumbra.filter_size)
    padded = np.pad(debug.values, r)
    needed = np.zeros_like(debug.values)
    for dy in range(2 * r + 1):
        for dx in range(2 * r + 1):
            needed = np.maximum(needed, padded[dy : dy + needed.shape[0], dx : dx + needed.shape[1]])
    assert np.array_equal(needed[surface], shaded[surface])
    own = surface & (needed == debug.values)
    assert own.mean() > 0.3 and np.array_equal(debug.values[own], shaded[own])
    assert debug.values.min() >= 8 and debug.values.max() == stats.samples
    assert debug.values.min() < debug.values.max()  # some pixels stopped early


def test_noise_view_is_what_the_convergence_check_compared(penumbra, gpu_call):
    """Stopped right after a convergence check (16 of 64 samples): every pixel whose 3x3
    neighbourhood error is below the threshold converged there, and every pixel that did not
    converge has an error at or above it."""
    from penumbra.engine.frame.sampling import Adaptive

    scene = _soft_demo(64, 36)
    threshold = 0.02
    adaptive = Adaptive(threshold=threshold, min_samples=8)
    debug, _shown, _renderer, _stats, extras = _frame(
        gpu_call, scene, "NOISE", samples=64, stop=16, aux=False, adaptive=adaptive
    )
    mask = extras["mask"] > 0.5
    values = debug.values
    assert 0.05 < mask.mean() < 0.95
    assert np.mean(mask[values < threshold * 0.999]) == 1.0
    assert np.mean(values[~mask] >= threshold * 0.999) == 1.0


def test_noise_view_without_adaptive_sampling_still_estimates(penumbra, gpu_call):
    scene = _soft_demo(48, 27)
    debug, _shown, _renderer, _stats, _extras = _frame(gpu_call, scene, "NOISE", samples=8, aux=False)
    assert debug.covered.all() and np.all(np.isfinite(debug.values)) and debug.values.max() > 0.0
    one, _shown, _renderer, _stats, _extras = _frame(gpu_call, scene, "NOISE", samples=1, aux=False)
    assert not one.covered.any() and "one sample" in one.legend


def test_shadow_maps_view_shows_each_map_where_planning_put_it(penumbra, gpu_call):
    """A point light (cube faces) and a sun: each tile of the plan is outlined at its atlas
    place scaled into the frame, labelled with its light, face and size, and the pixels inside
    show the atlas texels (read back separately)."""
    scene = _sun_over_plane(size=128)
    scenes.light(scene, "Lamp", "POINT", 100.0, location=(-2.0, -2.0, 3.0))
    debug, shown, renderer, _stats, extras = _frame(gpu_call, scene, "SHADOW_MAPS")
    plan = renderer.last_sample.plan
    atlas = extras["atlas"]
    assert len(debug.tiles) == len(plan.tiles) >= 2
    rows, cols = atlas.shape
    h, w = debug.values.shape
    scale = min(w / cols, h / rows)
    ox, oy = 0.5 * (w - cols * scale), 0.5 * (h - rows * scale)
    labels = [label for _rect, label in debug.tiles]
    assert any(label.startswith("Sun ") for label in labels)
    assert (
        sum(label.startswith("Lamp ") and label.split()[1] in {"+X", "-X", "+Y", "-Y", "+Z", "-Z"} for label in labels)
        >= 1
    )
    for (rect, label), tile in zip(debug.tiles, plan.tiles, strict=True):
        x0, y0, x1, y1 = rect
        assert (x0, y0) == pytest.approx((ox + tile.origin[0] * scale, oy + tile.origin[1] * scale))
        assert x1 - x0 == pytest.approx(tile.size * scale)
        assert label.endswith(f" {tile.size}")
        # The outline's left edge runs through the rectangle's first pixel column.
        col = int(math.floor(x0 + 0.5))
        mid = int(0.5 * (y0 + y1))
        assert shown[mid, col, :3].max() > 0.5 and not np.allclose(shown[mid, col, :3], shown[mid, col, 0])
        # Inside: the atlas texel under the pixel's centre.
        px, py = int(0.5 * (x0 + x1)), int(0.5 * (y0 + y1)) - 3
        tx, ty = int((px + 0.5 - ox) / scale), int((py + 0.5 - oy) / scale)
        assert debug.values[py, px] == pytest.approx(atlas[ty, tx])
    assert debug.covered.mean() > 0.1


def test_a_final_render_shows_the_view_and_reports_its_legend(penumbra):
    """F12 writes the debug image as the Combined pass and says what the colours mean in the
    render report."""
    scene = _sun_over_plane(size=32)
    scene.penumbra.render_samples = 4
    plain = render(scene)["Combined"]
    scene.penumbra.debug_view = "LIGHT_COST"
    try:
        shown = render(scene)["Combined"]
    finally:
        scene.penumbra.debug_view = "NONE"
    assert not np.allclose(plain, shown, atol=0.05)
    # One light everywhere: the whole surface has the colour scale's top (the frame's most),
    # but within the pixel filter's reach (2 px) of the frame's border, where samples that
    # look beyond the plane see nothing.
    rows = max(4, min(16, 32 // 16))
    body = shown[rows + 2 : -2, 2:-2, :3]
    assert np.allclose(body, body[0, 0], atol=1e-3)


def test_the_viewport_shows_the_view_and_its_legend(penumbra, gpu_call):
    scene = _sun_over_plane(size=48)
    scene.penumbra.debug_view = "TEXEL_DENSITY"

    def job(engine, depsgraph):
        cam = scene.camera.evaluated_get(depsgraph)
        view_matrix = cam.matrix_world.inverted()
        window_matrix = cam.calc_matrix_camera(depsgraph, x=48, y=48, scale_x=1.0, scale_y=1.0)
        out, _rendered = engine.viewport_frame(depsgraph, view_matrix, window_matrix, 48, 48)
        return out.debug, out.color_array().copy(), out.stats.debug_legend

    try:
        debug, shown, legend = gpu_call(job)
    finally:
        scene.penumbra.debug_view = "NONE"
    assert debug is not None and debug.view == "TEXEL_DENSITY"
    assert np.allclose(shown, debug.image, atol=1e-6)
    assert legend.startswith("Texel Density:")
