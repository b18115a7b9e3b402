"""Numerical stability at the extremes: grazing and axis-aligned suns, huge scenes, a 1e6
near/far ratio, a light inside a closed box, huge filter radii. Each check compares the
rendered shadow with the analytic one or counts wrongly shadowed pixels, with the bound stated
in the assertion."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.analytic import camera_matrices, iou, plane_hits, ray_hits_box
from devkit.render import render
from devkit.scenes import WHITE_ALBEDO as ALBEDO


@pytest.mark.parametrize("fit, bound", [("VIEW", 0.95), ("SCENE", None)])
def test_tight_sun_fit_keeps_shadows_sharp_in_a_huge_scene(shadow_scene, analytic_shadow, fit, bound):
    """A map fitted to a 2 km ground leaves a 1 m box a texel wide; fitted to the
    view it stays exact. The loose fit's IoU is measured to show the difference."""
    scene = shadow_scene("SUN", "NONE", size=128)
    scene.objects["Plane"].scale = (70.0, 70.0, 1.0)  # 2.1 km
    scene.penumbra.shadow_sun_fit = fit
    _lum, visibility, on_plane, shadowed = analytic_shadow(scene, scene.objects["L"])
    score = iou((visibility < 0.5)[on_plane], shadowed[on_plane])
    if bound is not None:
        assert score > bound, f"IoU {score:.3f}"
    else:
        assert score < 0.8, f"the whole-scene fit should be visibly coarse here (IoU {score:.3f})"


def test_grazing_sun_no_acne_and_bounded_peter_panning(penumbra, analytic_shadow):
    """Sun 2 degrees above the horizon over a plane with a box standing on it."""
    elevation = math.radians(2.0)
    scene = scenes.empty_scene(200, 200)
    scenes.box_over_plane(scene, plane_size=20.0, box_center=(0, 0, 0.5))
    # Light travels towards +Y, 2 degrees downwards.
    scenes.light(scene, "L", "SUN", 3.0, rotation=(math.pi / 2 - elevation, 0, 0), angle=0.0)
    scenes.top_camera(scene, height=20.0, ortho_scale=8.0)
    scene.penumbra.shadow_filter = "PCF"
    scene.penumbra.shadow_map_size = 2048
    lum, _vis, on_plane, shadowed = analytic_shadow(scene, scene.objects["L"], lo=(-0.5, -0.5, 0.0), hi=(0.5, 0.5, 1.0))
    lit = on_plane & ~shadowed
    expected = ALBEDO / math.pi * 3.0 * math.sin(elevation)
    assert np.median(lum[lit]) == pytest.approx(expected, rel=0.01)
    acne = (lit & (lum < 0.5 * expected)).sum() / lit.sum()
    assert acne < 0.005, f"acne on {acne:.2%} of the lit plane"
    # Peter-panning: along the centre column behind the box, the shadow must start within a
    # few light-space texels of the box's base (y = 0.5).
    from penumbra.engine.shadows import lightspace

    view, proj, w, h = camera_matrices(scene)
    p, _ = plane_hits(view, proj, w, h)
    col = w // 2
    ys = p[:, col, 1]
    behind = (ys > 0.5) & (ys < 3.0)
    dark = behind & (lum[:, col] < 0.5 * expected)
    first_dark = ys[dark].min()
    corners = np.array([[x, y, z] for x in (-10, 10) for y in (-10, 10) for z in (0, 1)])
    d = np.array([0, math.cos(elevation), -math.sin(elevation)])
    texel = lightspace.fit_sun_ortho(d, corners, 2048).texel
    gap_texels = (first_dark - 0.5) * math.sin(elevation) / texel  # gap measured across the light rays
    assert gap_texels < 3.0, f"shadow starts {gap_texels:.1f} texels from the caster"


@pytest.mark.parametrize("direction", ["-Z", "+Y", "-Y"])
def test_axis_aligned_suns(penumbra, direction):
    """Look-at degeneracy: suns exactly along world axes light and shadow correctly."""
    rotation = {"-Z": (0, 0, 0), "+Y": (math.pi / 2, 0, 0), "-Y": (-math.pi / 2, 0, 0)}[direction]
    scene = scenes.empty_scene(96, 96)
    mat = scenes.white()
    # A wall facing the light and a box between them.
    if direction == "-Z":
        scenes.box_over_plane(scene, plane_size=10.0, mat=mat)
        lo, hi = (-0.5, -0.5, 1.0), (0.5, 0.5, 2.0)
        scenes.camera(scene, (0, -6, 8), (math.radians(37), 0, 0), ortho_scale=6.0, clip=(0.1, 30))
        axis, value = 2, 0.0
    else:
        sign = 1.0 if direction == "+Y" else -1.0
        wall = scenes.plane(scene, size=10.0, mat=mat)
        wall.rotation_euler = (math.pi / 2, 0, 0)
        wall.location = (0, 3.0 * sign, 0)
        lo, hi = (-0.5, -0.5 + 1.0 * sign, -0.5), (0.5, 0.5 + 1.0 * sign, 0.5)
        scenes.box(scene, center=(0, 1.0 * sign, 0), mat=mat)
        scenes.camera(
            scene,
            (4.0, -8.0 * sign, 3.0),
            (math.radians(75), 0, math.radians(25 if sign > 0 else 155)),
            ortho_scale=7.0,
            clip=(0.1, 40),
        )
        axis, value = 1, 3.0 * sign
    sun = scenes.light(scene, "L", "SUN", 3.0, rotation=rotation, angle=0.0)
    scene.penumbra.shadow_filter = "NONE"
    out = render(scene, passes=("Combined", "Depth"))
    lum, depth = out["Combined"][..., 0], out["Depth"][..., 0]
    assert np.all(np.isfinite(lum))
    view, proj, w, h = camera_matrices(scene)
    p, plane_depth = plane_hits(view, proj, w, h, z=value, axis=axis)
    on_wall = np.abs(depth - plane_depth) < 1e-3 * np.maximum(plane_depth, 1.0)
    d = -np.array(sun.matrix_world.to_3x3().col[2])
    shadowed = ray_hits_box(p, np.broadcast_to(-d, p.shape), lo, hi)
    assert on_wall.sum() > 1000 and shadowed[on_wall].sum() > 50
    lit_value = ALBEDO / math.pi * 3.0
    assert np.median(lum[on_wall & ~shadowed]) == pytest.approx(lit_value, rel=1e-3)
    assert iou((lum < 0.5 * lit_value)[on_wall], shadowed[on_wall]) > 0.95


def test_camera_near_far_ratio_1e6(shadow_scene, analytic_shadow):
    scene = shadow_scene("SUN", "PCF")
    scene.camera.data.clip_start, scene.camera.data.clip_end = 1e-3, 1e3
    _lum, visibility, on_plane, shadowed = analytic_shadow(scene, scene.objects["L"])
    assert iou((visibility < 0.5)[on_plane], shadowed[on_plane]) > 0.95


def test_point_light_inside_a_closed_box(penumbra):
    """Walls around a light are lit by it, not shadowed by themselves (near plane, bias)."""
    scene = scenes.empty_scene(64, 64)
    scenes.box(scene, center=(0, 0, 0), size=(4, 4, 4), mat=scenes.white())
    scenes.light(scene, "L", "POINT", 100.0, location=(0, 0, 0), shadow_soft_size=0.0)
    scenes.camera(scene, (0, 0, 0.5), (0, 0, 0), lens=20.0, clip=(0.01, 10))  # looks at the floor
    scene.penumbra.shadow_filter = "PCF"
    c = render(scene)["Combined"][..., 0]
    # Floor centre: distance 2, normal incidence.
    expected = ALBEDO * 100.0 / (4 * math.pi**2 * 4.0)
    assert c[32, 32] == pytest.approx(expected, rel=0.01)
    assert (c < 0.2 * expected).mean() < 0.01  # nothing inside is in shadow


def test_huge_filter_radius_stays_bounded(shadow_scene):
    scene = shadow_scene("SUN", "PCF", size=64)
    scene.penumbra.pcf_kernel_size, scene.penumbra.pcf_spacing = 15, 200.0
    c = render(scene)["Combined"][..., 0]
    assert np.all(np.isfinite(c)) and c.max() <= ALBEDO / math.pi * 3.0 * 1.001
    scene.penumbra.shadow_filter = "JITTER"
    scene.penumbra.shadow_filter_radius = 32.0
    scene.penumbra.shadow_samples = 64
    c = render(scene)["Combined"][..., 0]
    assert np.all(np.isfinite(c)) and c.max() <= ALBEDO / math.pi * 3.0 * 1.001


# --- far from the origin, scaled cameras, extreme clip ratios ------------------------------


def _moved(scene, offset):
    for ob in scene.objects:
        if ob.parent is None:
            ob.location = tuple(c + o for c, o in zip(ob.location, offset, strict=True))


@pytest.mark.parametrize("scene_name", ["default cube", "box over plane"])
def test_a_scene_far_from_the_world_origin_renders_as_at_it(shadow_scene, scene_name):
    """The same scene moved 100 km along each axis (camera, light and all): positions reach
    the GPU relative to the camera, so float32 keeps its precision there. Blender itself
    stores the moved positions in float32 (8 mm apart at 1e5), so silhouettes may move by a
    tenth of a pixel; lit surfaces must not get acne or broken face normals. Before the frame
    origin, Blender's default cube scene moved so: mean 0.020, 3.6 % of pixels over 0.05."""
    if scene_name == "default cube":  # Blender's startup scene: 2 m cube, 1000 W point light
        scene = scenes.empty_scene(96, 64)
        scenes.box(scene, "Cube", center=(0, 0, 0), size=(2, 2, 2), mat=scenes.material("Grey", (0.8, 0.8, 0.8)))
        scenes.light(scene, "L", "POINT", 1000.0, location=(4.08, 1.0, 5.9), shadow_soft_size=0.1)
        scenes.camera(scene, (7.36, -6.93, 4.96), (math.radians(63.6), 0.0, math.radians(46.7)), lens=50.0)
    else:
        scene = shadow_scene("POINT", "PCF", size=96)
        scenes.look_at(scene, (2.0, -9.0, 7.0), (0.0, 0.0, 1.0))
    near = render(scene)["Combined"][..., :3]
    _moved(scene, (1.0e5, 1.0e5, 1.0e5))
    far = render(scene)["Combined"][..., :3]
    diff = np.abs(far - near).max(axis=-1)
    assert diff.mean() < 3e-3, diff.mean()  # measured 7e-4 on both
    assert np.mean(diff > 0.05) < 0.01, np.mean(diff > 0.05)  # measured 0.1 %


def test_a_scaled_camera_object_renders_as_unscaled(shadow_scene):
    """Blender's engines ignore the camera object's scale: the image and the Depth pass are
    those of the unscaled camera (a scaled camera used to scale the view, and so the clip
    distances and the Depth pass)."""
    scene = shadow_scene("SUN", "PCF", size=64)
    scenes.look_at(scene, (2.0, -9.0, 7.0), (0.0, 0.0, 1.0))
    plain = render(scene, passes=("Combined", "Depth"))
    scene.camera.scale = (3.0, 3.0, 3.0)
    scaled = render(scene, passes=("Combined", "Depth"))
    np.testing.assert_allclose(scaled["Combined"], plain["Combined"], atol=1e-5)
    np.testing.assert_allclose(scaled["Depth"], plain["Depth"], rtol=1e-5)


def test_camera_near_far_ratio_1e8_perspective(shadow_scene, analytic_shadow):
    """Clip Start 1e-6 with Clip End 100: Blender's float32 camera matrix rounds the far
    plane away (-(f + n) / (f - n) becomes -1); the depth terms are taken again in float64
    from the clip distances, so the frame renders (it used to fail with a division by zero)
    and the shadow is exact."""
    scene = shadow_scene("SUN", "PCF", size=96)
    scenes.look_at(scene, (2.0, -9.0, 7.0), (0.0, 0.0, 1.0))
    scene.camera.data.clip_start, scene.camera.data.clip_end = 1e-6, 100.0
    _lum, visibility, on_plane, shadowed = analytic_shadow(scene, scene.objects["L"])
    assert on_plane.sum() > 2000
    assert iou((visibility < 0.5)[on_plane], shadowed[on_plane]) > 0.95
    # Without a map (no shadow plan): the same image as with an ordinary clip range.
    scene.objects["L"].data.use_shadow = False
    extreme = render(scene)["Combined"]
    scene.camera.data.clip_start = 0.1
    np.testing.assert_allclose(extreme, render(scene)["Combined"], atol=1e-4)
