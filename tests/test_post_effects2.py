"""COLORIZER, FISHEYE and LENS_FLARE on the GPU against numpy references."""

from types import SimpleNamespace

import bpy
import numpy as np
import pytest

import scenes
from test_post import gaussian_reference, run_layers, run_stack


# --- helpers ------------------------------------------------------------------------------


def run_with_images(gpu_call, image, make_layers):
    """``run_layers`` for layers that reference Blender images (built after the file reset)."""
    return run_stack(gpu_call, image, make_layers=make_layers)[0]


def bpy_image(name, rgba):
    """A float Blender image holding ``rgba`` (h, w, 4), row 0 at the bottom, read at full
    float precision (no half-float GPU copy)."""
    h, w = rgba.shape[:2]
    img = bpy.data.images.new(name, w, h, float_buffer=True)
    img.use_half_precision = False
    img.pixels.foreach_set(np.ascontiguousarray(rgba, np.float32).ravel())
    return img


def pixel_centres(h, w):
    y, x = np.mgrid[0:h, 0:w] + 0.5
    return x, y


def bilinear(img, px, py, edge="CLAMP"):
    """Bilinear read of ``img`` (h, w, C) at pixel positions (texel centres at i + 0.5) with the
    fisheye edge modes; float64."""
    img = np.asarray(img, dtype=np.float64)
    h, w = img.shape[:2]
    tx, ty = np.asarray(px, np.float64) - 0.5, np.asarray(py, np.float64) - 0.5
    x0, y0 = np.floor(tx).astype(int), np.floor(ty).astype(int)
    fx, fy = (tx - x0)[..., None], (ty - y0)[..., None]

    def fold(i, n):
        if edge == "MIRROR":
            m = np.mod(i, 2 * n)
            return np.where(m >= n, 2 * n - 1 - m, m)
        return np.clip(i, 0, n - 1)

    def tap(ix, iy):
        v = img[fold(iy, h), fold(ix, w)]
        if edge == "BLACK":
            inside = (ix >= 0) & (ix < w) & (iy >= 0) & (iy < h)
            v = v * inside[..., None]
        return v

    bottom = tap(x0, y0) * (1 - fx) + tap(x0 + 1, y0) * fx
    top = tap(x0, y0 + 1) * (1 - fx) + tap(x0 + 1, y0 + 1) * fx
    return bottom * (1 - fy) + top * fy


def sanitized(img):
    return np.nan_to_num(img.astype(np.float64), nan=0.0, posinf=0.0, neginf=0.0)


# --- COLORIZER ----------------------------------------------------------------------------


def colorizer_layer(image=None, blur_radius=0, strength=1.0, mix=1.0):
    return ("COLORIZER", True, mix, SimpleNamespace(image=image, blur_radius=blur_radius, strength=strength))


def colorizer_reference(img, lut, blur_radius, strength):
    from penumbra.engine.post.colorizer import LUMA_WEIGHTS, lookup_coords, lut_lookup

    h, w = img.shape[:2]
    c = sanitized(img)
    blurred = gaussian_reference(c, blur_radius) if blur_radius > 0 else c
    x, y = pixel_centres(h, w)
    lx, ly = lookup_coords(blurred[..., :3] @ np.array(LUMA_WEIGHTS), x, y, w, h)
    out = c.copy()
    out[..., :3] = c[..., :3] * (1 - strength) + lut_lookup(lut, lx, ly)[..., :3] * strength
    return out


@pytest.mark.parametrize("blur_radius", [0, 3])
def test_colorizer_default_ramp_matches_reference(penumbra, gpu_call, blur_radius):
    from penumbra.engine.post.colorizer import DEFAULT_LUT

    rng = np.random.default_rng(10 + blur_radius)
    img = rng.uniform(0, 1.3, (37, 52, 4)).astype(np.float32)  # odd size, some luminance > 1
    out, stats = run_layers(gpu_call, img, [colorizer_layer(None, blur_radius, 0.7)])
    np.testing.assert_allclose(out, colorizer_reference(img, DEFAULT_LUT, blur_radius, 0.7), atol=2e-6)
    assert stats.post_passes == (3 if blur_radius else 1)


def test_colorizer_lookup_coordinates_hit_texel_centres(penumbra, gpu_call):
    """x = 0 / 0.5 / 1 and y = 0 land exactly on texel centres of a 3 x 2 LUT."""
    lut = np.zeros((2, 3, 4), np.float32)
    lut[..., 3] = 1.0
    lut[0, :, :3] = [(1, 0, 0), (0, 1, 0), (0, 0, 1)]  # y = 0 row (image centre)
    lut[1, :, :3] = [(5, 5, 5), (6, 6, 6), (7, 7, 7)]
    for value, expect in ((0.0, (1, 0, 0)), (0.5, (0, 1, 0)), (1.0, (0, 0, 1)), (3.0, (0, 0, 1))):
        img = np.full((5, 5, 4), value, np.float32)  # grey: luminance = value; centre pixel y = 0
        out, _ = run_with_images(gpu_call, img, lambda: [colorizer_layer(bpy_image("LUT", lut))])
        np.testing.assert_allclose(out[2, 2, :3], expect, atol=1e-6)
        assert out[2, 2, 3] == value  # alpha kept


@pytest.mark.parametrize("lut_shape", [(3, 7), (1, 16), (1, 1)])
def test_colorizer_with_image_lut(penumbra, gpu_call, lut_shape):
    rng = np.random.default_rng(sum(lut_shape))
    lut = rng.uniform(0, 2, (*lut_shape, 4)).astype(np.float32)
    img = rng.uniform(0, 1, (30, 41, 4)).astype(np.float32)
    out, _ = run_with_images(gpu_call, img, lambda: [colorizer_layer(bpy_image("LUT", lut), 2, 1.0)])
    np.testing.assert_allclose(out, colorizer_reference(img, lut, 2, 1.0), atol=5e-6)


def test_colorizer_identity_mix_nan_and_tiny_images(penumbra, gpu_call):
    from penumbra.engine.post.colorizer import DEFAULT_LUT

    rng = np.random.default_rng(5)
    img = rng.uniform(0, 1, (20, 24, 4)).astype(np.float32)
    same, stats = run_layers(gpu_call, img, [colorizer_layer(None, 4, 0.0)])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0

    full, _ = run_layers(gpu_call, img, [colorizer_layer(None, 1, 1.0)])
    half, _ = run_layers(gpu_call, img, [colorizer_layer(None, 1, 1.0, mix=0.5)])
    np.testing.assert_allclose(half, 0.5 * img + 0.5 * full, atol=1e-6)

    bad = img.copy()
    bad[5, 5] = np.nan
    bad[12, 7, 1] = np.inf
    out, _ = run_layers(gpu_call, bad, [colorizer_layer(None, 2, 1.0)])
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out, colorizer_reference(bad, DEFAULT_LUT, 2, 1.0), atol=2e-6)

    # 1 x 1 (y = 0: the centre row) and a 1-pixel-high strip with a blur wider than the image.
    one = np.full((1, 1, 4), 0.25, np.float32)
    out, _ = run_layers(gpu_call, one, [colorizer_layer(None, 256, 1.0)])
    np.testing.assert_allclose(out, colorizer_reference(one, DEFAULT_LUT, 0, 1.0), atol=1e-6)
    strip = rng.uniform(0, 1, (1, 300, 4)).astype(np.float32)
    out, _ = run_layers(gpu_call, strip, [colorizer_layer(None, 40, 1.0)])
    np.testing.assert_allclose(out, colorizer_reference(strip, DEFAULT_LUT, 40, 1.0), atol=2e-6)


# --- FISHEYE ------------------------------------------------------------------------------


def fisheye_layer(strength, edge="CLAMP", mix=1.0):
    return ("FISHEYE", True, mix, SimpleNamespace(strength=strength, edge=edge))


def fisheye_reference(img, strength, edge):
    from penumbra.engine.post.fisheye import fisheye_source

    h, w = img.shape[:2]
    x, y = pixel_centres(h, w)
    sx, sy = fisheye_source(x, y, w, h, strength)
    return bilinear(sanitized(img), sx, sy, edge)


def coordinate_image(h, w):
    """R, G = the pixel centre's x, y: the output then shows which position it read."""
    x, y = pixel_centres(h, w)
    return np.stack([x, y, np.zeros_like(x), np.ones_like(x)], -1).astype(np.float32)


@pytest.mark.parametrize("strength", [-1.0, -0.4, 0.5, 1.0])
def test_fisheye_reads_where_the_mapping_says(penumbra, gpu_call, strength):
    from penumbra.engine.post.fisheye import fisheye_source

    h, w = 45, 80
    out, _ = run_layers(gpu_call, coordinate_image(h, w), [fisheye_layer(strength)])
    x, y = pixel_centres(h, w)
    sx, sy = fisheye_source(x, y, w, h, strength)
    # Bilinear reads of a linear ramp return the position itself (clamped at the borders).
    np.testing.assert_allclose(out[..., 0], np.clip(sx, 0.5, w - 0.5), atol=1e-4)
    np.testing.assert_allclose(out[..., 1], np.clip(sy, 0.5, h - 0.5), atol=1e-4)
    # The map is monotonic along rows and columns through the centre (no folds), and the corner
    # circle is fixed: the corner pixels read (almost) themselves.
    assert np.all(np.diff(out[h // 2, :, 0]) >= -1e-5) and np.all(np.diff(out[:, w // 2, 1]) >= -1e-5)
    # Bulge: the pixel 10.5 px right of the centre reads closer to it (magnified); pinch: farther.
    read = out[h // 2, w // 2 + 10, 0] - w / 2
    assert (read < 10.5) if strength > 0 else (read > 10.5)


@pytest.mark.parametrize("edge", ["CLAMP", "BLACK", "MIRROR"])
@pytest.mark.parametrize("strength", [-1.0, -0.6, 0.3, 1.0])
def test_fisheye_edge_modes_match_reference(penumbra, gpu_call, edge, strength):
    rng = np.random.default_rng(int(strength * 10) + 17)
    img = rng.uniform(0, 3, (40, 64, 4)).astype(np.float32)
    out, stats = run_layers(gpu_call, img, [fisheye_layer(strength, edge)])
    assert np.all(np.isfinite(out)) and stats.post_passes == 1
    np.testing.assert_allclose(out, fisheye_reference(img, strength, edge), atol=1e-4)


def test_fisheye_limits_have_no_holes(penumbra, gpu_call):
    """A full bulge reads only inside the image, so even BLACK leaves no empty pixel; a full
    pinch with BLACK is empty exactly where the mapping leaves the image."""
    from penumbra.engine.post.fisheye import fisheye_source

    h, w = 36, 90
    img = np.ones((h, w, 4), np.float32)
    out, _ = run_layers(gpu_call, img, [fisheye_layer(1.0, "BLACK")])
    np.testing.assert_allclose(out, 1.0, atol=1e-6)
    out, _ = run_layers(gpu_call, img, [fisheye_layer(-1.0, "BLACK")])
    x, y = pixel_centres(h, w)
    sx, sy = fisheye_source(x, y, w, h, -1.0)
    inside = (sx >= 0.5) & (sx <= w - 0.5) & (sy >= 0.5) & (sy <= h - 0.5)
    far_out = (sx < -0.5) | (sx > w + 0.5) | (sy < -0.5) | (sy > h + 0.5)
    assert inside.any() and far_out.any()
    np.testing.assert_allclose(out[inside], 1.0, atol=1e-5)
    np.testing.assert_array_equal(out[far_out], 0.0)  # transparent black, alpha included


def test_fisheye_identity_mix_nan_and_tiny_images(penumbra, gpu_call):
    rng = np.random.default_rng(8)
    img = rng.uniform(0, 1, (25, 31, 4)).astype(np.float32)
    same, stats = run_layers(gpu_call, img, [fisheye_layer(0.0, "MIRROR")])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0

    full, _ = run_layers(gpu_call, img, [fisheye_layer(0.7)])
    half, _ = run_layers(gpu_call, img, [fisheye_layer(0.7, mix=0.5)])
    np.testing.assert_allclose(half, 0.5 * img + 0.5 * full, atol=1e-6)

    bad = img.copy()
    bad[12, 15] = np.nan  # the centre pixel, magnified by the bulge
    bad[3, 3, 0] = -np.inf
    out, _ = run_layers(gpu_call, bad, [fisheye_layer(0.8, "MIRROR")])
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out, fisheye_reference(bad, 0.8, "MIRROR"), atol=1e-4)

    for size in ((1, 1), (1, 300), (300, 1)):
        img = rng.uniform(0, 1, (*size, 4)).astype(np.float32)
        for edge in ("CLAMP", "BLACK", "MIRROR"):
            out, _ = run_layers(gpu_call, img, [fisheye_layer(-1.0, edge)])
            assert np.all(np.isfinite(out)) and out.shape == img.shape
            np.testing.assert_allclose(out, fisheye_reference(img, -1.0, edge), atol=1e-4)


# --- LENS_FLARE ---------------------------------------------------------------------------

FLARE = dict(threshold=1.0, intensity=1.0, mode="ADD", ghosts=5, ghost_spacing=0.35, halo_radius=0.5, halo_width=0.15, image=None)


def flare_layer(mix=1.0, **params):
    return ("LENS_FLARE", True, mix, SimpleNamespace(**{**FLARE, **params}))


def flare_reference(img, lens=None, **params):
    """The flare ``f`` of lens_flare.py's definition, in float64 (RGB)."""
    from penumbra.engine.post.colorizer import lut_lookup
    from penumbra.engine.post.lens_flare import LENS_RAMP

    p = SimpleNamespace(**{**FLARE, **params})
    h, w = img.shape[:2]
    bright = np.maximum(sanitized(img)[..., :3] - p.threshold, 0.0)
    x, y = pixel_centres(h, w)
    cx, cy = w / 2, h / 2
    diag = np.hypot(cx, cy)
    ux, uy = x - cx, y - cy
    dist = np.hypot(ux, uy)
    r = dist / diag
    f = np.zeros((h, w, 3))
    for i in range(p.ghosts):
        k = p.ghost_spacing * i - 1.0
        qx, qy = cx + ux * k, cy + uy * k
        a = 1.0 - np.clip(np.hypot(qx - cx, qy - cy) / diag, 0.0, 1.0)
        f += (a**3)[..., None] * bilinear(bright, qx, qy, "BLACK")
    if p.halo_width > 0:
        t = np.clip(1.0 - np.abs(r - p.halo_radius) / p.halo_width, 0.0, 1.0)
        ring = t * t * (3.0 - 2.0 * t)
        safe = np.where(dist > 0, dist, 1.0)
        dx, dy = np.where(dist > 0, ux / safe, 0.0), np.where(dist > 0, uy / safe, 0.0)
        along = p.halo_radius * diag - dist
        f += ring[..., None] * bilinear(bright, cx + dx * along, cy + dy * along, "BLACK")
    if lens is None:
        tint = lut_lookup(LENS_RAMP[None], r, np.zeros_like(r))
    else:
        lh, lw = lens.shape[:2]
        tint = bilinear(lens[..., :3], x / w * lw, y / h * lh, "CLAMP")
    return p.intensity * f * tint


def flare_scene(seed=0):
    """48 x 64: a dim background with a few HDR lights (one a 3 x 3 spot)."""
    rng = np.random.default_rng(seed)
    img = rng.uniform(0, 0.8, (48, 64, 4)).astype(np.float32)
    img[30, 41, :3] = (60.0, 40.0, 20.0)
    img[10:13, 12:15, :3] = 8.0
    img[20, 30, :3] = (1.5, 3.0, 0.5)
    return img


@pytest.mark.parametrize("ghosts,spacing", [(5, 0.35), (1, 0.0), (16, 0.13)])
def test_lens_flare_matches_reference(penumbra, gpu_call, ghosts, spacing):
    img = flare_scene()
    params = dict(ghosts=ghosts, ghost_spacing=spacing, intensity=0.8)
    out, stats = run_layers(gpu_call, img, [flare_layer(**params)])
    f = flare_reference(img, **params)
    assert f.max() > 1.0  # the test sees a real flare
    np.testing.assert_allclose(out[..., :3] - img[..., :3], f, atol=2e-5 * f.max())
    np.testing.assert_array_equal(out[..., 3], img[..., 3])
    assert stats.post_passes == 1


def test_lens_flare_with_lens_image(penumbra, gpu_call):
    rng = np.random.default_rng(3)
    lens = rng.uniform(0, 2, (5, 7, 4)).astype(np.float32)
    img = flare_scene(seed=1)
    out, _ = run_with_images(gpu_call, img, lambda: [flare_layer(image=bpy_image("Dirt", lens))])
    f = flare_reference(img, lens=lens)
    np.testing.assert_allclose(out[..., :3] - img[..., :3], f, atol=2e-5 * f.max())


def test_lens_flare_ghosts_sit_where_predicted(penumbra, gpu_call):
    """One bright pixel: each ghost's centroid is at C + (b - C) / (spacing * i - 1)."""
    from penumbra.engine.post.lens_flare import ghost_positions

    h, w = 96, 128
    img = np.zeros((h, w, 4), np.float32)
    img[60, 80, :3] = 100.0  # centre of the light: (80.5, 60.5)
    out, _ = run_layers(gpu_call, img, [flare_layer(threshold=1.0, ghosts=6, ghost_spacing=0.3, halo_width=0.0)])
    f = out[..., 0] - img[..., 0]
    x, y = pixel_centres(h, w)
    checked = 0
    for i, gx, gy, scale in ghost_positions(80.5, 60.5, w, h, 6, 0.3):
        reach = scale * np.sqrt(2.0) + 1.0  # the ghost of one texel spans +-scale pixels per axis
        if not (reach < gx < w - reach and reach < gy < h - reach):
            continue
        near = np.hypot(x - gx, y - gy) <= reach
        weight = f * near
        assert weight.sum() > 0, f"ghost {i} missing"
        cx, cy = (weight * x).sum() / weight.sum(), (weight * y).sum() / weight.sum()
        assert abs(cx - gx) < 0.3 and abs(cy - gy) < 0.3, (i, cx, cy, gx, gy)
        checked += 1
    assert checked >= 4
    # Nothing else flares: all energy lies in the predicted ghosts.
    mask = np.zeros((h, w), bool)
    for _, gx, gy, scale in ghost_positions(80.5, 60.5, w, h, 6, 0.3):
        mask |= np.hypot(x - gx, y - gy) <= scale * np.sqrt(2.0) + 1.0
    assert f[~mask].max() == 0.0


def test_lens_flare_halo_is_a_ring(penumbra, gpu_call):
    h, w = 80, 80
    img = np.zeros((h, w, 4), np.float32)
    x, y = pixel_centres(h, w)
    r = np.hypot(x - 40, y - 40) / np.hypot(40, 40)
    img[np.hypot(x - 40, y - 40) < 4, :3] = 10.0  # a bright disc at the centre
    out, _ = run_layers(gpu_call, img, [flare_layer(ghosts=0, halo_radius=0.5, halo_width=0.1)])
    f = out[..., 0] - img[..., 0]
    ref = flare_reference(img, ghosts=0, halo_radius=0.5, halo_width=0.1)
    np.testing.assert_allclose(out[..., :3] - img[..., :3], ref, atol=2e-5 * ref.max())
    assert f[(r < 0.4) | (r > 0.6)].max() == 0.0
    angles = np.arctan2(y - 40, x - 40)[f > 0.1]
    assert np.histogram(angles, bins=16, range=(-np.pi, np.pi))[0].min() > 0  # closed ring


@pytest.mark.parametrize("mode", ["ADD", "SCREEN", "AVERAGE", "DIFFERENCE"])
def test_lens_flare_merge_modes(penumbra, gpu_call, mode):
    """Each mode against its formula, given the flare the shader itself produced (ADD minus
    input) and the numpy reference of that flare."""
    from penumbra.engine.post.lens_flare import merge

    img = flare_scene(seed=4)
    img[5, 5, :3] = (1.5, 0.5, 3.0)  # HDR input where the flare is also present
    added, _ = run_layers(gpu_call, img, [flare_layer(intensity=0.6)])
    f = added[..., :3].astype(np.float64) - img[..., :3]
    np.testing.assert_allclose(f, flare_reference(img, intensity=0.6), atol=2e-5 * f.max())
    out, _ = run_layers(gpu_call, img, [flare_layer(intensity=0.6, mode=mode)])
    # f was read back as (c + f) - c in float32: allow its rounding, scaled like the formula.
    tol = 1e-6 * (1.0 + np.abs(img[..., :3])) * (1.0 + np.abs(f))
    assert np.all(np.abs(out[..., :3] - merge(img[..., :3], f, mode)) <= tol)
    np.testing.assert_array_equal(out[..., 3], img[..., 3])


def test_lens_flare_screen_hdr_behaviour(penumbra, gpu_call):
    """Documented: SCREEN on values above 1 follows the formula, even where it darkens."""
    from penumbra.engine.post.lens_flare import LENS_RAMP, merge

    img = np.zeros((1, 1, 4), np.float32)
    img[0, 0] = (3.0, 2.0, 0.5, 1.0)
    # 1 x 1: every ghost reads the pixel itself with weight 1; one ghost, tint LENS_RAMP[0].
    out, _ = run_layers(gpu_call, img, [flare_layer(threshold=0.0, ghosts=1, halo_width=0.0, mode="SCREEN")])
    f = img[0, 0, :3] * LENS_RAMP[0]
    np.testing.assert_allclose(out[0, 0, :3], merge(img[0, 0, :3], f, "SCREEN"), rtol=1e-6)
    assert out[0, 0, 0] == pytest.approx(-3.0)  # R: c = f = 3 gives 1 - (-2) * (-2)


def test_lens_flare_identities(penumbra, gpu_call):
    img = flare_scene(seed=2)
    for mode in ("ADD", "SCREEN", "AVERAGE", "DIFFERENCE"):
        same, stats = run_layers(gpu_call, img, [flare_layer(intensity=0.0, mode=mode)])
        np.testing.assert_array_equal(same, img)
        assert stats.post_passes == 0
    same, stats = run_layers(gpu_call, img, [flare_layer(ghosts=0, halo_width=0.0)])
    np.testing.assert_array_equal(same, img)
    assert stats.post_passes == 0
    # Nothing above the threshold: the flare is black and each mode returns merge(c, 0).
    high = float(img.max()) + 0.01
    for mode, expect, tol in (("ADD", img, 0.0), ("SCREEN", img, 1e-6), ("DIFFERENCE", img, 0.0)):
        out, stats = run_layers(gpu_call, img, [flare_layer(threshold=high, mode=mode)])
        np.testing.assert_allclose(out, expect, atol=tol * 60, rtol=tol)
        assert stats.post_passes == 1
    out, _ = run_layers(gpu_call, img, [flare_layer(threshold=high, mode="AVERAGE")])
    np.testing.assert_allclose(out[..., :3], img[..., :3] * 0.5, rtol=1e-7)


def test_lens_flare_mix_nan_and_tiny_images(penumbra, gpu_call):
    from penumbra.engine.post.lens_flare import LENS_RAMP

    img = flare_scene(seed=6)
    full, _ = run_layers(gpu_call, img, [flare_layer()])
    half, _ = run_layers(gpu_call, img, [flare_layer(mix=0.5)])
    np.testing.assert_allclose(half, 0.5 * img + 0.5 * full, atol=1e-5 * full.max())

    bad = img.copy()
    bad[30, 41] = np.nan  # the brightest light becomes NaN: read as 0, never spread
    bad[10, 12, 0] = np.inf
    out, _ = run_layers(gpu_call, bad, [flare_layer(threshold=0.5)])
    assert np.all(np.isfinite(out))
    f = flare_reference(bad, threshold=0.5)
    np.testing.assert_allclose(out[..., :3], sanitized(bad)[..., :3] + f, atol=2e-5 * f.max())

    # 1 x 1: every ghost reads the pixel itself (weight 1); the halo ring misses r = 0.
    one = np.full((1, 1, 4), 5.0, np.float32)
    out, _ = run_layers(gpu_call, one, [flare_layer(ghosts=16, ghost_spacing=2.0, halo_radius=0.0, halo_width=0.0)])
    np.testing.assert_allclose(out[0, 0, :3], 5.0 + 16 * 4.0 * LENS_RAMP[0], rtol=1e-6)
    out, _ = run_layers(gpu_call, one, [flare_layer(ghosts=0, halo_radius=0.0, halo_width=1.0)])
    np.testing.assert_allclose(out[0, 0, :3], 5.0 + 4.0 * LENS_RAMP[0], rtol=1e-6)  # ring = 1 at r = 0
    strip = np.random.default_rng(9).uniform(0, 0.8, (1, 300, 4)).astype(np.float32)
    strip[0, 200, :3] = 50.0
    out, _ = run_layers(gpu_call, strip, [flare_layer(ghosts=16, ghost_spacing=2.0, intensity=10.0, halo_width=0.5)])
    f = flare_reference(strip, ghosts=16, ghost_spacing=2.0, intensity=10.0, halo_width=0.5)
    assert np.all(np.isfinite(out))
    np.testing.assert_allclose(out[..., :3] - strip[..., :3], f, atol=2e-5 * f.max())


# --- all three ------------------------------------------------------------------------------


@pytest.mark.parametrize("effect_id", ["COLORIZER", "FISHEYE", "LENS_FLARE"])
def test_defaults_change_an_hdr_image_and_stay_finite(penumbra, gpu_call, effect_id):
    from penumbra.engine.post import EFFECTS

    img = flare_scene(seed=11)
    out, stats = run_layers(gpu_call, img, [(effect_id, True, 1.0, EFFECTS[effect_id].defaults())])
    assert np.all(np.isfinite(out)) and stats.post_passes >= 1
    assert np.abs(out - img).max() > 0.05


def test_image_parameters_through_layer_properties(penumbra):
    """The production path: layer properties (an Image pointer) -> render settings -> a final
    render. A 1 x 1 LUT recolours everything; a black lens image removes the flare."""
    from helpers import render

    scene = scenes.empty_scene(16, 12)
    scenes.top_camera(scene)
    scenes.set_world(scene, (0.5, 0.5, 0.5))
    lut = bpy_image("LUT", np.array([[(0.2, 0.4, 0.8, 1.0)]], np.float32))
    dirt = bpy_image("Dirt", np.zeros((2, 2, 4), np.float32))
    bpy.ops.penumbra.layer_add(effect="LENS_FLARE")
    bpy.ops.penumbra.layer_add(effect="COLORIZER")
    layers = scene.penumbra.layers
    assert [layer.effect for layer in layers] == ["COLORIZER", "LENS_FLARE"]
    layers[0].colorizer.image = lut
    layers[0].colorizer.blur_radius = 0
    layers[1].lens_flare.threshold = 0.0  # everything flares...
    layers[1].lens_flare.image = dirt  # ...through a black lens texture
    c = render(scene)["Combined"]
    np.testing.assert_allclose(c[..., :3], np.broadcast_to((0.2, 0.4, 0.8), c[..., :3].shape), atol=1e-6)
    layers[1].lens_flare.image = None  # the built-in ramp: now the flare shows
    c = render(scene)["Combined"]
    assert np.all(c[..., :3] > (0.2 + 1e-3, 0.4 + 1e-3, 0.8 + 1e-3))
