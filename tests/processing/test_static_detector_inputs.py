"""The static detector reads C-ordered float64 inputs in place (no copies) and checks them as
before: other layouts and dtypes give the same detection bit for bit, bad inputs the same
errors; and the field calibration's interval noise (two triads' block variances with one
``np.var``) equals ``block_variance`` of the six columns (docs/performance.md, "Field
calibration: the fits' fixed costs")."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.processing.static_detector import detect_static_and_rotations


def _same(a, b) -> None:
    assert [(s.start_index, s.stop_index) for s in a.static] == [
        (s.start_index, s.stop_index) for s in b.static]
    assert a.static, "the log has static intervals"
    for x, y in zip(a.static, b.static, strict=True):
        assert x.mean_rate_rps.tobytes() == y.mean_rate_rps.tobytes()
        assert x.mean_specific_force_mps2.tobytes() == y.mean_specific_force_mps2.tobytes()
    for x, y in zip(a.rotations, b.rotations, strict=True):
        assert x.angle_rad.tobytes() == y.angle_rad.tobytes()
    assert a.accel_variance.tobytes() == b.accel_variance.tobytes()
    assert a.gyro_variance.tobytes() == b.gyro_variance.tobytes()
    assert a.is_static.tobytes() == b.is_static.tobytes()


def test_other_layouts_give_the_same_detection_and_inputs_are_left_alone(hand_held_log):
    t, gyro, accel, _, _ = hand_held_log
    kept = [a.copy() for a in (t, gyro, accel)]
    ref = detect_static_and_rotations(t, gyro, accel)
    for a, k in zip((t, gyro, accel), kept, strict=True):
        assert a.tobytes() == k.tobytes()
    # lists and a strided time vector: copied (C order) and checked as before
    _same(detect_static_and_rotations(t.tolist(), gyro.tolist(), accel.tolist()), ref)
    wide = np.repeat(t, 2)[::2]
    _same(detect_static_and_rotations(wide, gyro, accel), ref)
    ro = [a.copy() for a in (t, gyro, accel)]
    for a in ro:
        a.setflags(write=False)
    _same(detect_static_and_rotations(*ro), ref)


@pytest.mark.parametrize("bad", ["nan_time", "inf_accel", "nan_gyro", "repeat_time", "shape"])
def test_bad_inputs_are_named_as_before(hand_held_log, bad):
    t, gyro, accel, _, _ = hand_held_log
    t, gyro, accel = t.copy(), gyro.copy(), accel.copy()
    message = {"nan_time": "`time_s` must be finite", "inf_accel": "`accel_mps2` must be finite",
               "nan_gyro": "`gyro_rps` must be finite", "repeat_time": "strictly increasing",
               "shape": "`accel_mps2` must have shape"}[bad]
    if bad == "nan_time":
        t[100] = np.nan
    elif bad == "inf_accel":
        accel[50, 1] = np.inf
    elif bad == "nan_gyro":
        gyro[7, 2] = np.nan
    elif bad == "repeat_time":
        t[10] = t[9]
    else:
        accel = accel[:-1]
    with pytest.raises(InvalidInputError, match=message):
        detect_static_and_rotations(t, gyro, accel)


def test_huge_finite_values_whose_sum_overflows_are_not_called_infinite(hand_held_log):
    import warnings

    from imucalib.processing.static_detector import _checked_samples

    _, _, accel, _, _ = hand_held_log
    big = accel.copy()
    big[:2, 0] = 1e308  # the sum overflows; every value is finite: checked element by element
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # and no overflow warning escapes the check
        assert _checked_samples(big, "accel_mps2", big.shape[0]) is big
        big[5, 2] = np.nan
        with pytest.raises(InvalidInputError, match="1 NaN or infinite"):
            _checked_samples(big, "accel_mps2", big.shape[0])


def test_the_interval_block_variance_pair_equals_the_six_columns_block_variance() -> None:
    from imucalib.procedures.common.noise import block_variance
    from imucalib.procedures.common.static_intervals import _block_variance_pair

    rng = np.random.default_rng(4)
    x = rng.normal(size=(10_007, 6)) * [1e-3, 2e-3, 5e-3, 1e-4, 3e-4, 2e-4] + [0, 0, 9.8, 0, 0, 0]
    for rows in (10_007, 800, 250, 80):   # 80 rows: fewer than three blocks, NaN
        a, g = x[:rows, :3].copy(), x[:rows, 3:].copy()
        dof, var = _block_variance_pair(a, g, 0.001, 0.05)
        want_dof, want = block_variance(x[:rows].copy(), 0.001, 0.05)
        assert dof == want_dof
        assert np.asarray(var).tobytes() == np.asarray(want).tobytes()
    # against the white-noise density it estimates: N² = σ²·Δt for white samples
    dof, var = _block_variance_pair(x[:, :3].copy(), x[:, 3:].copy(), 0.001, 0.05)
    expected = (np.array([1e-3, 2e-3, 5e-3, 1e-4, 3e-4, 2e-4]) ** 2) * 0.001
    np.testing.assert_allclose(var, expected, rtol=4 / np.sqrt(dof))
