"""Depth of field by lens sampling (engine/frame/lens.py), rendered, against the thin lens's
geometry: a small emitting sphere against a black world, seen by a 50 mm camera at the origin
(pixel filter 0: each sample looks through the pixel's centre), with Depth of Field on."""

import math

import bpy
import numpy as np
import pytest

from devkit import scenes
from devkit.render import render

W, H = 128, 96
RHO = 0.05  # the sphere's radius
SAMPLES = 64


def _scene(depth, focus, fstop=0.2, dof=True, samples=SAMPLES, blades=0):
    scene = scenes.empty_scene(W, H)
    mat = scenes.emissive()
    scenes.uv_sphere(scene, "Point", center=(0.0, 0.0, -depth), radius=RHO, segments=64, rings=32, mat=mat)
    cam = scenes.camera(scene, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), lens=50.0, clip=(0.1, 100.0))
    cam.data.sensor_fit = "HORIZONTAL"
    cam.data.dof.use_dof = dof
    cam.data.dof.focus_distance = focus
    cam.data.dof.aperture_fstop = fstop
    cam.data.dof.aperture_blades = blades
    scene.penumbra.filter_size = 0.0
    scene.penumbra.render_samples = samples
    scene.penumbra.use_adaptive_sampling = False
    return scene


def _k():
    """Pixels per unit of x / z of the camera: 50 mm on a 36 mm sensor across W pixels."""
    return 2.0 * 50.0 / 36.0 * 0.5 * W


def _simulated(depth, focus, fstop, samples):
    """The image the thin lens predicts, sampled as the film samples it: for each of the
    frame's points of the aperture (``lens.lens_offset``), the pixel centres inside the
    sphere's silhouette moved by o (1/f - 1/z) k, averaged."""
    from penumbra.engine.frame.lens import lens_offset
    from penumbra.engine.scene.extract import Lens

    lens = Lens(radius=50e-3 / (2.0 * fstop), focus=focus)
    k = _k()
    r = k * RHO / math.sqrt(depth**2 - RHO**2)  # the silhouette's radius in pixels
    x, y = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    image = np.zeros((H, W))
    shifts = []
    for s in range(samples):
        ox, oy = lens_offset(s, lens)
        dx, dy = ox * k * (1.0 / focus - 1.0 / depth), oy * k * (1.0 / focus - 1.0 / depth)
        shifts.append((dx, dy))
        image += (x - W / 2 - dx) ** 2 + (y - H / 2 - dy) ** 2 <= r * r
    return image / samples, np.array(shifts), lens


def _moments(image):
    y, x = np.mgrid[0:H, 0:W] + 0.5
    w = image / image.sum()
    cx, cy = (w * x).sum(), (w * y).sum()
    return cx, cy, (w * (x - cx) ** 2).sum(), (w * (y - cy) ** 2).sum()


def test_a_point_off_focus_spreads_over_the_thin_lens_circle_of_confusion(penumbra):
    """The sphere 4 units away, focused at 2, f/0.2: its image spreads over a disc whose
    diameter is the thin lens's circle of confusion, 2 r |1/f - 1/z| k (11.1 pixels), within
    half a pixel (from the image's second moments, against the same sampling of the
    aperture), centred where the pinhole sees it, its light spread, not lost."""
    depth, focus, fstop = 4.0, 2.0, 0.2
    image = render(_scene(depth, focus, fstop))["Combined"][..., 0].astype(np.float64)
    expected, shifts, lens = _simulated(depth, focus, fstop, SAMPLES)
    coc = 2.0 * lens.radius * abs(1.0 / focus - 1.0 / depth) * _k()
    assert coc == pytest.approx(11.1, abs=0.05)
    # The frame's points of the aperture cover it: their shifts' spread is the disc's.
    assert 4.0 * math.sqrt(shifts[:, 0].var()) == pytest.approx(coc, rel=0.04)
    got, want = _moments(image), _moments(expected)
    assert got[0] == pytest.approx(want[0], abs=0.25) and got[1] == pytest.approx(want[1], abs=0.25)
    for axis in (2, 3):  # a uniform disc of diameter D has variance D^2 / 16 along each axis
        assert 4.0 * math.sqrt(got[axis]) == pytest.approx(4.0 * math.sqrt(want[axis]), abs=0.5)
    lit = image > 0.5 / SAMPLES
    cols, rows = np.flatnonzero(lit.any(axis=0)), np.flatnonzero(lit.any(axis=1))
    span = expected > 0.0
    assert abs(len(cols) - np.flatnonzero(span.any(axis=0)).size) <= 1
    assert abs(len(rows) - np.flatnonzero(span.any(axis=1)).size) <= 1
    assert image.sum() == pytest.approx(expected.sum(), rel=0.05)


def test_a_point_at_the_focus_distance_stays_sharp(penumbra):
    """Focused on the sphere (f = z), every point of the aperture sees it where the pinhole
    does: the image with depth of field is the pinhole image's, but for the sphere's own depth
    (its rim 0.05 units nearer moves by 0.07 pixels)."""
    sharp = render(_scene(4.0, 4.0, dof=False))["Combined"][..., 0]
    focused = render(_scene(4.0, 4.0))["Combined"][..., 0]
    assert sharp.sum() > 10.0
    assert np.abs(focused - sharp).mean() < 2e-3
    assert focused.sum() == pytest.approx(sharp.sum(), rel=0.02)


@pytest.mark.parametrize(
    "setting",
    ["fstop 0.1", "fstop 1000", "focus at the near plane", "focus at infinity", "focus object behind", "one sample"],
)
def test_extreme_lenses_stay_finite(penumbra, setting):
    """f-stops 0.1 and 1000, focus at the near plane and far beyond the scene, a focus object
    behind the camera, one sample: finite images (the harness checks every render for finite,
    non-negative light), f/1000 the pinhole's, one sample the lens centre's, said so."""
    fstop = {"fstop 0.1": 0.1, "fstop 1000": 1000.0}.get(setting, 0.2)
    focus = {"focus at the near plane": 0.1, "focus at infinity": 1e9}.get(setting, 2.0)
    scene = _scene(4.0, focus, fstop, samples=1 if setting == "one sample" else 16)
    if setting == "focus object behind":
        target = bpy.data.objects.new("Behind", None)
        scene.collection.objects.link(target)
        target.location = (0.0, 0.0, 3.0)
        scene.camera.data.dof.focus_object = target
    image = render(scene)["Combined"][..., 0]
    assert np.all(np.isfinite(image))
    if setting in ("fstop 1000", "one sample"):
        pinhole = render(_scene(4.0, focus, dof=False, samples=1 if setting == "one sample" else 16))["Combined"]
        assert np.abs(image - pinhole[..., 0]).max() < 0.07  # f/1000: 0.005 pixels of blur


@pytest.mark.parametrize("fstop", [0.35, 0.15])
def test_defocused_pixels_keep_sampling_in_focus_ones_may_settle(penumbra, gpu_call, fstop):
    """The settle pilot's branching holds for focus too: a pixel whose circle of confusion is
    wider than half a pixel (from its depth, the thin lens's formula) never settles, since
    other points of the lens see other surfaces there, and no pixel settles within the reach of
    a blurred surface: at f/0.35 (the widest circle of confusion within the settle test's
    neighbourhood) pixels around the focus distance settle; at f/0.15 (blur wider than the
    neighbourhood it tests) none does."""
    from penumbra.engine.frame.features.settling import flag_reach
    from penumbra.engine.frame.film import texture_array
    from penumbra.engine.frame.lens import coc_pixels, lens_reach
    from penumbra.engine.frame.renderer import Renderer
    from penumbra.engine.frame.sampling import adaptive_settings
    from penumbra.engine.scene.extract import camera_from_scene

    scene = scenes.demo_scene(160, 90)
    scene.penumbra.layers.clear()
    scene.penumbra.world_shadows = False  # the world's light keeps its pixels sampling
    cam = scene.camera.data
    cam.dof.use_dof = True
    cam.dof.focus_object = scene.objects["Ball"]
    cam.dof.aperture_fstop = fstop
    w, h, count = 160, 90, 16

    def job(engine, depsgraph):
        engine.renderer = Renderer()
        film = engine.renderer.film
        camera = camera_from_scene(depsgraph, scene, w, h)
        adaptive = adaptive_settings(True, 0.01, 0, 0.0, count)
        out = engine.render_frame(depsgraph, camera, w, h, aux=True, samples=(0, count), sample_count=count,
                                  adaptive=adaptive)  # fmt: skip
        mask = texture_array(film.mask, 1)[..., 0] > 0.5 if film.mask is not None else np.zeros((h, w), bool)
        depth = out.depth_array().copy()
        return camera, mask, depth, out.stats

    camera, mask, depth, stats = gpu_call(job)
    settled = stats.pixels_settled
    seen = np.isfinite(depth) & (depth > 0.0) & (depth < 99.0)
    coc = np.zeros_like(depth)
    coc[seen] = [coc_pixels(camera, d, w, h) for d in depth[seen]]
    # The frame's bound (over the depths of what it draws) holds every pixel's.
    reach = stats.lens_reach
    assert reach >= lens_reach(camera, (depth[seen].min(), depth[seen].max()), w, h) - 1e-9
    defocused = coc > 0.5
    assert defocused.sum() > 0.02 * mask.size
    assert not (mask & defocused).any(), int((mask & defocused).sum())
    if fstop == 0.35:  # the case that settles: its blur stays within the tested neighbourhood
        assert flag_reach(scene.penumbra.filter_size, reach) is not None, reach
    if flag_reach(scene.penumbra.filter_size, reach) is None:
        assert settled == 0 and not mask.any()
    else:
        assert settled > 0.02 * mask.size and mask.sum() == settled
        # No settled pixel within a blurred surface's reach: its neighbourhood is in focus.
        r = int(math.ceil(reach))
        padded = np.pad(defocused, r)
        near = np.zeros_like(defocused)
        for dy in range(2 * r + 1):
            for dx in range(2 * r + 1):
                near |= padded[dy : dy + h, dx : dx + w]
        assert not (mask & near).any(), int((mask & near).sum())


def test_the_viewport_in_camera_view_refines_to_the_final_renders_depth_of_field(penumbra, gpu_call):
    """In camera view the viewport shows the scene camera's depth of field as its refinement
    samples arrive: after 8 redraws it is the final render of 8 samples, pixel for pixel; the
    first redraw (the frame's centred sample) looks through the lens's centre. A one-sample
    frame (a navigation frame while the view moves) stays sharp, and its status says so."""
    from penumbra.engine.scene.extract import camera_from_scene, camera_lens, matrix_np

    scene = _scene(4.0, 2.0, 0.2, samples=8)
    scene.penumbra.viewport_samples = 8
    scene.penumbra.use_preview_adaptive_sampling = False
    final = render(scene)["Combined"]

    def job(engine, depsgraph):
        cam = scene.camera.evaluated_get(depsgraph)
        view_matrix = cam.matrix_world.inverted()
        window_matrix = cam.calc_matrix_camera(depsgraph, x=W, y=H, scale_x=1.0, scale_y=1.0)
        lens = camera_lens(cam, matrix_np(view_matrix))
        first = None
        for _ in range(8):
            out, _rendered = engine.viewport_frame(depsgraph, view_matrix, window_matrix, W, H, lens=lens)
            first = first if first is not None else out.color_array().copy()
        eight = out.color_array().copy()
        camera = camera_from_scene(depsgraph, scene, W, H)
        moving = engine.render_frame(depsgraph, camera, W, H, aux=False, navigating=True)
        return first, eight, list(moving.stats.messages)

    one, eight, messages = gpu_call(job)
    np.testing.assert_allclose(eight, final, rtol=1e-5, atol=1e-6)
    assert any("depth of field needs 2 or more samples" in m for m in messages)
    sharp = render(_scene(4.0, 2.0, dof=False, samples=1))["Combined"]
    np.testing.assert_allclose(one, sharp, atol=1e-6)
