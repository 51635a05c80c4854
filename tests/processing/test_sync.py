"""Tests of imucalib.processing.sync: interpolation, alignment-error bound, clock reconstruction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib.errors import InvalidInputError, LimitExceededError
from imucalib.processing import estimate_timestamp_jitter_s, reconstruct_time_base, synchronize


def test_linear_signal_is_reproduced_exactly_on_both_columns() -> None:
    t_src = np.arange(0.0, 5.0, 0.002)
    x = np.column_stack([3.0 * t_src + 1.0, -2.0 * t_src])
    t_tgt = np.sort(np.random.default_rng(0).uniform(0.0, t_src[-1], 300))
    res = synchronize(t_src, x, t_tgt)
    np.testing.assert_allclose(res.values, np.column_stack([3 * t_tgt + 1, -2 * t_tgt]),
                               rtol=0, atol=1e-12)
    assert res.values.shape == (300, 2)
    assert np.all(res.nearest_sample_distance_s <= 0.001 + 1e-12)
    assert res.n_targets_in_gaps == 0


def test_interpolation_error_stays_within_the_bernstein_bound() -> None:
    # a sinusoid at f = f_max: value error ≤ e_interp · max|x'|, Eq. (2)
    fs, f = 200.0, 10.0
    t_src = np.arange(0.0, 2.0, 1 / fs)
    t_tgt = np.linspace(0.01, 1.99, 5000)
    res = synchronize(t_src, np.sin(2 * np.pi * f * t_src), t_tgt, signal_bandwidth_hz=f)
    err = np.abs(res.values - np.sin(2 * np.pi * f * t_tgt))
    slope_max = 2 * np.pi * f
    assert res.interpolation_error_s == pytest.approx(math.pi * f / 4 / fs**2)
    assert err.max() <= res.interpolation_error_s * slope_max
    assert err.max() > 0.5 * res.interpolation_error_s * slope_max  # and it is nearly reached


def test_default_bound_and_the_one_millisecond_check() -> None:
    tgt = np.arange(0.5, 9.5, 0.01)
    # 1 kHz IMU, default f_max = Nyquist: e = π·h/8 = 0.393 ms
    t1k = np.arange(0.0, 10.0, 1e-3)
    res = synchronize(t1k, np.zeros(t1k.size), tgt + 3e-4)
    assert res.alignment_error_s == pytest.approx(math.pi * 1e-3 / 8, rel=1e-6)
    assert res.signal_bandwidth_hz == pytest.approx(500.0)
    # 100 Hz IMU: 3.9 ms by default, refused; filtered at 10 Hz: 0.79 ms, accepted
    t100 = np.arange(0.0, 10.0, 1e-2)
    with pytest.raises(LimitExceededError,
                       match=r"the alignment error must be ≤ `max_alignment_error_s` = 1 ms; got "
                             r"3\.927 ms = offset uncertainty 0 ms \+ interpolation bound "
                             r"3\.927 ms \(f_max 50 Hz, longest source interval 10 ms\)"):
        synchronize(t100, np.zeros(t100.size), tgt + 3e-3)
    ok = synchronize(t100, np.zeros(t100.size), tgt + 3e-3, signal_bandwidth_hz=10.0)
    assert ok.alignment_error_s == pytest.approx(math.pi * 10.0 * 1e-4 / 4, rel=1e-6)
    # an offset uncertainty adds linearly; None disables the check
    with pytest.raises(LimitExceededError, match=r"offset uncertainty 0\.5 ms"):
        synchronize(t100, np.zeros(t100.size), tgt, signal_bandwidth_hz=10.0,
                    offset_uncertainty_s=5e-4)
    loose = synchronize(t100, np.zeros(t100.size), tgt, max_alignment_error_s=None)
    assert loose.alignment_error_s > 1e-3


def test_targets_on_samples_need_no_interpolation() -> None:
    t = np.arange(0.0, 1.0, 0.01)
    res = synchronize(t, t**2, t[10:20], max_alignment_error_s=1e-9)
    assert res.interpolation_error_s == 0.0 and res.max_source_interval_s == 0.0
    np.testing.assert_array_equal(res.values, t[10:20] ** 2)


def test_jitter_is_estimated_despite_lost_samples() -> None:
    rng = np.random.default_rng(1)
    k = np.arange(20_000)
    keep = rng.random(k.size) > 0.01  # 1 % lost
    t = 2.0 + k[keep] * 1e-3 * (1 + 50e-6) + rng.normal(0.0, 5e-5, keep.sum())
    jit = estimate_timestamp_jitter_s(t)
    assert jit == pytest.approx(5e-5, rel=0.05)
    tgt = np.linspace(3.0, 20.0, 100)
    # a target in a gap (2 ms interval) breaks 1 ms at the default f_max = Nyquist …
    with pytest.raises(LimitExceededError, match=r"longest source interval 1\.9[0-9]* ms"):
        synchronize(t, np.zeros(t.size), tgt)
    # … but not for a signal band-limited to 100 Hz
    res = synchronize(t, np.zeros(t.size), tgt, signal_bandwidth_hz=100.0)
    assert res.timestamp_jitter_s == pytest.approx(jit)
    assert res.alignment_error_s == pytest.approx(res.interpolation_error_s + 3 * jit)
    assert res.n_targets_in_gaps > 0
    none = synchronize(t, np.zeros(t.size), tgt, signal_bandwidth_hz=100.0, estimate_jitter=False)
    assert none.timestamp_jitter_s == 0.0


def test_source_offset_shifts_the_source_clock() -> None:
    t = np.arange(0.0, 2.0, 1e-3)
    latency = 0.0123
    # the source stamps are late by the latency: x was x(t_true) with t_stamp = t_true + latency
    res = synchronize(t + latency, np.sin(t), [0.5, 1.0, 1.5], source_offset_s=-latency)
    np.testing.assert_allclose(res.values, np.sin([0.5, 1.0, 1.5]), atol=1e-7)


def _device_stream(rng: np.random.Generator, n: int, fs: float, drift_ppm: float,
                   drop: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The twin's timing model (imucalib.sim.synth): true time, counter, receive time."""
    k = np.arange(n)
    t_true = 10.0 + k / (fs * (1 + drift_ppm * 1e-6))
    host = t_true + 2e-3 + rng.exponential(3e-4, n)
    host[n // 3] += 0.05  # an OS hiccup
    host = np.maximum.accumulate(host)  # stamped by a host reading a stream
    keep = rng.random(n) > drop
    keep[[0, -1]] = True
    return t_true[keep], k[keep], host[keep], keep


def test_reconstruct_time_base_recovers_rate_gaps_and_removes_jitter() -> None:
    rng = np.random.default_rng(2)
    fs = 1000.0
    t_true, k, host, keep = _device_stream(rng, 200_000, fs, 30.0, 0.002)
    tb = reconstruct_time_base(k % 65536, host, nominal_rate_hz=fs, counter_modulus=65536)
    assert tb.clock_rate_error == pytest.approx(30e-6, abs=0.3e-6)
    assert tb.sample_rate_hz == pytest.approx(fs * (1 + 30e-6), rel=3e-7)
    assert tb.n_missing == int(np.sum(~keep))
    np.testing.assert_array_equal(tb.counter, k)
    assert tb.gap_indices.size == int(np.sum(np.diff(k) > 1))
    err = tb.time_s - t_true
    # what remains is the (constant) latency, which regression cannot remove
    assert err.std() < 2e-6
    assert 2e-3 <= err.mean() <= 2.4e-3
    assert tb.n_rejected >= 1 and tb.max_abs_residual_s > 0.04
    assert 1e-4 < tb.jitter_s < 4e-4
    # the reconstructed time base has no jitter left
    assert estimate_timestamp_jitter_s(tb.time_s) < 1e-9


def test_reconstruct_without_nominal_rate_gives_nan_error() -> None:
    tb = reconstruct_time_base([0, 1, 2, 3, 5], [0.0, 0.01, 0.02, 0.03, 0.05])
    assert math.isnan(tb.clock_rate_error)
    assert tb.sample_period_s == pytest.approx(0.01)
    assert tb.gap_indices.tolist() == [4] and tb.n_missing == 1


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: synchronize([0.0, 1.0, 1.0], [1, 2, 3], [0.5]),
         r"`source_time_s` must be strictly increasing; got source_time_s\[2\] = 1.0"),
        (lambda: synchronize([0.0, 1.0, 2.0], [1, 2], [0.5]),
         r"`source_values` must have 3 rows \(one per source time\); got 2"),
        (lambda: synchronize([0.0, 1.0, 2.0], [1, 2, 3], [0.5, 2.5], max_alignment_error_s=None),
         r"`target_time_s` must lie within the source span \[0, 2\] s .*got 1 time\(s\) outside"),
        (lambda: synchronize([0.0, 1.0, 2.0], [1, 2, 3], [1.5, 0.5]),
         r"`target_time_s` must be non-decreasing"),
        (lambda: synchronize([0.0, 1.0, 2.0], [1, np.nan, 3], [0.5]),
         r"`source_values` must be finite"),
        (lambda: synchronize([0.0, 1.0, 2.0], [1, 2, 3], [0.5], offset_uncertainty_s=-1.0),
         r"`offset_uncertainty_s` must be ≥ 0; got -1.0"),
        (lambda: reconstruct_time_base([0, 1, 1, 2], [0.0, 0.1, 0.2, 0.3]),
         r"`counter` must increase at every sample .*got counter\[2\] = 1 after counter\[1\] = 1"),
        (lambda: reconstruct_time_base([0, 1.5, 2], [0.0, 0.1, 0.2]),
         r"`counter` must hold integers"),
        (lambda: reconstruct_time_base([0, 1, 2], [0.0, 0.1]),
         r"`host_time_s` must have shape \(3,\) \(one per counter value\); got \(2,\)"),
        (lambda: reconstruct_time_base([0, 1], [0.0, 0.1]),
         r"`counter` must have shape \(n,\) with n ≥ 3; got \(2,\)"),
        (lambda: estimate_timestamp_jitter_s([0.0, 1.0]), r"at least 3 stamps; got 2"),
    ],
)
def test_bad_inputs_raise_with_messages(call, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        call()
