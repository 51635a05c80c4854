"""The window statistics' fast paths equal their straightforward references bit for bit.

docs/performance.md, "P2 and Allan: the fourth pass": the Allan fit of a short window forms
its phase for all columns at once and calls scipy's NNLS core directly, the revolution window
is chosen by two minima instead of a sort, ``unwrap_angle`` skips np.unwrap's corrections of
a continuous angle, and ``reconstruct_time_base`` takes a gap-free counter as it is. Each is
checked here against the code it replaced (the references below), on random and on edge cases.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize

from imucalib.analysis._allan_engine import ArrayPhase, n_terms, sum_overlapping
from imucalib.analysis.allan import phase_from_rate
from imucalib.errors import InvalidInputError
from imucalib.processing import statistics as stats
from imucalib.processing.statistics import (
    compute_integer_revolution_window,
    compute_window_statistics,
    unwrap_angle,
    window_noise_fit,
)
from imucalib.processing.sync import reconstruct_time_base

# --------------------------------------------------------------------------- references


def _reference_fit(x: np.ndarray, dt: float, ms: np.ndarray) -> np.ndarray:
    """The Allan fit (2) column by column: the engine's phase and sums, scipy's nnls."""
    n, k = x.shape
    count = n_terms("oadev", ms, n + 1)
    tau = ms * dt
    basis = np.column_stack([1.0 / tau, np.ones_like(tau), tau])
    rel_sd = np.sqrt(2.0 / stats._edf_white(n, ms))
    out = np.zeros((k, 3))
    for j in range(k):
        col = np.ascontiguousarray(x[:, j])
        a = sum_overlapping(ArrayPhase(phase_from_rate(col, 1.0 / dt)), ms, count, 2) / (
            2.0 * count * tau**2)
        if not np.any(a > 0):
            continue
        model = np.maximum(a, 1e-300)
        for _ in range(2):
            sd = model * rel_sd
            coef, _ = optimize.nnls(basis / sd[:, None], a / sd)
            fitted = basis @ coef
            model = np.where(fitted > 0, fitted, model)
        out[j] = coef
    return out


def _reference_span(t: np.ndarray, theta: np.ndarray) -> tuple[int, int, int]:
    """The revolution window's (a, b, n) by the lexicographic sort it was chosen by before."""
    step = np.diff(theta)
    sign = 1.0 if step.sum() >= 0 else -1.0
    th = sign * theta
    bound = np.concatenate([th, [th[-1] + (th[-1] - th[-2])]])
    median_step = float(np.median(step * sign))
    n_rev = int(np.floor((bound[-1] - bound[0] + 0.5 * median_step) / (2.0 * np.pi) + 1e-12))
    target = bound[:-1] + 2.0 * np.pi * n_rev
    stop = np.searchsorted(bound, target)
    cand_a = np.arange(t.size)
    best_err = np.full(t.size, np.inf)
    best_stop = np.zeros(t.size, dtype=np.int64)
    for s in (stop - 1, stop):
        ok = (s > cand_a) & (s < bound.size)
        err = np.full(t.size, np.inf)
        err[ok] = np.abs(bound[s[ok]] - target[ok])
        better = err < best_err
        best_err[better], best_stop[better] = err[better], s[better]
    finite = np.isfinite(best_err)
    score = np.round(best_err / max(median_step, 1e-300), 9)
    center_off = np.abs((cand_a + best_stop) / 2.0 - t.size / 2.0)
    order = np.lexsort((center_off, score))
    a = int(next(i for i in order if finite[i]))
    return a, int(best_stop[a]), n_rev


# --------------------------------------------------------------------------- the Allan fit


@pytest.mark.parametrize(("n", "k"), [(8, 1), (600, 6), (1000, 6), (3999, 3), (4000, 2),
                                      (4001, 2), (9000, 3)])
def test_window_fit_equals_the_column_by_column_reference(n: int, k: int) -> None:
    rng = np.random.default_rng(n + k)
    x = rng.normal(size=(n, k)) * rng.uniform(1e-4, 10.0, k) \
        + np.cumsum(rng.normal(size=(n, k)), axis=0) * rng.uniform(0.0, 1e-2, k)
    if k > 1:
        x[:, 0] = 2.5  # a constant column: no variance, no fit
    fs = 100.0
    ms = stats._OCTAVES[stats._OCTAVES <= n // 2]
    dev = x - x.mean(axis=0)
    np.testing.assert_array_equal(stats._fit_allan(dev, 1.0 / fs, ms),
                                  _reference_fit(dev, 1.0 / fs, ms))
    full = compute_window_statistics(x, fs)
    mean, fit = window_noise_fit(x, fs)
    np.testing.assert_array_equal(mean, full.mean)
    np.testing.assert_array_equal(
        fit, np.vstack([full.white_density, full.flicker_variance, full.random_walk]))


def test_window_noise_fit_of_a_short_window_and_bad_inputs() -> None:
    mean, fit = window_noise_fit(np.arange(10.0).reshape(5, 2), 10.0)  # 2 cluster sizes
    np.testing.assert_array_equal(mean, [4.0, 5.0])
    assert fit.shape == (3, 2) and np.all(np.isnan(fit))
    with pytest.raises(InvalidInputError, match="min_cluster_samples"):
        window_noise_fit(np.ones(10), 10.0, min_cluster_samples=0)
    with pytest.raises(InvalidInputError, match="finite"):
        window_noise_fit([1.0, np.nan, 2.0], 10.0)


def test_the_nnls_core_is_scipys() -> None:
    rng = np.random.default_rng(3)
    for _ in range(200):
        a = rng.normal(size=(9, 3))
        b = rng.normal(size=9)
        np.testing.assert_array_equal(stats._nnls(a, b), optimize.nnls(a, b)[0])


# --------------------------------------------------------------------------- revolutions


def _turns(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    n = int(rng.integers(3, 900))
    t = np.cumsum(rng.uniform(0.5, 1.5, n)) / 100.0
    rate = rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 60.0)
    theta = rate * t + rng.normal(0.0, rng.choice([0.0, 1e-4, 1e-2]), n) \
        + rng.uniform(-10.0, 10.0)
    if rng.random() < 0.3:
        theta = np.round(theta / 0.01) * 0.01  # quantised: equal errors, ties
    return t, theta


def test_revolution_window_equals_the_sorted_choice() -> None:
    rng = np.random.default_rng(11)
    checked = 0
    for _ in range(1500):
        t, theta = _turns(rng)
        y = rng.normal(size=(t.size, 2))
        try:
            got = compute_integer_revolution_window(t, y, angle_rad=theta)
        except InvalidInputError:
            continue
        a, b, n_rev = _reference_span(t, np.unwrap(theta))
        assert (got.start_index, got.stop_index, got.n_revolutions) == (a, b, n_rev)
        checked += 1
    assert checked > 500


@pytest.mark.parametrize("n", [10, 91, 180, 181, 360, 361, 720])
def test_revolution_window_on_an_exact_grid_takes_the_central_tie(n: int) -> None:
    t = np.arange(n) / 100.0
    for theta in (np.arange(n) * (2 * np.pi / 90), -np.arange(n) * (2 * np.pi / 90)):
        try:
            got = compute_integer_revolution_window(t, np.ones((n, 1)), angle_rad=theta)
        except InvalidInputError:
            continue
        assert (got.start_index, got.stop_index) == _reference_span(t, theta)[:2]


@pytest.mark.parametrize("angle", [
    np.linspace(0.0, 30.0, 200),  # continuous
    np.angle(np.exp(1j * np.linspace(0.0, 30.0, 200))),  # wrapped
    -np.linspace(0.0, 30.0, 200),
    np.array([0.0, -0.0, 0.0, -0.0]),  # signed zeros
    np.array([-0.0, 1.0, -0.0, -3.5, 3.5]),
    np.array([0.0, np.nan, 1.0]),
    np.array([1.0]),
    np.array([0, 1, 5, 2]),  # integers
])
def test_unwrap_angle_is_np_unwrap(angle: np.ndarray) -> None:
    got, want = unwrap_angle(angle), np.unwrap(angle)
    np.testing.assert_array_equal(got, want)
    assert np.array_equal(np.signbit(got), np.signbit(want))
    assert got is not angle


# --------------------------------------------------------------------------- time base


def test_gap_free_counter_takes_the_general_path_s_values() -> None:
    rng = np.random.default_rng(2)
    c = np.arange(1000, 1600, dtype=np.int64)
    t = 5.0 + 0.01 * (c - c[0]) + rng.normal(0.0, 1e-4, c.size)
    fast = reconstruct_time_base(c, t)
    general = reconstruct_time_base(c, t, counter_modulus=1 << 40)  # no wrap: the cumsum path
    for name in ("time_s", "counter", "gap_indices"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(general, name))
        assert getattr(fast, name).dtype == getattr(general, name).dtype
        assert not getattr(fast, name).flags.writeable
    assert (fast.sample_period_s, fast.offset_s, fast.jitter_s, fast.n_missing) == (
        general.sample_period_s, general.offset_s, general.jitter_s, general.n_missing)
    assert c.flags.writeable  # the caller's counter is not the frozen result
    wrapped = reconstruct_time_base(c % 256, t, counter_modulus=256)  # wraps: unwrapped still
    np.testing.assert_array_equal(wrapped.counter - wrapped.counter[0], c - c[0])
