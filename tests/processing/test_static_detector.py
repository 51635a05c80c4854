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
G = np.array([0.0, 0.0, 9.80665])


def _rot(axis: np.ndarray, angle: float) -> np.ndarray:
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def hand_log(seed: int = 1):
    """Static 3 s, 90° about x (raised-cosine rate, 2 s), static 3 s, 360° about z (3 s), static
    3 s, −90° about y (1.5 s), static 3 s. Returns t, gyro, accel, the truth (still intervals and
    rotations: (start, end, angle vector))."""
    rng = np.random.default_rng(seed)
    plan = [("still", 3.0), ((0, np.pi / 2), 2.0), ("still", 3.0), ((2, 2 * np.pi), 3.0),
            ("still", 3.0), ((1, -np.pi / 2), 1.5), ("still", 3.0)]
    dt = 1.0 / RATE_HZ
    r_bn = np.eye(3)  # body → navigation
    ts, gs, accs = [], [], []
    still, rots = [], []
    t0 = 0.0
    for what, dur in plan:
        n = round(dur * RATE_HZ)
        t = t0 + np.arange(n) * dt
        if what == "still":
            still.append((t0, t0 + dur))
            w = np.zeros((n, 3))
            f = np.tile(r_bn.T @ G, (n, 1))
        else:
            ax, ang = what
            u = np.eye(3)[ax]
            s = (t - t0) / dur
            rate = ang / dur * (1 - np.cos(2 * np.pi * s))  # raised cosine, integral = ang
            rate += 0.02 * np.sin(2 * np.pi * 7 * (t - t0)) * (np.abs(ang) / dur)  # tremor
            w = rate[:, None] * u
            f = np.empty((n, 3))
            phi = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * dt)])
            for i in range(n):
                f[i] = (r_bn @ _rot(u, phi[i])).T @ G
            total = float(np.sum(0.5 * (rate[1:] + rate[:-1]) * dt)) + rate[-1] * dt
            r_bn = r_bn @ _rot(u, total)
            rots.append((t0, t0 + dur, total * u))
        ts.append(t)
        gs.append(w)
        accs.append(f)
        t0 += dur
    t = np.concatenate(ts)
    gyro = np.concatenate(gs) + np.deg2rad(BIAS_DPS) + rng.normal(0, np.deg2rad(0.1), (t.size, 3))
    accel = np.concatenate(accs) + np.array([0.05, -0.03, 0.08]) + rng.normal(0, 0.02, (t.size, 3))
    return t, gyro, accel, still, rots


@pytest.fixture(scope="module")
def log():
    return hand_log()


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
