"""Motion blur's time sampling and transform interpolation (engine/frame/motion.py)."""

import math

import numpy as np
import pytest

from devkit.session import load_penumbra

load_penumbra()
from penumbra.engine.frame import motion  # noqa: E402


def _rotation_z(angle, translation=(0.0, 0.0, 0.0), scale=1.0):
    m = np.eye(4)
    c, s = math.cos(angle), math.sin(angle)
    m[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) * scale
    m[:3, 3] = translation
    return m


def test_transforms_interpolate_piecewise_with_rotation_along_the_arc():
    """Between steps, translation and scale are linear and rotation turns at a constant rate
    (a matrix lerp would shrink a half turn to nothing); at the steps, the steps themselves."""
    times = (0.0, 0.5, 1.0)
    steps = [_rotation_z(0.0), _rotation_z(math.pi / 2, (1, 0, 0), 2.0), _rotation_z(math.pi, (1, 2, 0))]
    for u, angle, position, scale in ((0.25, math.pi / 4, (0.5, 0, 0), 1.5), (0.75, 3 * math.pi / 4, (1, 1, 0), 1.5)):
        np.testing.assert_allclose(motion.interpolate(times, steps, u), _rotation_z(angle, position, scale), atol=1e-12)
    for k, u in enumerate(times):
        np.testing.assert_allclose(motion.interpolate(times, steps, u), steps[k], atol=1e-12)
    np.testing.assert_allclose(motion.interpolate(times, steps, -3.0), steps[0])  # clamped to the shutter
    mirrored = np.diag([-1.0, 1.0, 1.0, 1.0])
    np.testing.assert_allclose(motion.interpolate(times, [mirrored, mirrored, mirrored], 0.3), mirrored, atol=1e-12)


@pytest.mark.parametrize("count", [2, 5, 16, 64])
def test_a_frames_sample_times_cover_the_shutter_once_each(count):
    """The frame's N samples take the N strata of the shutter, each once; sample 0 the middle
    one; under a shutter curve, strata of its distribution (more samples where it is high)."""
    times = sorted(motion.sample_time(s, count) for s in range(count))
    np.testing.assert_allclose(times, (np.arange(count) + 0.5) / count)
    assert motion.sample_time(0, count) == pytest.approx((count // 2 + 0.5) / count)
    ramp = tuple(np.linspace(0.0, 1.0, motion.CURVE_POINTS))  # weight rising along the shutter
    curved = np.array([motion.sample_time(s, count, ramp) for s in range(count)])
    # A ramp's distribution is u^2: strata at sqrt((k + 1/2) / N).
    np.testing.assert_allclose(np.sort(curved), np.sqrt((np.arange(count) + 0.5) / count), atol=2e-3)
    assert motion.sample_time(3, count, (0.0,) * motion.CURVE_POINTS) == motion.sample_time(3, count)  # flat: a box
