"""The contract every registered post effect keeps, checked over ``EFFECTS``: a new effect is
covered by adding it to the registry, without new test code.

Each check runs the effect's declared defaults (unless it says otherwise) through the real
stack on the GPU, on float RGBA images, row 0 at the bottom:

* mix 0 returns the input exactly and runs no pass; so does a disabled layer;
* mix is linear: out(m) = in + m * (out(1) - in), |error| <= 1e-6 + 1e-6 * |expected|
  (one float32 blend; inputs up to 40, measured errors are a few ulps);
* NaN/Inf input never gives NaN/Inf output: non-finite components read exactly as 0;
* 1x1, 300x1 and 1x300 frames give finite output of the right shape, alone and all stacked;
* every parameter at its extremes (``devkit.post.param_extremes``: min, max or soft max, a
  large value where no hard max exists, every enum item, both booleans; for images none,
  a huge-valued one and one holding NaN/Inf), one at a time and all together, gives finite
  output on clean and on non-finite input;
* an 8K frame (7680x4320) through each effect gives finite sampled output (its INT sizes and
  counts at their lightest values that still run a pass: see ``_lightest_settings``; every
  effect at its full defaults costs about 24 s at 8K on llvmpipe, this about 8 s).
"""

import numpy as np
import pytest

from devkit.post import (
    HDR_PIXEL,
    blender_image,
    effects,
    hdr_image,
    layer,
    param_extremes,
    run_flat,
    run_many,
    with_non_finite,
)

EFFECT_IDS = list(effects())
PARAMS = [(eid, p.name) for eid, cls in effects().items() for p in cls.params]

# (check, effect id[, parameter]) -> why it fails today: the case is marked xfail(strict=True)
# until the engine is fixed, so the suite stays green and the fix turns it into a pass.
KNOWN_FAILURES = {}

SIZES = [(1, 1), (300, 1), (1, 300)]  # width x height
FRAME = 7  # a frame other than 0, for effects that animate


def cases(check, keys):
    """pytest params for ``keys`` (effect ids or (effect id, param) pairs) with the known
    failures of ``check`` marked xfail(strict=True)."""
    out = []
    for key in keys:
        key_tuple = key if isinstance(key, tuple) else (key,)
        reason = KNOWN_FAILURES.get((check, *key_tuple))
        marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
        out.append(pytest.param(*key_tuple, id="-".join(map(str, key_tuple)), marks=marks))
    return out


def param(effect_id, name):
    return next(p for p in effects()[effect_id].params if p.name == name)


def image_extremes(name):
    """IMAGE parameter values: none (the effect's built-in behaviour), a huge-valued image and
    one holding NaN/Inf and negative texels. Built inside the GPU call's fresh file."""
    hot = np.full((1, 1, 4), HDR_PIXEL, np.float32)
    bad = np.array(
        [
            [[np.nan, 1.0, -np.inf, 1.0], [np.inf, -5.0, 0.5, np.nan]],
            [[0.25, np.nan, 2.0, 1.0], [-1.0, 0.0, np.inf, 0.0]],
        ],
        np.float32,
    )
    return [
        ("None", lambda: None),
        ("huge", lambda: blender_image(f"{name} huge", hot)),
        ("non-finite", lambda: blender_image(f"{name} non-finite", bad)),
    ]


def extremes(p):
    """[(label, value factory)] for one parameter (factories: images need a fresh file)."""
    if p.type == "IMAGE":
        return image_extremes(p.name)
    values = param_extremes(p)
    assert values, f"{p.name}: no extremes for type {p.type}"
    return [(label, lambda v=value: v) for label, value in values]


def assert_finite(out, what):
    bad = ~np.isfinite(out)
    assert not bad.any(), f"{what}: {bad.sum()} non-finite values, first at {np.argwhere(bad)[0].tolist()}"


# --- mix, enable ------------------------------------------------------------------------------


@pytest.mark.parametrize("effect_id", cases("mix 0", EFFECT_IDS))
def test_zero_mix_is_the_input_exactly_and_runs_no_pass(penumbra, gpu_call, effect_id):
    img = with_non_finite(hdr_image(24, 40, 11), seed=1)  # even NaN comes back as it went in
    ((out, stats),) = run_many(gpu_call, [(img, [layer(effect_id, mix=0.0)], FRAME)])
    np.testing.assert_array_equal(out, img)
    assert stats.post_passes == 0


@pytest.mark.parametrize("effect_id", cases("disabled", EFFECT_IDS))
def test_disabled_layer_is_the_input_exactly_and_runs_no_pass(penumbra, gpu_call, effect_id):
    img = with_non_finite(hdr_image(24, 40, 11), seed=2)
    ((out, stats),) = run_many(gpu_call, [(img, [layer(effect_id, enabled=False)], FRAME)])
    np.testing.assert_array_equal(out, img)
    assert stats.post_passes == 0


@pytest.mark.parametrize("effect_id", cases("mix", EFFECT_IDS))
def test_mix_is_linear(penumbra, gpu_call, effect_id):
    img = hdr_image(24, 40, 11)
    mixes = (1.0, 0.25, 0.5, 0.9)
    runs = run_many(gpu_call, [(img, [layer(effect_id, mix=m)], FRAME) for m in mixes])
    full, stats = runs[0]
    assert stats.post_passes >= 1
    assert np.abs(full - img).max() > 1e-3, "the defaults leave the image unchanged: nothing to blend"
    for m, (out, s) in zip(mixes[1:], runs[1:]):
        assert s.post_passes == stats.post_passes
        expected = img + m * (full.astype(np.float64) - img)
        np.testing.assert_allclose(out, expected, rtol=1e-6, atol=1e-6, err_msg=f"mix {m}")


# --- bad input, odd frames ------------------------------------------------------------------


@pytest.mark.parametrize("effect_id", cases("non-finite", EFFECT_IDS))
def test_non_finite_input_reads_as_zero(penumbra, gpu_call, effect_id):
    img = with_non_finite(hdr_image(24, 40, 13), seed=3)
    zeroed = np.nan_to_num(img, nan=0.0, posinf=0.0, neginf=0.0)
    runs = run_many(gpu_call, [(src, [layer(effect_id, mix=m)], FRAME) for m in (1.0, 0.5) for src in (img, zeroed)])
    for (out, _), (ref, _), m in zip(runs[::2], runs[1::2], (1.0, 0.5)):
        assert_finite(out, f"mix {m}")
        np.testing.assert_array_equal(out, ref, err_msg=f"mix {m}: NaN/Inf do not read as 0")


@pytest.mark.parametrize("effect_id", cases("sizes", EFFECT_IDS))
def test_degenerate_frame_sizes(penumbra, gpu_call, effect_id):
    images = [hdr_image(h, w, seed=w + h, highlights=2) for w, h in SIZES]
    runs = run_many(gpu_call, [(img, [layer(effect_id)], FRAME) for img in images])
    for (w, h), img, (out, stats) in zip(SIZES, images, runs):
        assert out.shape == img.shape
        assert_finite(out, f"{w}x{h}")
        assert stats.post_passes >= 1


@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
def test_all_effects_stacked_on_degenerate_frame_sizes(penumbra, gpu_call, size):
    w, h = size
    img = np.full((h, w, 4), 0.5, np.float32)
    img[0, 0, :3] = 20.0
    alone = [(img, [layer(eid)], FRAME) for eid in EFFECT_IDS]
    runs = run_many(gpu_call, alone + [(img, [layer(eid) for eid in EFFECT_IDS], FRAME)])
    out, stats = runs[-1]
    assert out.shape == img.shape
    assert_finite(out, "all effects stacked")
    assert stats.post_layers == len(EFFECT_IDS)  # every layer ran
    # ... in the passes each takes alone, but for consecutive point layers, which share one.
    from penumbra.engine.post.base import PointEffect

    point = [issubclass(effects()[eid], PointEffect) for eid in EFFECT_IDS]
    shared = sum(1 for before, this in zip(point, point[1:]) if before and this)
    assert shared >= 1
    assert stats.post_passes == sum(s.post_passes for _, s in runs[:-1]) - shared


# --- parameters ----------------------------------------------------------------------------


def _run_extremes(gpu_call, effect_id, settings):
    """Run ``settings`` ([(label, {param: value factory})]) on a clean and a non-finite HDR
    image; assert every output is finite, or, where the parameters make the layer an identity
    (no pass ran), exactly the input (NaN included: a layer that does not run reads nothing)."""
    clean = hdr_image(24, 40, 17)
    dirty = with_non_finite(clean, seed=4)

    def make_runs():
        runs = []
        for _, factories in settings:
            params = {name: make() for name, make in factories.items()}
            runs += [(clean, [layer(effect_id, **params)], FRAME), (dirty, [layer(effect_id, **params)], FRAME)]
        return runs

    results = run_many(gpu_call, None, make_runs)
    failures = []
    for i, (label, _) in enumerate(settings):
        for (out, stats), src, which in zip(results[2 * i : 2 * i + 2], (clean, dirty), ("clean", "non-finite")):
            if stats.post_passes == 0:
                if not np.array_equal(out, src, equal_nan=True):
                    failures.append(f"{label} on {which} input: no pass ran, yet the output is not the input")
                continue
            bad = ~np.isfinite(out)
            if bad.any():
                failures.append(
                    f"{label} on {which} input: {bad.sum()} non-finite values, e.g. {out[bad][:3].tolist()}"
                )
    assert not failures, f"{effect_id}: " + "; ".join(failures)


@pytest.mark.parametrize("effect_id,name", cases("extremes", PARAMS))
def test_each_parameter_at_its_extremes_gives_finite_output(penumbra, gpu_call, effect_id, name):
    settings = [(f"{name}={label}", {name: make}) for label, make in extremes(param(effect_id, name))]
    _run_extremes(gpu_call, effect_id, settings)


@pytest.mark.parametrize("effect_id", cases("extremes together", EFFECT_IDS))
def test_all_parameters_at_their_extremes_together_give_finite_output(penumbra, gpu_call, effect_id):
    """Every parameter at its first extreme (the lows) at once, then at its last (the highs)."""
    per_param = {p.name: extremes(p) for p in effects()[effect_id].params}
    settings = [
        (which, {name: values[index][1] for name, values in per_param.items()})
        for which, index in (("all low", 0), ("all high", -1))
    ]
    _run_extremes(gpu_call, effect_id, settings)


# --- 8K -------------------------------------------------------------------------------------


def _lightest_settings(gpu_call):
    """{effect id: params} for the 8K check: the defaults, with every INT parameter that has a
    declared minimum at the smallest value from it upwards that still runs a pass (found on a
    small frame). Per-pixel cost grows with kernel widths and counts (GLOW at its default
    radius 16 alone takes about 13 s at 8K on llvmpipe); the size-dependent code an 8K frame
    exercises (targets, coordinates, cell and hash arithmetic) does not depend on them, and
    the widths themselves are checked at their extremes above."""
    img = hdr_image(8, 8, 5)
    candidates = []  # (effect id, param, value)
    for eid, cls in effects().items():
        for p in cls.params:
            if p.type == "INT" and p.min is not None:
                top = p.max if p.max is not None else p.min + 3
                candidates += [(eid, p.name, v) for v in range(int(p.min), min(int(p.min) + 4, int(top) + 1))]
    runs = run_many(gpu_call, [(img, [layer(eid, **{name: v})], FRAME) for eid, name, v in candidates])
    chosen = {eid: {} for eid in EFFECT_IDS}
    for (eid, name, v), (_, stats) in zip(candidates, runs):
        if stats.post_passes > 0 and name not in chosen[eid]:
            chosen[eid][name] = v
    return chosen


def test_8k_frame_through_every_effect(penumbra, gpu_call):
    """Each effect alone on a 7680x4320 HDR frame cleared on the GPU; every 60th row and column
    read back. One GPU call for all effects keeps this to one source frame and one pool."""
    w, h = 7680, 4320
    color = (2.0, 1.0, 0.5, 1.0)  # above the default thresholds: glow and flare do work
    settings = _lightest_settings(gpu_call)
    results = run_flat(gpu_call, w, h, color, [[layer(eid, **settings[eid])] for eid in EFFECT_IDS], step=60)
    failures = []
    for eid, (sampled, stats) in zip(EFFECT_IDS, results):
        assert sampled.shape == (h // 60, w // 60, 4)
        if stats.post_passes < 1:
            failures.append(f"{eid} {settings[eid]}: no pass ran")
        if not np.all(np.isfinite(sampled)):
            failures.append(f"{eid} {settings[eid]}: {np.sum(~np.isfinite(sampled))} non-finite samples")
    assert not failures, "; ".join(failures)
