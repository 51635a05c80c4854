"""Tests of imucalib.processing.segmentation on table motion from the twin, three IMU grades."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from imucalib import units
from imucalib.errors import InvalidInputError
from imucalib.models.imu import sample_imu_model
from imucalib.models.noise_generator import simulate_noise
from imucalib.processing import SEGMENT_LABELS, detect_segments
from imucalib.sim import RateTableSpec, SimRateTable

D = units.DEG
FS = 200.0


def _scenario(grade: str, seed: int):
    """P1-like sequence on a lab-grade dual-axis table; returns data and the true steady spans."""
    table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("lab"))
    spans = [("static", 0.0, 5.0, 0.0)]
    t1 = table.command_rate("roll", 50 * D, 5.0)
    spans.append(("rotating", t1, 20.0, 50.0))
    t2 = table.command_stop("roll", 20.0)
    spans.append(("static", t2, 30.0, 0.0))
    t3 = table.command_position("pitch", 90 * D, 30.0)
    spans.append(("static", t3, 40.0, 0.0))
    t4 = table.command_rate("roll", -100 * D, 40.0)
    spans.append(("rotating", t4, 55.0, -100.0))
    t5 = table.command_stop("roll", 55.0)
    spans.append(("static", t5, 62.0, 0.0))
    t6 = table.command_rate("roll", 5 * D, 62.0)  # the slowest rate of imucalib's plans
    spans.append(("rotating", t6, 75.0, 5.0))
    imu = sample_imu_model(grade, seed, sample_rate_hz=FS)
    t = np.arange(0.0, 75.0, 1 / FS)
    motion = table.motion(t)
    rng = np.random.default_rng(seed)
    gyro = (motion.omega_tp_p_rps + imu.gyro.bias
            + simulate_noise(imu.gyro_noise, t.size, 1 / FS, rng))
    accel = (motion.rot_tp.inv().apply([0.0, 0.0, units.G0_MPS2]) + imu.accel.bias
             + simulate_noise(imu.accel_noise, t.size, 1 / FS, rng))
    return t, gyro, accel, spans, imu


@pytest.mark.parametrize("grade", ["consumer", "tactical", "navigation"])
@pytest.mark.parametrize("with_accel", [True, False])
def test_twin_sequence_is_segmented_for_every_grade(grade: str, with_accel: bool) -> None:
    t, gyro, accel, spans, imu = _scenario(grade, 11)
    res = detect_segments(t, gyro, accel_mps2=accel if with_accel else None)
    assert [s.kind for s in res.segments] == [k for k, *_ in spans]
    half = res.window_samples / FS / 2
    for seg, (kind, a, b, rate_dps) in zip(res.segments, spans, strict=True):
        # inside the true steady span, losing at most the half window plus 1.2 s of settling
        assert a - 1e-9 <= seg.start_time_s - half + 1e-9 and seg.start_time_s <= a + half + 1.2
        assert b - half - 0.6 <= seg.end_time_s <= b
        expected = np.array([rate_dps * D, 0.0, 0.0]) + imu.gyro.bias
        tol = 0.05 * D if grade == "consumer" else 0.005 * D
        np.testing.assert_allclose(seg.mean_rate_rps, expected, atol=tol)
        labels = res.labels[seg.start_index:seg.stop_index]
        assert np.all(labels == (1 if kind == "static" else 2))
        assert (seg.mean_specific_force_mps2 is not None) == with_accel
    # no labelled sample during a transition
    for (_, _, b, _), (_, a_next, _, _) in itertools.pairwise(spans):
        gap = (t > b) & (t < a_next)
        assert np.all(res.labels[gap] == 0)
    assert len(res.static) == 4 and len(res.rotating) == 3
    assert SEGMENT_LABELS[int(res.labels[len(t) // 2])] in ("static", "rotating", "transition")


def test_accelerometer_disturbance_splits_a_static_segment() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 30.0, 1 / FS)
    gyro = rng.normal(0.0, 0.01 * D, (t.size, 3))
    accel = rng.normal(0.0, 1e-3, (t.size, 3)) + np.array([0.0, 0.0, units.G0_MPS2])
    bump = (t > 14.0) & (t < 15.0)
    accel[bump] += rng.normal(0.0, 0.05, (bump.sum(), 3))  # a knock on the bench
    with_a = detect_segments(t, gyro, accel_mps2=accel)
    without = detect_segments(t, gyro)
    assert len(with_a.segments) == 2 and len(without.segments) == 1
    assert with_a.segments[0].end_time_s < 14.0 and with_a.segments[1].start_time_s > 15.0


def test_short_segments_are_dropped() -> None:
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 20.0, 1 / FS)
    rate = np.where((t > 8.0) & (t < 9.6), 30 * D, 0.0)  # a 1.6 s "rotation" (with steps)
    gyro = rng.normal(0.0, 0.01 * D, (t.size, 3))
    gyro[:, 2] += rate
    res = detect_segments(t, gyro, min_rotating_s=2.0)
    assert [s.kind for s in res.segments] == ["static", "static"]
    res2 = detect_segments(t, gyro, min_rotating_s=0.1)
    assert [s.kind for s in res2.segments] == ["static", "rotating", "static"]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"window_s": 0.01}, r"`window_s` must span at least 5 samples; got 2"),
        ({"gyro_rps": np.zeros((100, 2))},
         r"`gyro_rps` must have shape \(100, 3\); got \(100, 2\)"),
        ({"time_s": np.arange(50) / FS, "gyro_rps": np.zeros((50, 3))},
         r"at least three windows \(600 samples\) long; got 50"),
        ({"threshold_factor": 1.0}, r"`threshold_factor` must be > 1; got 1.0"),
        ({"accel_mps2": np.zeros((99, 3))}, r"`accel_mps2` must have shape \(100, 3\)"),
        ({"min_static_s": 0.0}, r"`min_static_s` must be > 0"),
    ],
)
def test_bad_inputs_raise_with_messages(kwargs: dict, match: str) -> None:
    args = {"time_s": np.arange(100) / FS, "gyro_rps": np.zeros((100, 3))}
    args.update(kwargs)
    t, g = args.pop("time_s"), args.pop("gyro_rps")
    with pytest.raises(InvalidInputError, match=match):
        detect_segments(t, g, **args)
