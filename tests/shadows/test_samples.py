"""Render samples against analytic references: anti-aliased edges (pixel coverage convolved
with the film filter), soft shadows that converge to the unoccluded fraction of the light,
area-light irradiance, determinism, the viewport's refinement and cancelling."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.analytic import camera_matrices, plane_hits, ray_hits_box
from devkit.render import render

# The box of box_over_plane() at its default place: a unit cube centred 1.5 over the plane.
BOX_LO, BOX_HI = (-0.5, -0.5, 1.0), (0.5, 0.5, 2.0)


def _samples(scene, n):
    scene.penumbra.render_samples = n
    return scene


# --- anti-aliasing ---------------------------------------------------------------------------


def _disc_scene(size=48):
    """A flat white disc (radius 1.3, 64 sides) on nothing, lit straight down by a sun, under
    an orthographic camera: pixel value = albedo/pi * 3 * coverage."""
    scene = scenes.empty_scene(size, size)
    verts = [(1.3 * math.cos(2 * math.pi * k / 64), 1.3 * math.sin(2 * math.pi * k / 64), 0.0) for k in range(64)]
    scenes.mesh_object(scene, "Disc", verts, [tuple(range(64))], mat=scenes.white())
    scenes.light(scene, "Sun", "SUN", 3.0, use_shadow=False)
    scenes.top_camera(scene, height=10.0, ortho_scale=4.0)
    return scene, verts


def _expected_coverage(verts, size, ortho_scale, filter_size, grid=48):
    """Per pixel, the disc polygon's coverage convolved with the Blackman-Harris filter of
    ``filter_size`` pixels: a dense grid of offsets over the filter, each weighted by it."""
    from matplotlib.path import Path

    from penumbra.engine.frame.sampling import blackman_harris, filter_width

    px = ortho_scale / size
    width = filter_width(filter_size)
    offs = (np.arange(grid) + 0.5) / grid * width - width / 2
    w1 = np.array([blackman_harris(o, width) for o in offs])
    centres = (np.arange(size) + 0.5) * px - ortho_scale / 2
    path = Path(np.array(verts)[:, :2])
    out = np.zeros((size, size))
    for j, oy in enumerate(offs):
        for i, ox in enumerate(offs):
            X, Y = np.meshgrid(centres + ox * px, centres + oy * px)
            inside = path.contains_points(np.c_[X.ravel(), Y.ravel()]).reshape(size, size)
            out += w1[i] * w1[j] * inside
    return out / (w1.sum() ** 2)


# Measured on both lines with the gathering film: 16 samples mean 0.0145 / max 0.066, 64 samples
# mean 0.0068 / max 0.027 (0.047 / 0.15 and 0.017 / 0.057 when each pixel took its own sample).
@pytest.mark.parametrize("samples, mean_tol, max_tol", [(16, 0.02, 0.1), (64, 0.01, 0.04)])
def test_edges_converge_to_coverage_convolved_with_the_filter(penumbra, samples, mean_tol, max_tol):
    scene, verts = _disc_scene()
    lit = scenes.WHITE_ALBEDO / math.pi * 3.0
    image = render(_samples(scene, samples))["Combined"][..., 0] / lit
    expected = _expected_coverage(verts, 48, 4.0, scene.penumbra.filter_size)
    edge = (expected > 0.02) & (expected < 0.98)
    error = np.abs(image - expected)
    assert edge.sum() > 60
    assert error[edge].mean() < mean_tol and error.max() < max_tol, (
        f"{samples} samples: mean {error[edge].mean():.4f}, max {error.max():.4f}"
    )
    levels = len(np.unique(np.round(image[edge], 3)))
    assert levels >= 10  # graded edges, not the two levels of one sample
    one = render(_samples(scene, 1))["Combined"][..., 0] / lit
    assert len(np.unique(np.round(one, 3))) <= 3


def test_edges_at_16_samples_are_no_worse_than_eevees(penumbra):
    """Anti-aliasing of a silhouette at the default 16 samples, against the disc's coverage
    convolved with the filter: Penumbra's gathering film (each sample reaching the 3 x 3
    pixels its filter covers) is no further off on edge pixels than EEVEE's 16 samples through
    its own filter of the same Filter Size (measured on both lines: 0.0145 against 0.0197)."""
    from devkit import engines

    scene, verts = _disc_scene()
    scene.render.filter_size = scene.penumbra.filter_size  # EEVEE's Filter Size, the same reach
    lit = scenes.WHITE_ALBEDO / math.pi * 3.0
    expected = _expected_coverage(verts, 48, 4.0, scene.penumbra.filter_size)
    edge = (expected > 0.02) & (expected < 0.98)
    penumbra = render(_samples(scene, 16))["Combined"][..., 0] / lit
    engines.configure(scene, "EEVEE")
    eevee = render(scene)["Combined"][..., 0] / lit
    ours, theirs = (float(np.abs(image - expected)[edge].mean()) for image in (penumbra, eevee))
    assert ours <= theirs, (ours, theirs)
    assert abs(float(eevee[24, 24]) - 1.0) < 0.01  # the same light inside the disc


# --- soft shadows ---------------------------------------------------------------------------


def _light_visibility(points, light_points, lo=BOX_LO, hi=BOX_HI):
    """Per receiver point, the fraction of ``light_points`` it sees past the box."""
    seen = np.zeros(points.shape[:-1])
    for q in light_points:
        seen += ~ray_hits_box(points, q - points, lo, hi)
    return seen / len(light_points)


def _area_scene(size=64):
    scene = scenes.empty_scene(size, size)
    scenes.box_over_plane(scene, plane_size=30.0)
    scenes.light(scene, "L", "AREA", 2000.0, location=(0.0, 0.0, 5.0), shape="RECTANGLE", size=2.0, size_y=1.0)
    scenes.top_camera(scene, height=20.0, ortho_scale=5.0)
    scene.penumbra.shadow_map_size = 1024
    return scene


def _area_light_points(scene, n=48):
    ob = scene.objects["L"]
    u = (np.arange(n) + 0.5) / n - 0.5
    X, Y = np.meshgrid(u * ob.data.size, u * ob.data.size_y)
    local = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size), np.ones(X.size)], axis=1)
    return (local @ np.array(ob.matrix_world).T)[:, :3]


def _sun_scene(size=64):
    """The box over the plane under a sun 10 degrees wide, 25 degrees off vertical."""
    scene = scenes.empty_scene(size, size)
    scenes.box_over_plane(scene, plane_size=30.0)
    scenes.light(scene, "L", "SUN", 3.0, rotation=(math.radians(-25), 0, 0), angle=math.radians(10))
    scenes.top_camera(scene, height=20.0, ortho_scale=5.0)
    scene.penumbra.shadow_map_size = 1024
    return scene


def _sun_points(scene, receivers, n=40):
    """Far points along directions filling the sun's disc (a dense polar grid, equal areas)."""
    ob = scene.objects["L"]
    d = -np.array(ob.matrix_world.to_3x3().col[2])
    u = np.cross(d, (1.0, 0.0, 0.0))
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    tan_half = math.tan(ob.data.angle / 2)
    r = np.sqrt((np.arange(n) + 0.5) / n)
    a = 2 * math.pi * (np.arange(2 * n) + 0.5) / (2 * n)
    R, A = np.meshgrid(r, a)
    dirs = d + tan_half * (R.ravel()[:, None] * np.cos(A.ravel())[:, None] * u + (R * np.sin(A)).ravel()[:, None] * v)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    return -dirs * 1e4  # offsets from a receiver towards the sun


def _sun_visibility(points, offsets, lo=BOX_LO, hi=BOX_HI):
    seen = np.zeros(points.shape[:-1])
    for q in offsets:
        seen += ~ray_hits_box(points, np.broadcast_to(q, points.shape), lo, hi)
    return seen / len(offsets)


@pytest.mark.parametrize("light", ["AREA", "SUN"])
def test_soft_shadow_converges_to_the_unoccluded_fraction_of_the_light(penumbra, light):
    """Mean visibility error, measured on 5.2 at 1/4/16/64/256 samples: area light (2 x 1 m
    rectangle) 0.170/0.059/0.020/0.0055/0.0037, sun (10 degrees) 0.027/0.010/0.0035/0.0026/
    0.0012: about N^-0.85 from 4 to 64 samples on the area light. Bound at 64: 0.015."""
    scene = _area_scene() if light == "AREA" else _sun_scene()
    view, proj, w, h = camera_matrices(scene)
    p, _depth = plane_hits(view, proj, w, h)
    if light == "AREA":
        expected = _light_visibility(p, _area_light_points(scene))
    else:
        expected = _sun_visibility(p, _sun_points(scene, p))
    # The plane around the box's shadow, less the box's top face (the camera looks straight down).
    under_box = (np.abs(p[..., 0]) < 0.55) & (np.abs(p[..., 1]) < 0.55)
    region = ((expected < 0.999) | (np.abs(p[..., 0]) < 1.5) & (np.abs(p[..., 1]) < 1.5)) & ~under_box
    errors = {}
    for n in (4, 16, 64):
        shadow = render(_samples(scene, n), passes=("Combined", "Shadow"))["Shadow"][..., 0]
        errors[n] = float(np.abs(shadow - expected)[region].mean())
    assert errors[4] > errors[16] > errors[64], errors
    assert errors[64] < 0.015, errors
    penumbra_px = (expected > 0.05) & (expected < 0.95)
    assert penumbra_px.sum() > 100  # a real penumbra is compared, not a hard edge


def test_area_light_irradiance_matches_its_form_factor(penumbra):
    """Unshadowed, an area light's irradiance on the plane is the integral over its surface:
    E = P / (pi A) * sum(cos_r cos_e / d^2 dA); the sampled average converges to it."""
    scene = _area_scene(size=32)
    scene.objects["L"].data.use_shadow = False
    scene.objects["Box"].hide_render = True
    view, proj, w, h = camera_matrices(scene)
    p, _depth = plane_hits(view, proj, w, h)
    ob = scene.objects["L"]
    q = _area_light_points(scene, n=96)
    d = q[None, None] - p[..., None, :]
    dist2 = (d**2).sum(-1)
    cos_r = d[..., 2] / np.sqrt(dist2)  # the plane faces +Z, the light faces -Z
    area = ob.data.size * ob.data.size_y
    E = ob.data.energy / (math.pi * area) * (cos_r * cos_r / dist2).mean(-1) * area
    expected = scenes.WHITE_ALBEDO / math.pi * E
    image = render(_samples(scene, 64))["Combined"][..., 0]
    rel = np.abs(image - expected) / expected
    # 64 Halton points over the light (the first at its centre) against a 96x96 quadrature.
    assert np.median(rel) < 0.02 and rel.max() < 0.04, f"median {np.median(rel):.4f}, max {rel.max():.4f}"


# --- determinism, reuse, one sample -----------------------------------------------------------


def test_same_frame_and_settings_give_bit_identical_pixels(penumbra):
    scene = _samples(scenes.demo_scene(64, 36), 8)
    scene.objects["Spot"].data.shadow_soft_size = 0.5
    a = render(scene, passes=("Combined", "Shadow", "Depth"))
    b = render(scene, passes=("Combined", "Shadow", "Depth"))
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


_CHILD = """
import hashlib, sys
from devkit import session
session.isolate()
from devkit import scenes
from devkit.render import render
session.load_penumbra().register()
scene = scenes.demo_scene(64, 36)
scene.penumbra.render_samples = 8
scene.objects["Spot"].data.shadow_soft_size = 0.5
print("HASH", hashlib.sha256(render(scene)["Combined"].tobytes()).hexdigest())
sys.stdout.flush()
session.hard_exit(0)
"""


def test_a_new_process_renders_the_same_bits(penumbra):
    import hashlib
    import subprocess
    import sys

    from devkit.session import ROOT, child_env

    scene = _samples(scenes.demo_scene(64, 36), 8)
    scene.objects["Spot"].data.shadow_soft_size = 0.5
    here = hashlib.sha256(render(scene)["Combined"].tobytes()).hexdigest()
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD], capture_output=True, text=True, timeout=300, cwd=ROOT, env=child_env()
    )
    lines = [line for line in proc.stdout.splitlines() if line.startswith("HASH ")]
    assert proc.returncode == 0 and lines, proc.stderr[-2000:]
    assert lines[-1].split()[1] == here


def test_hard_lights_keep_one_map_and_soft_lights_move_theirs(penumbra, gpu_call):
    """Without map jitter a hard light's map is drawn once and reused. With it (the default)
    every shadowed light's map moves by a sub-texel offset in each sample after the first,
    so it is redrawn each sample; a light without shadows draws no map either way."""
    from penumbra.engine.scene.extract import camera_from_scene

    scene = scenes.empty_scene(48, 48)
    scenes.box_over_plane(scene)
    sun = scenes.light(scene, "Sun", "SUN", 3.0, rotation=(0.3, 0.2, 0))
    scenes.top_camera(scene)

    def job(engine, depsgraph):
        cam = camera_from_scene(depsgraph, scene, 48, 48)
        out = engine.render_frame(depsgraph, cam, 48, 48, samples=(0, 8), sample_count=8)
        return out.stats

    scene.penumbra.shadow_map_jitter = False
    sun.data.angle = 0.0
    hard = gpu_call(job)
    sun.data.angle = math.radians(5)
    soft = gpu_call(job)
    assert hard.samples == soft.samples == 8
    assert (hard.shadow_maps, hard.shadow_maps_reused, hard.lights_sampled) == (1, 7, 0)
    assert (soft.shadow_maps, soft.lights_sampled) == (8, 1)
    scene.penumbra.shadow_map_jitter = True
    sun.data.angle = 0.0
    jittered = gpu_call(job)
    assert (jittered.shadow_maps, jittered.shadow_maps_reused, jittered.lights_sampled) == (8, 0, 1)
    sun.data.use_shadow = False
    unshadowed = gpu_call(job)
    assert (unshadowed.shadow_maps, unshadowed.lights_sampled) == (0, 0)


def test_one_sample_is_the_single_sample_frame(penumbra, gpu_call):
    """samples = 1 accumulates nothing: the same passes, the same pixels as the frame of a
    renderer that knows no samples (sample 0 is centred and lights sit at their centres)."""
    from penumbra.engine.scene.extract import camera_from_scene

    scene = scenes.demo_scene(64, 36)
    scene.objects["Spot"].data.shadow_soft_size = 0.5

    def job(engine, depsgraph):
        cam = camera_from_scene(depsgraph, scene, 64, 36)
        one = engine.render_frame(depsgraph, cam, 64, 36)
        first_of_many = engine.render_frame(depsgraph, cam, 64, 36, samples=(0, 1), sample_count=16)
        return one.stats, one.color_array().copy(), first_of_many.color_array().copy()

    stats, one, first = gpu_call(job)
    assert stats.samples == 1 and stats.passes == 1 + stats.shadow_maps + stats.post_passes
    # The first of 16 samples differs only by PCSS seeing 1/4 of the spot's size.
    assert np.abs(one - first).mean() < 0.01


# --- viewport and cancel ----------------------------------------------------------------------


def test_viewport_after_n_redraws_shows_the_final_render_of_n_samples(penumbra, gpu_call):
    scene = scenes.demo_scene(64, 36)
    scene.objects["Spot"].data.shadow_soft_size = 0.4
    scene.penumbra.render_samples = scene.penumbra.viewport_samples = 6
    # Pixels settle by the Noise Threshold (render 0.01, viewport 0.1 by default): the same here.
    scene.penumbra.preview_adaptive_threshold = scene.penumbra.adaptive_threshold
    final = render(scene)["Combined"]

    def job(engine, depsgraph):
        cam = scene.camera.evaluated_get(depsgraph)
        view = cam.matrix_world.inverted()
        window = cam.calc_matrix_camera(depsgraph, x=64, y=36, scale_x=1.0, scale_y=1.0)
        statuses, rendered = [], []
        for _ in range(8):
            out, r = engine.viewport_frame(depsgraph, view, window, 64, 36)
            rendered.append(r)
            statuses.append(engine.viewport_status())
        return out.color_array().copy(), rendered, statuses, engine.refining()

    image, rendered, statuses, refining = gpu_call(job)
    assert rendered == [True] * 6 + [False] * 2
    assert statuses[0] == "Sample 1/6" and statuses[-1] == "Sample 6/6" and not refining
    np.testing.assert_array_equal(image, final)


def test_cancelling_keeps_the_samples_done_and_raises_nothing(penumbra, gpu_call):
    from penumbra.engine.scene.extract import camera_from_scene

    scene = scenes.demo_scene(48, 27)

    def job(engine, depsgraph):
        cam = camera_from_scene(depsgraph, scene, 48, 27)
        calls = []
        out = engine.render_frame(
            depsgraph,
            cam,
            48,
            27,
            samples=(0, 16),
            sample_count=16,
            on_sample=lambda done: calls.append(done) or done < 3,
        )
        stopped = (out.stats.samples, out.stats.cancelled, list(calls), out.color_array().copy())
        three = engine.render_frame(depsgraph, cam, 48, 27, samples=(0, 3), sample_count=16).color_array().copy()
        return stopped, three

    (samples, cancelled, calls, image), three = gpu_call(job)
    assert samples == 3 and cancelled and calls == [1, 2, 3]
    np.testing.assert_array_equal(image, three)


# --- parameter extremes -----------------------------------------------------------------------


def test_filter_size_zero_and_ten_and_hard_lights_at_many_samples(penumbra, gpu_call):
    """filter_size 0 jitters no pixel: with only hard lights and no map jitter every sample
    is the same, so any sample count gives the one-sample image (with map jitter the shadow
    edges average over texel grids: the same image but for them). filter_size 10 (its
    maximum) stays finite and keeps the mean brightness (the filter is normalised)."""
    from penumbra.engine.scene.extract import camera_from_scene

    scene = scenes.demo_scene(48, 27)
    scene.penumbra.layers.clear()
    # The world's ambient occlusion occludes a frame's first sample only, the world's sampled
    # directions the others, and the reflections' rays are drawn anew each sample after the
    # first: all off, so every sample is the same.
    scene.penumbra.world_ao = False
    scene.penumbra.world_shadows = False
    scene.penumbra.screen_space_reflections = False
    for ob in scene.objects:
        if ob.type == "LIGHT":
            ob.data.shadow_soft_size = 0.0
            if ob.data.type == "SUN":
                ob.data.angle = 0.0

    def frames(filter_size):
        scene.penumbra.filter_size = filter_size

        def job(engine, depsgraph):
            cam = camera_from_scene(depsgraph, scene, 48, 27)
            one = engine.render_frame(depsgraph, cam, 48, 27).color_array().copy()
            many = engine.render_frame(depsgraph, cam, 48, 27, samples=(0, 8), sample_count=8).color_array().copy()
            return one, many

        return gpu_call(job)

    scene.penumbra.shadow_map_jitter = False
    one, many = frames(0.0)
    np.testing.assert_allclose(many, one, rtol=1e-6, atol=1e-7)
    scene.penumbra.shadow_map_jitter = True
    one_jittered, many = frames(0.0)
    np.testing.assert_array_equal(one_jittered, one)  # one sample: no jitter at all
    changed = np.abs(many - one).max(axis=-1) > 1e-4
    assert 0 < changed.mean() < 0.2  # shadow edges only
    assert abs(many[..., :3].mean() - one[..., :3].mean()) < 0.01 * one[..., :3].mean()
    one, wide = frames(10.0)
    assert np.isfinite(wide).all()
    assert abs(wide[..., :3].mean() - one[..., :3].mean()) < 0.05 * one[..., :3].mean()
    assert np.abs(wide - one).max() > 0.05  # a 10-pixel filter does blur the 48x27 frame


def test_smallest_navigation_scale_on_a_tiny_region(penumbra, gpu_call):
    scene = scenes.demo_scene(5, 3)
    scene.penumbra.navigation_scale = 0.1

    def job(engine, depsgraph):
        cam = scene.camera.evaluated_get(depsgraph)
        view = cam.matrix_world.inverted()
        window = cam.calc_matrix_camera(depsgraph, x=5, y=3, scale_x=1.0, scale_y=1.0)
        engine.viewport_frame(depsgraph, view, window, 5, 3)
        moved = view.copy()
        moved.translation.x += 0.1
        out, _ = engine.viewport_frame(depsgraph, moved, window, 5, 3)
        return out.width, out.height, out.color_array().copy()

    w, h, image = gpu_call(job)
    assert (w, h) == (1, 1) and np.isfinite(image).all()
