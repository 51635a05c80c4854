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


# -- closed-form line fits against np.polyfit (the implementation they replaced) ---------------

def _polyfit_time_base(counter: np.ndarray, host: np.ndarray) -> tuple[float, float, np.ndarray,
                                                                       np.ndarray]:
    """The trimmed regression written with np.polyfit / np.polyval, as before the closed form."""
    x = (counter - counter[0]).astype(np.float64)
    y = host - host[0]
    keep = np.ones(x.size, dtype=bool)
    coef = np.polyfit(x, y, 1)
    for _ in range(2):
        resid = y - np.polyval(coef, x)
        med = np.median(resid[keep])
        mad = 1.4826 * float(np.median(np.abs(resid[keep] - med)))
        new_keep = np.abs(resid - med) <= 5.0 * mad if mad > 0 else keep
        if new_keep.sum() < 3 or np.array_equal(new_keep, keep):
            break
        keep = new_keep
        coef = np.polyfit(x[keep], y[keep], 1)
    return float(coef[0]), float(coef[1]), y - np.polyval(coef, x), keep


def _close(a: float, b: float, scale: float = 0.0) -> bool:
    return abs(a - b) <= 1e-12 * max(abs(a), abs(b), scale)


@pytest.mark.parametrize("case", ["three", "gaps", "outlier", "long", "epoch", "exact"])
def test_time_base_line_fit_matches_polyfit(case: str) -> None:
    rng = np.random.default_rng(7)
    if case == "three":
        c = np.array([5, 6, 7])
        host = np.array([1.0, 1.011, 1.019])
    elif case == "exact":  # on the line: no jitter, MAD = 0
        c = np.arange(100)
        host = 3.0 + 0.01 * c
    else:
        n = {"gaps": 5000, "outlier": 2000, "long": 200_000, "epoch": 20_000}[case]
        c = np.cumsum(rng.integers(1, 4 if case == "gaps" else 2, n)) + 1000
        host = 7.0 + c * 1e-3 * (1 + 20e-6) + rng.exponential(2e-4, n)
        if case == "outlier":
            host[n // 2] += 1e3  # a huge hiccup
        if case == "epoch":
            host += 1.7e9
    tb = reconstruct_time_base(c, host, nominal_rate_hz=1000.0)
    slope, icpt, resid, keep = _polyfit_time_base(c, host)
    scale = float(np.abs(host - host[0]).max())  # the size of the fitted values
    assert _close(tb.sample_period_s, slope)
    # the intercept and the residuals are small differences of values of size `scale`: both
    # fits carry rounding errors of order 1e-16·scale there
    assert _close(tb.offset_s, float(host[0] + icpt - slope * c[0]), scale)
    assert tb.n_rejected == int(np.sum(~keep))
    assert _close(tb.max_abs_residual_s, float(np.abs(resid).max()), scale)
    jitter = float(np.sqrt(np.sum(resid[keep] ** 2) / max(int(keep.sum()) - 2, 1)))
    assert _close(tb.jitter_s, jitter, scale * 1e-2)
    np.testing.assert_allclose(tb.time_s, host[0] + icpt + slope * (c - c[0]), rtol=1e-12,
                               atol=1e-12 * scale)
    if case == "outlier":
        assert tb.n_rejected >= 1 and tb.max_abs_residual_s > 900.0
    if case == "exact":
        assert tb.n_rejected == 0 and tb.jitter_s < 1e-12


def test_time_base_accepts_float_and_list_counters_alike() -> None:
    host = 2.0 + np.arange(50) * 0.01 + np.random.default_rng(3).normal(0.0, 1e-4, 50)
    ints = reconstruct_time_base(np.arange(50), host)
    for counter in (np.arange(50.0), list(range(50)), np.arange(50, dtype=np.uint16)):
        other = reconstruct_time_base(counter, host.tolist())
        assert other.sample_period_s == ints.sample_period_s
        np.testing.assert_array_equal(other.time_s, ints.time_s)
        assert other.counter.dtype == np.int64


def test_time_base_rejects_constant_host_time() -> None:
    with pytest.raises(InvalidInputError, match=r"host time must increase with the counter; got "
                                                r"a fitted period of 0 s"):
        reconstruct_time_base([0, 1, 2, 3], [5.0, 5.0, 5.0, 5.0])


def _polyfit_jitter(t: np.ndarray) -> float:
    d = np.diff(t)
    k = np.concatenate([[0.0], np.cumsum(np.maximum(np.round(d / np.median(d)), 1.0))])
    coef = np.polyfit(k, t - t[0], 1)
    resid = (t - t[0]) - np.polyval(coef, k)
    return float(np.sqrt(np.sum(resid**2) / (t.size - 2)))


@pytest.mark.parametrize("case", ["three", "gaps", "outlier", "epoch", "uniform"])
def test_jitter_line_fit_matches_polyfit(case: str) -> None:
    rng = np.random.default_rng(11)
    if case == "three":
        t = np.array([0.0, 0.0101, 0.0199])
    elif case == "uniform":
        t = 4.0 + np.arange(1000) * 0.004
    else:
        k = np.cumsum(rng.integers(1, 3 if case == "gaps" else 2, 30_000))
        t = 1.0 + k * 1e-3 + rng.normal(0.0, 3e-5, k.size)
        if case == "outlier":
            t[k.size // 2:] += 0.5  # one step of 500 samples
        if case == "epoch":
            t = t + 1.7e9
    want = _polyfit_jitter(t)
    got = estimate_timestamp_jitter_s(t)
    scale = float(t[-1] - t[0])
    assert abs(got - want) <= 1e-12 * max(want, 1e-3 * scale)
    if case != "uniform":
        assert got > 0
    # synchronize reuses the validated stamps, their steps and median step: the same value
    res = synchronize(t, np.zeros(t.size), [t[1]], max_alignment_error_s=None)
    assert res.timestamp_jitter_s == got
