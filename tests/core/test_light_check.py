"""The suite's light check (``devkit.session.light_check_failure``), which the harness runs on
every frame Penumbra renders in a test: it must catch what it is there to catch."""

import numpy as np

from devkit.session import light_check_failure


def _frame(value=0.5):
    frame = np.full((4, 6, 4), value, np.float32)
    frame[..., 3] = 1.0
    return frame


def test_a_non_negative_finite_frame_passes_and_rounding_is_forgiven():
    assert light_check_failure(_frame()) is None
    frame = _frame(1000.0)
    frame[0, 0, 0] = -1e-4  # a millionth of the largest value is rounding
    assert light_check_failure(frame) is None


def test_negative_light_and_non_finite_values_fail():
    frame = _frame()
    frame[1, 2, 1] = -0.01
    assert "below zero" in light_check_failure(frame)
    for bad in (np.nan, np.inf, -np.inf):
        frame = _frame()
        frame[0, 0, 3] = bad  # alpha too
        assert "not finite" in light_check_failure(frame)
