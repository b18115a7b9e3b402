"""Shadow maps sized to what the camera can resolve (``shadows.Density``): every visible
receiver a map holds gets at least the asked texels per screen pixel, with the fewest texels
(a power of two) that do, and never more than the Shadow Map Size."""

import math

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.scene.extract import Camera, Light  # noqa: E402
from penumbra.engine.shadows import lightspace  # noqa: E402
from penumbra.engine.shadows import planning as shadows  # noqa: E402

FOV = math.radians(50)


def _light(kind, position=(0.5, 0.3, 4.0), **kw):
    matrix = np.eye(4)
    matrix[:3, 3] = position
    return Light(type=kind, color=np.ones(3), matrix=matrix, radius=0.1, **kw)


def _corners(scale=1.0):
    ground = lightspace.box_corners(np.array([-5.0, -5.0, -0.1]), np.array([5.0, 5.0, 0.0]))
    caster = lightspace.box_corners(np.array([-0.5, -0.5, 0.5]), np.array([0.5, 0.5, 1.5]))
    return np.stack([ground, caster]) * scale


def _camera(distance, scale=1.0, ortho=False):
    eye = np.array([0.0, -distance, 0.6 * distance]) * scale
    view = lightspace.look_at(eye, -eye)
    if ortho:
        h = 0.5 * distance * scale
        projection = lightspace.orthographic(-h * 16 / 9, h * 16 / 9, -h, h, 0.01 * scale, 100.0 * scale)
    else:
        projection = lightspace.perspective(FOV, 16 / 9, 0.01 * scale, 100.0 * scale)
    return Camera(view=view, projection=projection, is_ortho=ortho)


def _plan(light, camera, width, per_pixel=2.0, size=8192, scale=1.0, kernel=1.0):
    corners = _corners(scale)
    density = None
    if per_pixel is not None:
        footprint = lightspace.pixel_footprint(camera.projection, camera.is_ortho, width, width * 9 // 16)
        density = shadows.Density(camera.view, *footprint, per_pixel)
    view_corners = lightspace.frustum_corners(camera.projection @ camera.view)
    return shadows.plan_shadows(
        [light],
        corners,
        shadows.MapOptions(size, kernel=kernel),
        shadows.ViewFit(view_corners, camera, density=density),
    )


def _ratio(tile, camera, width):
    """The largest texel / pixel width over the visible receiver points the tile holds."""
    receivers = lightspace.visible_receivers(_corners(), camera.projection @ camera.view)
    points = np.concatenate(
        lightspace.pieces_in(shadows.light_bins.frustum_planes(tile.fit.view_proj), receivers.whole, receivers.pieces)
    )
    per_depth, constant = lightspace.pixel_footprint(camera.projection, camera.is_ortho, width, width * 9 // 16)
    z = -(points @ camera.view[2, :3] + camera.view[2, 3])
    pixel = per_depth * z + constant
    if tile.fit.texel_per_distance > 0:
        texel = tile.fit.texel_per_distance * -(points @ tile.fit.view[2, :3] + tile.fit.view[2, 3])
    else:
        texel = np.full(len(points), tile.fit.texel)
    return float(np.max(texel / pixel))


def test_pixel_footprint_of_perspective_and_orthographic_cameras():
    proj = lightspace.perspective(FOV, 2.0, 0.1, 100.0)
    per_depth, constant = lightspace.pixel_footprint(proj, False, 800, 400)
    assert constant == 0.0
    assert per_depth == pytest.approx(2.0 * math.tan(FOV / 2.0) / 400)  # both sides equal at aspect 2
    ortho = lightspace.orthographic(-4.0, 4.0, -1.0, 1.0, 0.1, 10.0)
    assert lightspace.pixel_footprint(ortho, True, 800, 100) == (0.0, pytest.approx(0.01))
    assert lightspace.pixel_footprint(np.zeros((4, 4)), False, 800, 400) == (0.0, 0.0)


@pytest.mark.parametrize("kind", ["SUN", "SPOT", "POINT"])
@pytest.mark.parametrize("ortho", [False, True])
def test_maps_give_every_pixel_the_asked_texels_with_the_fewest_texels(kind, ortho):
    """Each map: texel / pixel width <= 1 / per_pixel at every visible receiver it holds, and a
    map half as wide would not be (or it is already the smallest)."""
    extra = {"spot_size": math.radians(100)} if kind == "SPOT" else {}
    light = _light(kind, **extra)
    camera = _camera(8.0, ortho=ortho)
    plan = _plan(light, camera, 640)
    full = _plan(light, camera, 640, per_pixel=None)
    assert len(plan.tiles) == len(full.tiles) > 0
    for tile in plan.tiles:
        assert tile.size & (tile.size - 1) == 0 and shadows.MIN_MAP_SIZE <= tile.size < 8192
        ratio = _ratio(tile, camera, 640)
        assert ratio * 2.0 <= 1.0 + 1e-6
    sizes = {t.size for t in plan.tiles}
    # Minimal: the light's largest map at half its size would give some pixel too few texels
    # (texel width scales as 1 / size, up to the 2^(1/4) steps of the crop's extent).
    worst = max(_ratio(t, camera, 640) for t in plan.tiles if t.size == max(sizes))
    assert max(sizes) == shadows.MIN_MAP_SIZE or worst * 2.0 * 2.0 > 1.0 / 1.19


def test_size_follows_resolution_and_distance_and_stops_at_the_setting():
    sun = _light("SUN")
    near = _camera(6.0)
    sizes = {w: _plan(sun, near, w).tiles[0].size for w in (160, 320, 640, 1280)}
    assert sizes[320] == 2 * sizes[160] and sizes[640] == 2 * sizes[320] and sizes[1280] == 2 * sizes[640]
    far = _camera(24.0)
    assert _plan(sun, far, 640).tiles[0].size < sizes[640]  # the same scene seen smaller needs fewer
    assert _plan(sun, near, 640, size=128).tiles[0].size == 128  # capped by the setting
    assert _plan(sun, near, 640, per_pixel=None).tiles[0].size == 8192  # 0 texels per pixel: full size
    # A wider fixed filter needs finer maps (its blur stays within half a pixel).
    assert _plan(sun, near, 640, kernel=3.0).tiles[0].size == 2 * sizes[640]


@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e6])
def test_sizes_do_not_depend_on_the_scene_scale(scale):
    for light in (_light("SUN"), _light("SPOT", spot_size=math.radians(100)), _light("POINT")):
        light.matrix[:3, 3] *= scale
        light.radius *= scale
        unit = _plan(
            _light(light.type, **({"spot_size": math.radians(100)} if light.type == "SPOT" else {})), _camera(8.0), 640
        )
        scaled = _plan(light, _camera(8.0, scale), 640, scale=scale)
        assert [t.size for t in scaled.tiles] == [t.size for t in unit.tiles]


def test_a_camera_inside_a_receiver_keeps_the_full_size():
    """A receiver reaching the camera itself (its pixels are as small as it gets) needs every
    texel: no division by a zero depth, the setting's size."""
    sun = _light("SUN")
    camera = Camera(
        view=lightspace.look_at(np.array([0.0, 0.0, -0.05]), np.array([0.0, 1.0, 0.0])),
        projection=lightspace.perspective(FOV, 16 / 9, 0.01, 100.0),
    )
    plan = _plan(sun, camera, 640, size=1024)
    assert plan.tiles
    assert [t.size for t in plan.tiles] == [1024] * len(plan.tiles)


@pytest.mark.parametrize(
    "sizes, slots",
    [
        ([2048, 512, 512, 256, 256, 512, 512], 2),  # the small maps share one slot
        ([512] * 32, 32),
        ([1024, 1024, 1024, 1024, 2048], 2),
        ([777, 256, 256, 256, 256, 256], 3),  # no power of two: 4 cells of 388 a slot
        ([16, 2048, 16, 64, 1024], 2),
        ([1], 1),
    ],
)
def test_packed_maps_never_overlap_and_share_slots(sizes, slots):
    slot, count, where = shadows.pack_tiles(sizes)
    assert slot == max(sizes) and count == slots
    covered = {}
    for n, (index, x, y) in zip(sizes, where, strict=True):
        assert 0 <= index < count and 0 <= x and 0 <= y and x + n <= slot and y + n <= slot
        covered.setdefault(index, np.zeros((slot, slot), int))[y : y + n, x : x + n] += 1
    assert all(c.max() == 1 for c in covered.values())  # no texel holds two maps
    assert shadows.pack_tiles([]) == (0, 0, [])


def test_a_sun_fitted_to_the_whole_scene_keeps_its_size():
    """Sun Fit 'SCENE' maps do not depend on the camera (never redrawn when the view moves):
    no density sizing for them; a view-fitted sun in the same frame is sized."""
    camera = _camera(8.0)
    footprint = lightspace.pixel_footprint(camera.projection, False, 160, 90)
    density = shadows.Density(camera.view, *footprint, 4.0)
    corners = _corners()
    receivers = lightspace.visible_receivers(corners, camera.projection @ camera.view)
    scene_fit = shadows.plan_shadows(
        [_light("SUN")],
        corners,
        shadows.MapOptions(4096),
        shadows.ViewFit(None, camera, receivers=receivers, density=density),
    )
    view_fit = _plan(_light("SUN"), camera, 160, per_pixel=4.0, size=4096)
    assert [t.size for t in scene_fit.tiles] == [4096]
    assert view_fit.tiles[0].size < 4096


def test_texels_per_pixel_at_its_extremes():
    """A vanishing density asks for the smallest map; a huge one for the setting's size; both
    plan the same maps (same lights, same faces) as full-size maps."""
    camera = _camera(8.0)
    for light in (_light("SUN"), _light("POINT")):
        full = _plan(light, camera, 640, per_pixel=None, size=2048)
        tiny = _plan(light, camera, 640, per_pixel=1e-9, size=2048)
        huge = _plan(light, camera, 640, per_pixel=1e9, size=2048)
        assert len(tiny.tiles) == len(huge.tiles) == len(full.tiles) > 0
        assert {t.size for t in tiny.tiles} == {shadows.MIN_MAP_SIZE}
        assert {t.size for t in huge.tiles} == {2048}
