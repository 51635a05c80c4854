"""Tests of imucalib.processing.statistics: standard error under correlated noise (Monte Carlo
against Eq. (1): the scatter of adjacent window means), and integer-revolution windows."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from imucalib import units
from imucalib.errors import InvalidInputError
from imucalib.models.noise import NoiseModel, compute_theoretical_adev
from imucalib.models.noise_generator import simulate_noise
from imucalib.processing import compute_integer_revolution_window, compute_window_statistics


def _chi2_bounds(dof: int, widen: float = 0.0) -> tuple[float, float]:
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], dof) / dof
    return lo * (1 - widen), hi * (1 + widen)


def test_white_noise_model_se_is_n_over_root_t_and_matches_monte_carlo() -> None:
    fs, n, runs = 100.0, 1000, 300
    model = NoiseModel(white_density=0.1)
    x = simulate_noise(model, n * runs, 1 / fs, np.random.default_rng(0)).reshape(runs, n, 3)
    st = compute_window_statistics(x[0], fs, noise_model=model)
    assert st.se_method == "noise-model"
    np.testing.assert_allclose(st.standard_error, 0.1 / np.sqrt(10.0), rtol=1e-12)
    means = x.mean(axis=1).ravel()
    ratio = means.var(ddof=1) / st.standard_error[0] ** 2
    lo, hi = _chi2_bounds(means.size - 1)
    assert lo < ratio < hi
    # with white noise the white formula agrees
    np.testing.assert_allclose(st.standard_error_white, st.standard_error, rtol=0.1)
    np.testing.assert_allclose(st.n_effective, n, rtol=0.2)


@pytest.mark.slow
def test_white_flicker_random_walk_se_matches_adjacent_window_scatter() -> None:
    # equal thirds of white, flicker and random walk in σ²_A(T) at T = 20 s
    fs, n, runs = 100.0, 2000, 300
    model = NoiseModel(white_density=1.0, bias_instability=0.34, random_walk=0.087)
    rng = np.random.default_rng(1)
    diffs = []
    for _ in range(runs):
        x = simulate_noise(model, 2 * n, 1 / fs, rng)
        diffs.append((x[n:].mean(axis=0) - x[:n].mean(axis=0)) / np.sqrt(2.0))
    d = np.concatenate(diffs)
    st = compute_window_statistics(x[:n], fs, noise_model=model)
    want = compute_theoretical_adev(model, [n / fs])[0]
    np.testing.assert_allclose(st.standard_error, want, rtol=1e-12)
    ratio = np.mean(d**2) / st.standard_error[0] ** 2  # E[d²] = σ²_A(T): Eq. (1)
    lo, hi = _chi2_bounds(d.size, widen=0.03)  # the generator's flicker is within ±1.5 % in ADEV
    assert lo < ratio < hi, ratio
    # the white formula misses the correlated part by a factor of about √3
    assert st.standard_error[0] > 1.5 * model.white_density[0] / np.sqrt(n / fs)


def test_random_walk_from_window_start_spread_of_the_mean() -> None:
    # a walk started at the window's start: var(mean) = N²/T + K²T/3 = σ²_A(T)
    fs, n, runs = 50.0, 1000, 400
    model = NoiseModel(white_density=0.05, random_walk=0.02)
    rng = np.random.default_rng(2)
    means = np.concatenate([simulate_noise(model, n, 1 / fs, rng).mean(axis=0)
                            for _ in range(runs)])
    st = compute_window_statistics(np.zeros((n, 3)), fs, noise_model=model)
    T = n / fs
    np.testing.assert_allclose(st.standard_error**2, 0.05**2 / T + 0.02**2 * T / 3, rtol=1e-9)
    ratio = np.mean(means**2) / st.standard_error[0] ** 2
    lo, hi = _chi2_bounds(means.size, widen=0.02)
    assert lo < ratio < hi, ratio


@pytest.mark.slow
def test_allan_fit_captures_correlated_noise_of_long_gyro_records() -> None:
    # a consumer MEMS gyro (0.3 °/√h, 8 °/h, 30 °/h/√h) over 30 min at 10 Hz: flicker and random
    # walk dominate σ²_A(T) over several octaves, and s/√n is far too small
    model = NoiseModel(white_density=0.3 * units.DEG_PER_RTH,
                       bias_instability=8.0 * units.DEG_PER_H,
                       random_walk=30.0 * units.DEG_PER_H_RTH)
    fs, n, runs = 10.0, 18_000, 60
    rng = np.random.default_rng(3)
    se2, white2, d2 = [], [], []
    for _ in range(runs):
        x = simulate_noise(model, 2 * n, 1 / fs, rng)
        st = compute_window_statistics(x[:n], fs)
        assert st.se_method == "allan-fit"
        se2.append(st.standard_error**2)
        white2.append(st.standard_error_white**2)
        d2.append((x[n:].mean(axis=0) - x[:n].mean(axis=0)) ** 2 / 2.0)
    se2_mean, d2_mean = np.mean(se2), np.mean(d2)
    assert 0.7 < se2_mean / d2_mean < 1.4, se2_mean / d2_mean
    assert np.sqrt(se2_mean / np.mean(white2)) > 10.0
    assert st.random_walk[0] == pytest.approx(model.random_walk[0], rel=0.8)


def test_allan_fit_on_white_noise_stays_near_the_white_formula() -> None:
    rng = np.random.default_rng(4)
    ratios = []
    for _ in range(40):
        st = compute_window_statistics(rng.normal(0.0, 1.0, (2000, 3)), 100.0)
        assert np.all(st.standard_error >= st.standard_error_white)
        ratios.append(st.standard_error / st.standard_error_white)
        np.testing.assert_allclose(st.white_density, 0.1, rtol=0.2)
    assert 0.99 <= np.median(ratios) < 1.5  # SE, not SE²: docs table median SE² 1.47


def test_short_window_falls_back_to_white_and_basic_statistics() -> None:
    x = np.array([[1.0, 2.0], [3.0, 2.0], [2.0, 2.0], [6.0, 2.0], [3.0, 2.0]])
    st = compute_window_statistics(x, 10.0)
    assert st.se_method == "white" and st.n_samples == 5
    assert st.duration_s == pytest.approx(0.5)
    np.testing.assert_allclose(st.mean, [3.0, 2.0])
    np.testing.assert_allclose(st.std, [np.std(x[:, 0], ddof=1), 0.0])
    np.testing.assert_allclose(st.standard_error, st.std / np.sqrt(5))
    assert np.isnan(st.white_density).all()
    explicit = compute_window_statistics(x, 10.0, se_method="white")
    np.testing.assert_allclose(explicit.standard_error, st.standard_error)


# --- integer revolutions -------------------------------------------------------------------------
def _rotating_step(rate_dps: float, duration_s: float, fs: float, ripple: float = 0.0):
    t = np.arange(0.0, duration_s, 1 / fs)
    w = rate_dps * units.DEG
    theta = 0.3 + w * t + ripple / (2 * np.pi * 1.3) * w * np.sin(2 * np.pi * 1.3 * t)
    return t, theta


@pytest.mark.parametrize("rate_dps", [100.0, -37.0, 360.0])
def test_integer_revolutions_cancel_once_per_revolution_terms(rate_dps: float) -> None:
    fs = 200.0
    t, theta = _rotating_step(rate_dps, 23.7, fs)
    y = np.column_stack([5.0 + 0.8 * np.cos(theta) - 0.4 * np.sin(2 * theta),
                         -1.0 + 2.0 * np.sin(theta + 0.7)])
    w = compute_integer_revolution_window(t, y, angle_rad=np.mod(theta, 2 * np.pi))
    n_rev = int(abs(rate_dps) * 23.7 / 360.0)
    assert w.n_revolutions == n_rev
    step = abs(rate_dps) * units.DEG / fs
    assert abs(w.angle_error_rad) <= 0.5 * step + 1e-9
    assert abs(w.covered_angle_rad - 2 * np.pi * n_rev) == pytest.approx(abs(w.angle_error_rad))
    # a sinusoid of amplitude A leaves at most A·|δ|/covered for a coverage error δ (0 when the
    # sample step divides 360°, as at 100 °/s and 360 °/s here)
    bound = np.array([1.2, 2.0]) * abs(w.angle_error_rad) / w.covered_angle_rad
    assert np.all(np.abs(w.mean - [5.0, -1.0]) <= 1.01 * bound + 1e-9)
    if rate_dps in (100.0, 360.0):
        np.testing.assert_allclose(w.mean, [5.0, -1.0], atol=1e-9)
    assert w.n_samples == w.stop_index - w.start_index
    # the plain mean over the whole step does not cancel them
    assert np.max(np.abs(y.mean(axis=0) - [5.0, -1.0])) > 1e-3


def test_angle_weighting_is_exact_under_rate_ripple_and_rate_input_agrees() -> None:
    fs = 100.0
    t, theta = _rotating_step(60.0, 20.0, fs, ripple=0.05)  # 5 % rate ripple
    y = 2.0 + np.cos(theta)
    by_angle = compute_integer_revolution_window(t, y, angle_rad=theta)
    by_time = compute_integer_revolution_window(t, y, angle_rad=theta, weighting="time")
    assert abs(by_angle.mean[0] - 2.0) < 2e-3
    assert abs(by_time.mean[0] - 2.0) > abs(by_angle.mean[0] - 2.0)
    rate = np.gradient(theta, t)
    by_rate = compute_integer_revolution_window(t, y, rate_rps=rate)
    assert by_rate.n_revolutions == by_angle.n_revolutions
    assert abs(by_rate.start_index - by_angle.start_index) <= 2


def test_window_is_central_when_there_is_slack() -> None:
    fs = 100.0
    t = np.arange(0.0, 15.0, 1 / fs)
    theta = np.deg2rad(36.0) * t  # exactly 10 s per revolution: 1 revolution, 5 s of slack
    w = compute_integer_revolution_window(t, np.ones(t.size), angle_rad=theta)
    assert w.n_revolutions == 1 and w.n_samples == 1000
    assert abs((w.start_index + w.stop_index) / 2 - t.size / 2) <= 1
    assert w.end_time_s - w.start_time_s == pytest.approx(10.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"angle_rad": None}, r"give exactly one of `angle_rad` and `rate_rps`; got neither"),
        ({"rate_rps": np.ones(500)}, r"give exactly one .*; got both"),
        ({"angle_rad": np.linspace(0, 6.0, 500)}, r"at least one revolution; got 344\.46"),
        ({"angle_rad": np.r_[np.linspace(0, 10, 250), np.linspace(10, 20, 250)]},
         r"must change monotonically .*; got 1 sample step\(s\) against it"),
        ({"angle_rad": np.linspace(0, 20, 499)}, r"`angle_rad` must have shape \(500,\)"),
        ({"weighting": "count"}, r"`weighting` must be 'angle' or 'time'; got 'count'"),
    ],
)
def test_revolution_bad_inputs(kwargs: dict, match: str) -> None:
    args = {"angle_rad": np.linspace(0.0, 20.0, 500)}
    args.update(kwargs)
    with pytest.raises(InvalidInputError, match=match):
        compute_integer_revolution_window(np.arange(500) / 50.0, np.ones(500), **args)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: compute_window_statistics([1.0], 10.0), r"at least 2 samples"),
        (lambda: compute_window_statistics(np.ones((10, 2)), 10.0,
                                           noise_model=NoiseModel(white_density=1.0)),
         r"`values` must have 3 columns \(the axes of `noise_model`\); got 2"),
        (lambda: compute_window_statistics(np.ones(10), 10.0, se_method="noise-model"),
         r"'noise-model' needs a `noise_model`; got None"),
        (lambda: compute_window_statistics(np.ones(10), 10.0, se_method="batch"),
         r"`se_method` must be 'noise-model', 'allan-fit' or 'white'; got 'batch'"),
        (lambda: compute_window_statistics(np.ones(10), 10.0, min_cluster_samples=0),
         r"`min_cluster_samples` must be an integer ≥ 1; got 0"),
        (lambda: compute_window_statistics(np.ones(10), 0.0), r"`sample_rate_hz` must be > 0"),
    ],
)
def test_statistics_bad_inputs(call, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        call()


# -- the batched Allan path against a straightforward reference ---------------------------------

def _reference_oavar(x: np.ndarray, fs: float, ms: np.ndarray) -> np.ndarray:
    """Overlapping Allan variance per column from the cumulative sum (NIST SP 1065 Eq. (8))."""
    out = np.empty((ms.size, x.shape[1]))
    for j in range(x.shape[1]):
        y = x[:, j] - x[:, j].mean()
        phase = np.concatenate([[0.0], np.cumsum(y)]) / fs
        for t, m in enumerate(ms):
            d = phase[2 * m:] - 2 * phase[m:-m] + phase[: -2 * m]
            out[t, j] = np.sum(d**2) / (2 * d.size * (m / fs) ** 2)
    return out


@pytest.mark.parametrize(("n", "k"), [(7, 1), (6000, 6), (70_001, 3)])
def test_batched_overlapping_avar_matches_a_column_by_column_reference(n: int, k: int) -> None:
    from imucalib.analysis._allan_engine import ArrayPhase, n_terms, sum_overlapping
    from imucalib.analysis.allan import phase_from_rate
    from imucalib.processing.statistics import _overlapping_avar

    fs = 200.0
    rng = np.random.default_rng(n)
    x = rng.normal(size=(n, k)) + np.cumsum(rng.normal(size=(n, k)), axis=0) * 1e-2
    x[:, -1] = 3.0  # a constant column: no variance at all
    ms = 2 ** np.arange(0, int(np.log2(n // 2)) + 1)
    got = _overlapping_avar(x - x.mean(axis=0), 1.0 / fs, ms)
    want = _reference_oavar(x, fs, ms)
    scale = np.max(want, axis=0)
    assert np.all(np.abs(got - want) <= 1e-9 * np.maximum(want, 1e-12 * scale) + 1e-300)
    assert np.all(got[:, -1] == 0.0)
    # and bit for bit the one-column-at-a-time path of the analysis package
    count = n_terms("oadev", ms, n + 1)
    for j in range(k):
        col = np.ascontiguousarray((x - x.mean(axis=0))[:, j])
        one = sum_overlapping(ArrayPhase(phase_from_rate(col, fs)), ms, count, 2) / (
            2.0 * count * (ms / fs) ** 2)
        np.testing.assert_array_equal(got[:, j], one)


def test_window_statistics_mean_std_are_numpys_and_fit_is_stable() -> None:
    rng = np.random.default_rng(9)
    x = rng.normal(size=(6000, 4)) * [1.0, 1e-3, 5.0, 0.0] + [0.0, 9.81, -3.0, 7.0]
    st = compute_window_statistics(x, 100.0)
    np.testing.assert_array_equal(st.mean, x.mean(axis=0))
    np.testing.assert_array_equal(st.std, x.std(axis=0, ddof=1))
    assert st.std[3] == 0.0 and st.standard_error[3] == 0.0
    assert st.n_effective[3] == 6000.0
    one = compute_window_statistics(x[:, 0], 100.0)  # a column alone: the same numbers
    # (numpy sums a lone column pairwise, columns of a 2-D array row by row: rounding apart)
    assert one.standard_error[0] == pytest.approx(st.standard_error[0], rel=1e-12)
    assert one.white_density[0] == pytest.approx(st.white_density[0], rel=1e-12)
