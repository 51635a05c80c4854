"""The variance static detector (Tedaldi et al. 2014) and the hand-rotation angles, on a synthetic
hand-held log whose gyro bias (3.7 °/s per axis) would fool a rate threshold."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.processing import detect_segments
from imucalib.processing.static_detector import detect_static_and_rotations

RATE_HZ = 200.0
BIAS_DPS = np.array([3.7, -3.7, 3.7])


@pytest.fixture(scope="module")
def log(hand_held_log):
    return hand_held_log


def test_the_rate_threshold_detector_sees_no_static_interval_with_a_3_7_dps_bias(log):
    t, gyro, accel, _, _ = log
    res = detect_segments(t, gyro, accel_mps2=accel)
    assert res.static == ()


def test_static_intervals_lie_inside_the_true_still_periods(log):
    t, gyro, accel, still, _ = log
    res = detect_static_and_rotations(t, gyro, accel)
    assert len(res.static) == len(still)
    half_window = res.window_samples / RATE_HZ / 2
    for seg, (a, b) in zip(res.static, still, strict=True):
        assert a - 1e-9 <= seg.start_time_s and seg.end_time_s <= b + 1e-9
        # and cover it but for about half a window at each end (a transition's own motion)
        assert seg.start_time_s - a <= half_window + 0.15 or a == 0.0
        assert b - seg.end_time_s <= half_window + 0.15 or b == t[-1] + 1 / RATE_HZ
        # the static mean rate is the bias
        assert np.allclose(np.rad2deg(seg.mean_rate_rps), BIAS_DPS, atol=0.05)


def test_hand_rotations_and_their_integrated_angles(log):
    t, gyro, accel, _, rots = log
    res = detect_static_and_rotations(t, gyro, accel)
    assert len(res.rotations) == len(rots)
    for found, (a, b, truth) in zip(res.rotations, rots, strict=True):
        assert found.start_time_s <= a + 0.01 and found.end_time_s >= b - 0.01
        err = np.linalg.norm(found.angle_rad - truth) / np.linalg.norm(truth)
        assert err < 0.02, (np.rad2deg(found.angle_rad), np.rad2deg(truth))
    assert np.rad2deg(res.rotations[1].angle_norm_rad) == pytest.approx(360.0, rel=0.02)


def test_the_threshold_is_a_multiple_of_the_initial_variance(log):
    t, gyro, accel, _, _ = log
    lo = detect_static_and_rotations(t, gyro, accel, threshold_factor=3.0)
    hi = detect_static_and_rotations(t, gyro, accel, threshold_factor=12.0)
    assert hi.accel_threshold == pytest.approx(4 * lo.accel_threshold)
    assert hi.is_static.sum() >= lo.is_static.sum()


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"threshold_factor": 1.0}, "must be > 1"),
    ({"init_static_s": 100.0}, "initial static interval"),
    ({"window_s": 0.01}, "at least 5 samples"),
])
def test_bad_parameters_are_named(log, kwargs, message):
    t, gyro, accel, _, _ = log
    with pytest.raises(InvalidInputError, match=message):
        detect_static_and_rotations(t, gyro, accel, **kwargs)


def test_a_log_that_does_not_begin_at_rest_is_refused(log):
    t, gyro, accel, _, _ = log
    start = np.searchsorted(t, 3.2)  # inside the first rotation
    with pytest.raises(InvalidInputError, match="are not at rest"):
        detect_static_and_rotations(t[start:], gyro[start:], accel[start:], init_static_s=1.0)


def test_thresholds_share_curves_and_interval_means(log):
    """Each detection of detect_for_thresholds equals its own detect_static_and_rotations."""
    from imucalib.processing.static_detector import detect_for_thresholds

    t, gyro, accel, _, _ = log
    ks = (4.0, 6.0, 9.0)
    together = detect_for_thresholds(t, gyro, accel, threshold_factors=ks)
    for k, got in zip(ks, together, strict=True):
        alone = detect_static_and_rotations(t, gyro, accel, threshold_factor=k)
        assert [(s.start_index, s.stop_index) for s in got.static] == [
            (s.start_index, s.stop_index) for s in alone.static]
        for a, b in zip(got.static, alone.static, strict=True):
            np.testing.assert_array_equal(a.mean_rate_rps, b.mean_rate_rps)
            np.testing.assert_array_equal(a.mean_specific_force_mps2, b.mean_specific_force_mps2)
            np.testing.assert_array_equal(a.mean_rate_rps, gyro[a.start_index:a.stop_index]
                                          .mean(axis=0))
        np.testing.assert_array_equal(got.accel_variance, alone.accel_variance)
        assert not got.accel_variance.flags.writeable
