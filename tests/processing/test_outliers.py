"""Tests of imucalib.processing.outliers: 3σ (robust and classical), Grubbs, generalised ESD."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.processing import (
    grubbs_critical_value,
    reject_outliers_3sigma,
    reject_outliers_grubbs,
)

# NIST/SEMATECH e-Handbook §1.3.5.17.3 (generalized ESD test), Rosner's (1983) example: 54 values;
# with r = 10 and α = 0.05 the test finds 3 outliers while the first Grubbs test is not
# significant (masking). Ri and λi as printed by the handbook.
ROSNER = np.array([
    -0.25, 0.68, 0.94, 1.15, 1.20, 1.26, 1.26, 1.34, 1.38, 1.43, 1.49, 1.49, 1.55, 1.56, 1.58,
    1.65, 1.69, 1.70, 1.76, 1.77, 1.81, 1.91, 1.94, 1.96, 1.99, 2.06, 2.09, 2.10, 2.14, 2.15,
    2.23, 2.24, 2.26, 2.35, 2.37, 2.40, 2.47, 2.54, 2.62, 2.64, 2.90, 2.92, 2.92, 2.93, 3.21,
    3.26, 3.30, 3.59, 3.68, 4.30, 4.64, 5.34, 5.42, 6.01,
])
ROSNER_R = [3.118, 2.942, 3.179, 2.810, 2.815, 2.848, 2.279, 2.310, 2.101, 2.067]
ROSNER_LAMBDA = [3.158, 3.151, 3.143, 3.136, 3.128, 3.120, 3.111, 3.103, 3.094, 3.085]


def test_rosner_example_generalized_esd_and_masking() -> None:
    gesd = reject_outliers_grubbs(ROSNER, alpha=0.05, max_outliers=10)
    assert gesd.test == "generalized-esd"
    assert gesd.n_outliers.tolist() == [3]
    np.testing.assert_array_equal(np.sort(ROSNER[gesd.outlier_mask]), [5.34, 5.42, 6.01])
    # the classic iterated Grubbs test stops at the first (masked) step
    classic = reject_outliers_grubbs(ROSNER, alpha=0.05)
    assert classic.n_outliers.tolist() == [0] and classic.n_iterations.tolist() == [1]
    # the handbook's critical values, Eq. (1), for n = 54 … 45
    lam = grubbs_critical_value(np.arange(54, 44, -1), 0.05)
    np.testing.assert_allclose(lam, ROSNER_LAMBDA, atol=1.5e-3)
    # and its test statistics
    x = ROSNER.copy()
    for r_expected in ROSNER_R:
        dev = np.abs(x - x.mean())
        assert dev.max() / x.std(ddof=1) == pytest.approx(r_expected, abs=1.5e-3)
        x = np.delete(x, np.argmax(dev))


def test_grubbs_critical_value_bounds_and_table() -> None:
    assert grubbs_critical_value(10, 0.05) == pytest.approx(2.290, abs=5e-4)  # NIST table
    n = np.arange(3, 200)
    g = grubbs_critical_value(n, 0.01)
    assert np.all(g < (n - 1) / np.sqrt(n))  # the largest possible G
    assert np.all(np.diff(g) > 0)


def test_grubbs_false_alarm_rate_is_alpha() -> None:
    # 4000 clean columns of 30 samples: the fraction with any flag estimates P(reject) = α
    x = np.random.default_rng(0).normal(size=(30, 4000))
    res = reject_outliers_grubbs(x, alpha=0.05)
    rate = np.mean(res.n_outliers > 0)
    assert rate == pytest.approx(0.05, abs=4 * np.sqrt(0.05 * 0.95 / 4000))


def test_grubbs_finds_planted_outliers_in_every_column() -> None:
    rng = np.random.default_rng(1)
    x = rng.normal(size=(200, 3))
    x[17, 0] += 8.0
    x[150, 1] -= 9.0
    x[[40, 41], 2] += [7.0, -7.5]
    res = reject_outliers_grubbs(x, alpha=0.01, max_outliers=5)
    assert res.outlier_mask[17, 0] and res.outlier_mask[150, 1]
    assert res.outlier_mask[40, 2] and res.outlier_mask[41, 2]
    assert res.n_outliers.tolist() == [1, 1, 2]
    # interpolation from the neighbours of the same column
    assert res.values[17, 0] == pytest.approx(0.5 * (x[16, 0] + x[18, 0]))
    assert res.values[40, 2] == pytest.approx(x[39, 2] + (x[42, 2] - x[39, 2]) / 3)
    np.testing.assert_array_equal(res.values[~res.outlier_mask], x[~res.outlier_mask])
    np.testing.assert_allclose(res.center, [x[~res.outlier_mask[:, j], j].mean()
                                            for j in range(3)])


def test_3sigma_robust_finds_outliers_and_interpolates() -> None:
    rng = np.random.default_rng(2)
    x = rng.normal(0.0, 1.0, 5000)
    idx = rng.choice(np.arange(1, 4999), 25, replace=False)
    x[idx] += rng.choice([-1.0, 1.0], 25) * rng.uniform(10.0, 1000.0, 25)
    res = reject_outliers_3sigma(x)
    assert res.test == "3sigma-robust" and res.method == "interpolate"
    assert np.all(res.outlier_mask[idx])
    # clean Gaussian samples flagged at about the 3σ rate (0.27 %)
    assert res.n_outliers[0] - 25 < 0.006 * 5000
    assert res.center[0] == pytest.approx(0.0, abs=0.05)
    assert res.scale[0] == pytest.approx(1.0, rel=0.05)
    assert res.values.shape == x.shape and res.n_removed_rows == 0
    assert np.max(np.abs(res.values)) < 3.5 * res.scale[0]


@pytest.mark.slow
def test_3sigma_false_positive_rate_on_clean_data() -> None:
    x = np.random.default_rng(3).normal(size=(200_000, 2))
    for robust in (True, False):
        res = reject_outliers_3sigma(x, robust=robust)
        frac = res.n_outliers / x.shape[0]
        # P(|z| > 3) = 0.27 %; the iteration adds a few more (truncated scale)
        assert np.all((frac > 0.0024) & (frac < 0.0040)), (robust, frac)


def test_robust_scale_resists_masking_where_classical_fails() -> None:
    rng = np.random.default_rng(4)
    x = rng.normal(0.0, 1.0, 1000)
    x[:150] = 5.0 + rng.normal(0.0, 0.1, 150)  # 15 % contamination at 5σ
    robust = reject_outliers_3sigma(x, robust=True)
    classic = reject_outliers_3sigma(x, robust=False)
    assert np.all(robust.outlier_mask[:150])
    assert np.count_nonzero(classic.outlier_mask[:150]) < 150  # masked by the inflated σ
    assert classic.test == "3sigma"


def test_zero_mad_falls_back_to_standard_deviation() -> None:
    x = np.zeros(100)
    x[::5] = 1.0
    x[2::5] = -1.0  # quantised data, 60 % zeros: MAD = 0
    x[51] = 100.0
    res = reject_outliers_3sigma(x)
    assert res.outlier_mask.tolist() == [i == 51 for i in range(100)]
    assert res.scale[0] == pytest.approx(np.std(np.delete(x, 51), ddof=1))


def test_drop_removes_union_of_rows_and_reports_counts() -> None:
    rng = np.random.default_rng(5)
    x = rng.normal(size=(500, 3))
    x[10, 0] = 50.0
    x[10, 2] = -50.0
    x[300, 1] = 40.0
    res = reject_outliers_3sigma(x, method="drop", n_sigma=6.0)
    assert res.n_outliers.tolist() == [1, 1, 1]
    assert res.n_removed_rows == 2
    assert not res.kept[10] and not res.kept[300]
    np.testing.assert_array_equal(res.values, x[res.kept])
    assert res.outlier_mask.shape == x.shape


def test_interpolation_uses_time_when_given() -> None:
    t = np.array([0.0, 1.0, 1.5, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0])
    x = 2.0 * t
    x[3] = 1000.0
    res = reject_outliers_grubbs(x, time_s=t)
    assert res.outlier_mask[3]
    assert res.values[3] == pytest.approx(8.0)  # 2·t, from t = 1.5 and t = 5
    by_index = reject_outliers_grubbs(x)
    assert by_index.values[3] == pytest.approx(0.5 * (x[2] + x[4]))


def test_one_dimensional_input_keeps_its_shape() -> None:
    x = np.r_[np.random.default_rng(6).normal(size=99), 30.0]
    res = reject_outliers_grubbs(x, method="drop")
    assert res.values.shape == (99,) and res.outlier_mask.shape == (100,)
    assert res.n_outliers.shape == (1,)
    with pytest.raises(ValueError, match="read-only"):
        res.values[0] = 0.0


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: reject_outliers_3sigma([1.0, 2.0]), r"at least 3 samples .*; got shape \(2,\)"),
        (lambda: reject_outliers_3sigma([1.0, np.nan, 2.0, 3.0]), r"`values` must be finite"),
        (lambda: reject_outliers_3sigma(np.zeros((4, 2, 2))),
         r"`values` must have shape \(n,\) or \(n, k\); got \(4, 2, 2\)"),
        (lambda: reject_outliers_3sigma(np.ones(5), method="median"),
         r"`method` must be 'interpolate' or 'drop'; got 'median'"),
        (lambda: reject_outliers_3sigma(np.ones(5), n_sigma=0.0), r"`n_sigma` must be > 0"),
        (lambda: reject_outliers_3sigma(np.ones(5), max_iterations=0),
         r"`max_iterations` must be an integer ≥ 1; got 0"),
        (lambda: reject_outliers_3sigma(np.ones(4), time_s=[0.0, 1.0, 1.0, 2.0]),
         r"`time_s` must be strictly increasing; got time_s\[2\] = 1.0 after time_s\[1\] = 1.0"),
        (lambda: reject_outliers_3sigma(np.ones(4), time_s=[0.0, 1.0, 2.0]),
         r"`time_s` must have 4 samples \(one per row\); got 3"),
        (lambda: reject_outliers_grubbs(np.ones(5), alpha=1.5),
         r"`alpha` must be in \(0, 1\); got 1.5"),
        (lambda: reject_outliers_grubbs(np.ones(5), max_outliers=4),
         r"`max_outliers` must be ≤ n − 2 = 3; got 4"),
    ],
)
def test_bad_inputs_raise_with_messages(call, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        call()


def test_interpolation_from_the_kept_neighbours_equals_that_from_all_kept_samples():
    """The replacement of flagged samples reads only the kept rows around each run of them."""
    from imucalib.processing.outliers import _kept_neighbours

    rng = np.random.default_rng(5)
    checked = 0
    for trial in range(2000):
        n = int(rng.integers(3, 60))
        m = rng.random(n) < rng.uniform(0.02, 0.7)
        if trial % 3 == 0:  # a run at the start
            m[: rng.integers(1, n)] = True
        if trial % 5 == 0:  # a run at the end
            m[-int(rng.integers(1, n)):] = True
        if m.all() or not m.any():
            continue
        axis = np.sort(rng.uniform(0.0, 100.0, n))
        col = rng.normal(size=n)
        bad = np.flatnonzero(m)
        near = _kept_neighbours(bad, n)
        assert np.all(np.diff(near) > 0) and not m[near].any()
        np.testing.assert_array_equal(np.interp(axis[bad], axis[near], col[near]),
                                      np.interp(axis[m], axis[~m], col[~m]))
        checked += 1
    assert checked > 1500
