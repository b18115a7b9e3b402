"""One diffuse bounce from reflective shadow maps (Light Paths > Diffuse Bounces 1,
``shaders/lib/indirect_rsm.glsl``): the bounced light on a wall beside a sun-lit floor against
a numpy integration of the floor's radiance, frames without the bounce unchanged, no
reflective code or targets where no light has a map, and finite values at the extremes."""

import math

import numpy as np
import pytest

from devkit import scenes
from devkit.analytic import camera_matrices, plane_hits
from devkit.render import render

W, H = 128, 72
ALBEDO = scenes.WHITE_ALBEDO
SUN = 3.0
FLOOR = 2.0  # the floor's half side
WALL = (1.0, 2.0)  # the wall's half width and height


def floor_and_wall(scale=1.0, sun_tilt=0.0, strength=SUN, size=(W, H)):
    """A white floor of side 2 FLOOR at z = 0 lit by a sun from straight above (tilted about X
    by ``sun_tilt`` radians), and a white wall across it at y = 0 (a single quad, two-sided)
    that the sun meets edge-on: it gets no direct light, only what the floor reflects. The
    camera looks at the wall's -y side over the floor in front of it; world black."""
    scene = scenes.empty_scene(*size)
    mat = scenes.white()
    f, (hw, hh) = FLOOR * scale, (WALL[0] * scale, WALL[1] * scale)
    scenes.mesh_object(scene, "Floor", [(-f, -f, 0), (f, -f, 0), (f, f, 0), (-f, f, 0)], [(0, 1, 2, 3)], mat=mat)
    scenes.mesh_object(scene, "Wall", [(-hw, 0, 0), (hw, 0, 0), (hw, 0, hh), (-hw, 0, hh)], [(0, 1, 2, 3)], mat=mat)
    scenes.light(scene, "Sun", "SUN", strength, rotation=(sun_tilt, 0, 0), angle=0.0)
    cam = scenes.camera(scene, (0.0, -6.5 * scale, 3.2 * scale), (0, 0, 0), lens=35.0, clip=(0.05 * scale, 50 * scale))
    scenes.aim(cam, (0.0, 0.0, 0.9 * scale))
    scene.penumbra.shadow_map_size = 512
    return scene


def wall_reference(points, albedo=ALBEDO, sun=SUN, n=600, irradiance=None):
    """Radiance a Lambertian wall at ``points`` (on y = 0, seen from -y) reflects of the light
    the floor's part y < 0 sends it: albedo / pi * integral of L cos_p cos_s / d^2 over the
    floor, L = albedo * E / pi (midpoint rule on an n x n/2 grid); E = ``sun``, or
    ``irradiance(x, y)`` on the floor."""
    xs = (np.arange(n) + 0.5) / n * 2 * FLOOR - FLOOR
    ys = (np.arange(n // 2) + 0.5) / (n // 2) * FLOOR - FLOOR
    X, Y = np.meshgrid(xs, ys)
    dA = (2 * FLOOR / n) * (FLOOR / (n // 2))
    E = sun if irradiance is None else irradiance(X, Y)
    out = []
    for px, _py, pz in points:
        d2 = (X - px) ** 2 + Y**2 + pz**2
        out.append(np.sum(E * -Y * pz / d2**2) * dA)
    return albedo / math.pi * albedo / math.pi * np.array(out)


def wall_pixels(scene, scale=1.0):
    """(mask of wall pixels away from its edges, their points in the unscaled scene), rows
    bottom-up."""
    view, proj, w, h = camera_matrices(scene)
    p, _depth = plane_hits(view, proj, w, h, z=0.0, axis=1)
    p = p / scale
    hw, hh = WALL
    mask = (np.abs(p[..., 0]) < hw - 0.3) & (p[..., 2] > 0.3) & (p[..., 2] < hh - 0.3)
    return mask, p[mask]


@pytest.fixture
def bounce(penumbra):
    return floor_and_wall


def test_wall_bounce_matches_integration(bounce):
    scene = bounce()
    scene.penumbra.render_samples = 16
    scene.penumbra.indirect_bounces = 1
    scene.penumbra.indirect_samples = 64
    img = render(scene)["Combined"][..., :3]
    mask, points = wall_pixels(scene)
    assert mask.sum() > 300
    ref = wall_reference(points)
    got = img[mask].mean(axis=1)
    ratio = got.mean() / ref.mean()
    print(f"wall bounce: penumbra {got.mean():.5f}, numpy {ref.mean():.5f}, ratio {ratio:.4f}")
    assert abs(ratio - 1.0) < 0.05
    # Along the wall's height, where the bounce falls off (x2.6 from 0.3 to 1.7 above the floor).
    bands = np.digitize(points[:, 2], (0.65, 1.0, 1.35))
    for b in range(4):
        r = got[bands == b].mean() / ref[bands == b].mean()
        print(f"  band {b}: penumbra {got[bands == b].mean():.5f}, numpy {ref[bands == b].mean():.5f}, ratio {r:.4f}")
        assert abs(r - 1.0) < 0.08
    scene.penumbra.indirect_bounces = 0
    off = render(scene)["Combined"][..., :3]
    assert float(np.abs(off[mask]).max()) < 1e-6  # the wall gets no direct light


LOCAL = (1.6, 0.0, 1.0)  # in the wall's plane, beside it: the wall gets no direct light


@pytest.mark.parametrize("kind", ["POINT", "SPOT", "AREA"])
def test_local_light_bounce_matches_integration(bounce, kind):
    """The same wall lit by the floor under a point, spot (150 degree cone) or small area light
    standing in the wall's plane beside it (Blender's conventions, lib/lights.glsl): the
    point's and area's senders span several cube faces (the mixed strategy), the spot's one
    perspective map cut by its cone."""
    scene = bounce()
    import bpy

    bpy.data.objects.remove(scene.objects["Sun"])
    power = 300.0
    props = {"POINT": {"shadow_soft_size": 0.0}, "SPOT": {"shadow_soft_size": 0.0, "spot_size": math.radians(150)}}
    props["SPOT"]["spot_blend"] = 0.0
    props["AREA"] = {"size": 0.01}
    scenes.light(scene, "L", kind, power, location=LOCAL, **props[kind])
    scene.penumbra.render_samples = 16
    scene.penumbra.indirect_bounces = 1
    scene.penumbra.indirect_samples = 64

    def irradiance(x, y):
        dx, dy, h = x - LOCAL[0], y - LOCAL[1], LOCAL[2]
        d2 = dx**2 + dy**2 + h**2
        cos = h / np.sqrt(d2)
        if kind == "AREA":
            return power / math.pi * cos * cos / d2
        e = power / (4 * math.pi) * cos / d2
        return np.where(cos > math.cos(math.radians(75)), e, 0.0) if kind == "SPOT" else e

    img = render(scene)["Combined"][..., :3]
    mask, points = wall_pixels(scene)
    ref = wall_reference(points, irradiance=irradiance, n=800)
    ratio = img[mask].mean() / ref.mean()
    print(f"{kind}: penumbra {img[mask].mean():.5f}, numpy {ref.mean():.5f}, ratio {ratio:.4f}")
    assert abs(ratio - 1.0) < 0.05


def _frame(gpu_call, scene):
    """One single-sample frame through the engine core: (colour, the renderer's compiled
    program names, whether its atlas has reflective targets)."""
    from penumbra.engine.scene.extract import camera_from_scene

    def job(engine, depsgraph):
        out = engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, W, H), W, H)
        renderer = engine.renderer
        names = {key[0] for key in renderer.shaders._cache}
        return out.color_array().copy(), names, renderer.shadows.flux is not None

    return gpu_call(job)


def test_without_the_bounce_nothing_changes(bounce, gpu_call):
    """Diffuse Bounces 0 compiles no reflective program, makes no reflective target and draws
    the same frame before and after a frame with the bounce; with it the wall lights up."""
    scene = bounce()
    before, names, targets = _frame(gpu_call, scene)
    assert not targets and not any("rsm" in n for n in names)
    scene.penumbra.indirect_bounces = 1
    lit, names, targets = _frame(gpu_call, scene)
    assert targets and any(n.startswith("lit") and n.endswith("_rsm") for n in names)
    assert any(n.startswith("shadow_depth") and n.endswith("_rsm") for n in names)
    mask, _points = wall_pixels(scene)
    assert float(lit[mask][:, :3].mean()) > 0.05 > float(before[mask][:, :3].mean())
    scene.penumbra.indirect_bounces = 0
    after, names, targets = _frame(gpu_call, scene)
    assert not targets and not any("rsm" in n for n in names)
    assert np.array_equal(before, after)


def test_no_shadowed_light_no_reflective_maps(bounce, gpu_call):
    """With the bounce on but no light with a map (the sun's shadow off), nothing reflective
    is compiled or drawn and the frame is the one without the bounce."""
    scene = bounce()
    scene.objects["Sun"].data.use_shadow = False
    plain, _names, _targets = _frame(gpu_call, scene)
    scene.penumbra.indirect_bounces = 1
    image, names, targets = _frame(gpu_call, scene)
    assert not targets and not any("rsm" in n for n in names)
    assert np.array_equal(plain, image)


@pytest.mark.parametrize(
    "case",
    ["strength 1e6", "scale 1e-3", "scale 1e4", "grazing sun", "one pixel"],
)
def test_finite_at_the_extremes(bounce, case):
    """Finite frames at extreme strength, scale, sun angle and frame size; at either scale the
    wall's bounced radiance is the unscaled scene's (radiance does not depend on scale)."""
    scale = {"scale 1e-3": 1e-3, "scale 1e4": 1e4}.get(case, 1.0)
    strength = 1e6 if case == "strength 1e6" else SUN
    tilt = math.radians(89.5) if case == "grazing sun" else 0.0
    size = (1, 1) if case == "one pixel" else (W, H)
    scene = bounce(scale=scale, sun_tilt=tilt, strength=strength, size=size)
    scene.penumbra.render_samples = 4
    scene.penumbra.indirect_bounces = 1
    scene.penumbra.indirect_samples = 32
    img = render(scene)["Combined"]
    assert np.all(np.isfinite(img))
    if case in ("strength 1e6", "scale 1e-3", "scale 1e4"):
        mask, points = wall_pixels(scene, scale)
        ratio = img[mask][:, :3].mean() / wall_reference(points, sun=strength).mean()
        print(f"{case}: ratio to the numpy reference {ratio:.4f}")
        assert abs(ratio - 1.0) < 0.1


@pytest.mark.parametrize("depth_format", ["FLOAT16", "RGBA8"])
def test_bounce_with_colour_depth_formats(bounce, depth_format):
    """Maps stored as colour (drawn in the scratch target and copied) carry the reflective
    targets too."""
    scene = bounce()
    scene.penumbra.shadow_depth_format = depth_format
    scene.penumbra.render_samples = 4
    scene.penumbra.indirect_bounces = 1
    scene.penumbra.indirect_samples = 64
    img = render(scene)["Combined"][..., :3]
    mask, points = wall_pixels(scene)
    ratio = img[mask].mean() / wall_reference(points).mean()
    print(f"{depth_format}: ratio to the numpy reference {ratio:.4f}")
    assert abs(ratio - 1.0) < 0.05


def test_reflective_maps_are_budgeted_and_a_refusal_never_fails_the_render(bounce, gpu_call, monkeypatch):
    """The bounce's reflective targets are budgeted before they are allocated: a frame whose
    maps would take more than the budget draws them smaller and says so once, still with the
    bounce (a budget of 1 MB here: the sun's one map of 512 texels reduced to 256, 16 bytes a
    texel); where the GPU refuses
    the targets anyway (an allocation that raises), the frame renders without the bounce,
    the same as Diffuse Bounces 0, with a message, instead of failing."""
    from penumbra.engine.frame import shadow_maps, shadow_pass
    from penumbra.engine.scene.extract import camera_from_scene

    assert shadow_pass.reflective_map_size(26, 2730) == math.isqrt((1 << 30) // (16 * 30))  # 6 x 5 slots
    assert shadow_pass.reflective_map_size(4, 1024) is None

    def frame(scene):
        def job(engine, depsgraph):
            out = engine.render_frame(depsgraph, camera_from_scene(depsgraph, scene, W, H), W, H)
            atlas = engine.renderer.shadows
            return out.color_array().copy(), list(out.stats.messages), atlas.flux is not None, atlas.size

        return gpu_call(job)

    scene = bounce()
    plain, _messages, _targets, _size = frame(scene)
    scene.penumbra.indirect_bounces = 1
    full, _messages, targets, size = frame(scene)
    assert targets and size == 512
    monkeypatch.setattr(shadow_pass, "RSM_BUDGET_BYTES", 1 << 20)
    small, messages, targets, size = frame(scene)
    assert targets and size == math.isqrt((1 << 20) // 16) == 256, size
    assert sum("reduced to" in m and "reflective maps" in m for m in messages) == 1, messages
    mask, _points = wall_pixels(scene)
    assert float(small[mask][:, :3].mean()) == pytest.approx(float(full[mask][:, :3].mean()), rel=0.1)
    monkeypatch.setattr(shadow_pass, "RSM_BUDGET_BYTES", 1 << 30)

    real = shadow_maps.new_texture

    def refuse(pool, size, fmt):
        if fmt == shadow_maps.RSM_FORMAT:
            raise RuntimeError("GPUTexture.__new__(...) failed with 'unknown error'")
        return real(pool, size, fmt)

    monkeypatch.setattr(shadow_maps, "new_texture", refuse)
    refused, messages, targets, _size = frame(scene)
    assert not targets
    assert sum("refused the bounce's reflective maps" in m for m in messages) == 1, messages
    np.testing.assert_allclose(refused, plain, atol=1e-6)
