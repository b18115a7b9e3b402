"""Consecutive point layers (per-pixel: SCANLINES, VIGNETTE, SEPIA, NOISE) share one pass: the
same image as one pass each, and as the numpy references chained, in fewer passes."""

import numpy as np
import pytest

from devkit.post import hdr_image, layer, run_stack, with_non_finite

FRAME = 11


def _stack():
    """Every point effect, one twice, with partial mixes and non-default parameters."""
    return [
        layer("VIGNETTE", mix=0.6, radius=0.3, softness=0.5, roundness=0.4, color=(0.2, 0.1, 0.4)),
        layer("SEPIA", amount=0.7),
        layer("SCANLINES", mix=0.5, count=7, thickness=0.3, intensity=0.8, scroll_speed=0.25, antialias=True),
        layer("NOISE", amount=0.3, size=2, monochrome=False, seed=3),
        layer("NOISE", mix=0.8, amount=0.1, size=1, monochrome=True, seed=4),
        layer("SCANLINES", count=5, thickness=0.5, intensity=0.4, antialias=False),
    ]


def _run(gpu_call, image, layers, fuse, monkeypatch):
    from penumbra.engine.post import base

    monkeypatch.setattr(base, "FUSE_POINT_LAYERS", fuse)
    return run_stack(gpu_call, image, layers, frames=[FRAME])[0]


def _reference(img, layers):
    """The stack's numpy references chained in float64 (finite input)."""
    from penumbra.engine.post.noise import apply_reference, grain_reference
    from penumbra.engine.post.scanlines import scanline_darkness, scroll_offset
    from penumbra.engine.post.sepia import sepia_reference
    from penumbra.engine.post.vignette import vignette_factor

    c = img.astype(np.float64)
    h, w = c.shape[:2]
    y, x = np.mgrid[0:h, 0:w] + 0.5
    for lay in layers:
        p, e = lay.params, c.copy()
        if lay.effect == "VIGNETTE":
            f = vignette_factor(x, y, w, h, p.radius, p.softness, p.roundness)[..., None]
            e[..., :3] = c[..., :3] + f * (np.array(p.color) - c[..., :3])
        elif lay.effect == "SEPIA":
            e[..., :3] = sepia_reference(c[..., :3], p.amount)
        elif lay.effect == "SCANLINES":
            offset = scroll_offset(FRAME, p.scroll_speed)
            dark = scanline_darkness(np.arange(h), h, p.count, p.thickness, offset, p.antialias)
            e[..., :3] *= (1.0 - p.intensity * dark)[:, None, None]
        elif lay.effect == "NOISE":
            e = apply_reference(c, p.amount, grain_reference(w, h, FRAME, p.size, p.seed, p.monochrome))
        c = c + lay.mix * (e - c) if lay.mix < 1.0 else e
    return c


def test_point_layers_share_a_pass_and_match_their_references(penumbra, gpu_call, monkeypatch):
    img = hdr_image(36, 52, seed=21)
    layers = _stack()
    fused, stats = _run(gpu_call, img, layers, True, monkeypatch)
    apart, apart_stats = _run(gpu_call, img, layers, False, monkeypatch)
    assert (stats.post_passes, stats.post_layers) == (1, len(layers))
    assert (apart_stats.post_passes, apart_stats.post_layers) == (len(layers), len(layers))
    # Each layer's arithmetic is the same float32 sequence, stored in registers instead of an
    # RGBA32F target; the compiler may fuse a multiply and an add across two layers.
    np.testing.assert_allclose(fused, apart, rtol=1e-6, atol=1e-6)
    # Against the references in float64: six layers of float32 rounding on values up to 40.
    np.testing.assert_allclose(fused, _reference(img, layers), rtol=1e-5, atol=1e-5)


def test_non_finite_input_is_cleaned_between_fused_layers_as_between_passes(penumbra, gpu_call, monkeypatch):
    img = with_non_finite(hdr_image(20, 24, seed=5), seed=2)
    # Finite, but SEPIA takes its red and green past float32's range: the second SEPIA reads
    # that +Inf as 0, as a pass of its own would (were it read as Inf, all three would be).
    img[10, 12, :3] = 3.0e38
    overflow = [layer("SEPIA"), layer("SEPIA"), layer("NOISE", amount=0.3, monochrome=False), layer("SEPIA")]
    for layers in (_stack(), overflow):
        fused, _ = _run(gpu_call, img, layers, True, monkeypatch)
        apart, _ = _run(gpu_call, img, layers, False, monkeypatch)
        assert np.isfinite(fused).all()
        np.testing.assert_allclose(fused, apart, rtol=1e-6, atol=1e-6)
    assert np.all(fused[10, 12, :3] != 0.0)


@pytest.mark.parametrize(
    "effects, passes, apart",
    [
        (["SEPIA"] * 9, 2, 9),  # a pass takes at most MAX_POINT_LAYERS (8) layers
        (["VIGNETTE", "BLUR", "SEPIA", "NOISE"], 1 + 2 + 1, 5),  # a blur between point layers parts them
        (["SCANLINES", "FISHEYE", "VIGNETTE"], 3, 3),
    ],
)
def test_runs_of_point_layers_are_parted_by_other_layers_and_by_the_limit(
    penumbra, gpu_call, monkeypatch, effects, passes, apart
):
    from penumbra.engine.post.base import MAX_POINT_LAYERS

    assert MAX_POINT_LAYERS == 8
    img = hdr_image(16, 20, seed=9)
    layers = [layer(eid, mix=0.9) for eid in effects]
    fused, stats = _run(gpu_call, img, layers, True, monkeypatch)
    separate, apart_stats = _run(gpu_call, img, layers, False, monkeypatch)
    assert (stats.post_passes, stats.post_layers) == (passes, len(effects))
    assert (apart_stats.post_passes, apart_stats.post_layers) == (apart, len(effects))
    np.testing.assert_allclose(fused, separate, rtol=1e-6, atol=1e-6)
