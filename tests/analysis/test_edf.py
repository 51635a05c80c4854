"""EDF (Greenhall–Riley, SP 1065), χ² intervals and lag-1 noise identification."""

from __future__ import annotations

import math

import numpy as np
import pytest
from allantools import ci as at_ci
from scipy import special

from imucalib.analysis import (
    ONE_SIGMA,
    compute_confidence_interval,
    compute_edf,
    compute_edf_greenhall,
    compute_edf_totdev,
    compute_oadev,
    identify_noise_lag1,
)
from imucalib.errors import InvalidInputError

CASES = [(d, alpha, ov, mod, n, m)
         for d in (2, 3) for alpha in range(-4, 3) if alpha + 2 * d > 1
         for ov in (False, True) for mod in (False, True)
         for n in (100, 1001, 100_001) for m in (1, 2, 7, 16, 100, 1000)
         if m * (d + 1) < n and not (alpha == 2 and not mod)]


@pytest.mark.parametrize(("d", "alpha", "ov", "mod", "n", "m"), CASES)
def test_greenhall_edf_equals_allantools(d: int, alpha: int, ov: bool, mod: bool, n: int,
                                         m: int) -> None:
    try:
        ref = at_ci.edf_greenhall(alpha, d, m, n, overlapping=ov, modified=mod)
    except AssertionError:  # allantools lacks Table 2 rows for α = −3, −4 unmodified
        ref = None
    ours = compute_edf_greenhall(alpha, d, m, n, overlapping=ov, modified=mod)
    if ref is not None:
        assert ours == pytest.approx(ref, rel=1e-12)
    assert ours > 0


def brute_white_pm_inverse_edf(d: int, m: int, n: int, overlapping: bool) -> float:
    """1/edf of the unmodified d-th-difference variance of white phase, by direct summation."""
    coef = np.array([(-1) ** (d - k) * special.comb(d, k) for k in range(d + 1)])
    stride = 1 if overlapping else m
    starts = np.arange(0, n - d * m, stride)
    # Cov(z_i, z_j) = Σ_{a,b} c_a c_b δ(start_i + a m, start_j + b m)
    big_m = starts.size
    total = 0.0
    norm = float(np.sum(coef**2))
    for i in range(big_m):
        for j in range(big_m):
            lag = starts[j] - starts[i]
            if lag % m:
                continue
            k = lag // m
            c = sum(coef[a] * coef[a - k] for a in range(d + 1) if 0 <= a - k <= d)
            total += (c / norm) ** 2
    return total / big_m**2


@pytest.mark.parametrize(("d", "m", "n", "ov"), [(2, 1, 40, True), (2, 5, 40, True),
                                                 (2, 5, 40, False), (3, 4, 30, True),
                                                 (2, 8, 30, True), (3, 3, 13, False)])
def test_white_pm_edf_equals_direct_summation(d: int, m: int, n: int, ov: bool) -> None:
    """Case 4 (α = 2, unmodified), including K = ⌈r⌉ ≤ d, which allantools leaves undone."""
    ours = compute_edf_greenhall(2, d, m, n, overlapping=ov, modified=False)
    assert 1 / ours == pytest.approx(brute_white_pm_inverse_edf(d, m, n, ov), rel=1e-12)


def test_totdev_edf_table_7() -> None:
    assert compute_edf_totdev(0, 10, 1001) == pytest.approx(1.50 * 100)
    assert compute_edf_totdev(-1, 10, 1001) == pytest.approx(1.17 * 100 - 0.22)
    assert compute_edf_totdev(-2, 10, 1001) == pytest.approx(0.93 * 100 - 0.36)
    # other noise types fall back to the overlapping Allan EDF
    assert compute_edf_totdev(2, 10, 1001) == pytest.approx(
        compute_edf_greenhall(2, 2, 10, 1001, overlapping=True, modified=False))


def test_edf_dispatch_clips_alpha() -> None:
    assert compute_edf("oadev", -4, 10, 1001) == compute_edf("oadev", -2, 10, 1001)
    assert compute_edf("ohdev", -4, 10, 1001) == compute_edf_greenhall(
        -4, 3, 10, 1001, overlapping=True, modified=False)
    assert compute_edf("mdev", 0, 10, 1001) == compute_edf_greenhall(
        0, 2, 10, 1001, overlapping=True, modified=True)
    with pytest.raises(InvalidInputError, match="unknown deviation kind 'xdev'"):
        compute_edf("xdev", 0, 1, 100)
    with pytest.raises(InvalidInputError, match=r"not defined for alpha=-3 \(needs alpha"):
        compute_edf_greenhall(-3, 2, 1, 100, overlapping=True, modified=False)
    with pytest.raises(InvalidInputError, match="no complete term: m=50 needs more than 150"):
        compute_edf_greenhall(0, 2, 50, 120, overlapping=True, modified=True)


def test_confidence_interval_is_the_chi2_interval() -> None:
    lo, hi = compute_confidence_interval(2.0, 10.0, 0.9)
    from scipy import stats
    assert lo == pytest.approx(2.0 * math.sqrt(10 / stats.chi2.ppf(0.95, 10)))
    assert hi == pytest.approx(2.0 * math.sqrt(10 / stats.chi2.ppf(0.05, 10)))
    assert ONE_SIGMA == pytest.approx(0.6826894921370859)
    with pytest.raises(InvalidInputError, match=r"`confidence` must be in \(0, 1\); got 1.5"):
        compute_confidence_interval(1.0, 5.0, 1.5)
    with pytest.raises(InvalidInputError, match=r"`edf` must be > 0; got minimum 0\.0"):
        compute_confidence_interval(1.0, 0.0)


def powerlaw(alpha: int, n: int, rng: np.random.Generator) -> np.ndarray:
    """Rate samples with S_y ∝ f^α (α = 2, 0, −2 exactly; −1 by a 1/f filter in frequency)."""
    w = rng.standard_normal(n + 1)
    if alpha == 2:
        return np.diff(w)
    if alpha == 0:
        return w[:n]
    if alpha == -2:
        return np.cumsum(w[:n])
    f = np.fft.rfftfreq(2 * n)
    spec = np.fft.rfft(rng.standard_normal(2 * n))
    spec[1:] /= np.sqrt(f[1:])
    spec[0] = 0
    return np.fft.irfft(spec)[:n]


@pytest.mark.parametrize("alpha", [2, 0, -1, -2])
def test_lag1_identifies_power_law_noise(alpha: int) -> None:
    rng = np.random.default_rng(alpha + 10)
    y = powerlaw(alpha, 4000, rng)
    ident = identify_noise_lag1(y, max_differences=2)
    assert ident.alpha == alpha
    assert ident.n_points == 4000
    res = compute_oadev(powerlaw(alpha, 1 << 16, rng), 1.0)
    enough = [a for a, how in zip(res.noise_alpha, res.noise_id_method, strict=True)
              if how == "lag1-acf"]
    assert np.mean(np.array(enough[:8]) == alpha) >= 0.75


def test_noise_id_needs_30_points_and_long_tau_reuses_the_nearest() -> None:
    with pytest.raises(InvalidInputError, match="at least 30 τ-averages; got 29"):
        identify_noise_lag1(np.arange(29.0))
    res = compute_oadev(np.random.default_rng(1).standard_normal(5000), 1.0)
    methods = np.array(res.noise_id_method)
    assert methods[0] == "lag1-acf" and methods[-1] == "nearest"
    last_acf = np.flatnonzero(methods == "lag1-acf")[-1]
    assert np.all(res.noise_alpha[last_acf + 1:] == res.noise_alpha[last_acf])


def test_confidence_intervals_cover_the_truth() -> None:
    """White rate noise: σ(τ) = N/√τ lies in the ±1σ interval in about 68 % of the records."""
    rng = np.random.default_rng(4)
    hits, total = 0, 0
    for _ in range(60):
        res = compute_oadev(rng.standard_normal(4096), 1.0, taus=[1, 4, 16, 64, 256])
        truth = 1 / np.sqrt(res.taus_s)
        hits += int(np.sum((res.ci_low <= truth) & (truth <= res.ci_high)))
        total += truth.size
    assert 0.60 <= hits / total <= 0.76


def test_lag1_detrending_line_is_polyfits_to_rounding() -> None:
    """The closed-form line: the same α as ``np.polyfit``'s detrending, ρ to rounding."""
    from imucalib.analysis.edf import _detrended, _lag1

    rng = np.random.default_rng(3)
    for i in range(400):
        n = int(rng.integers(30, 1200))
        z = rng.standard_normal(n)
        z = (z, np.cumsum(z), np.cumsum(np.cumsum(z)), z + 1e3 + 0.01 * np.arange(n))[i % 4]
        k = np.arange(n, dtype=np.float64)
        slow = z - np.polyval(np.polyfit(k, z, 1), k)
        fast = _detrended(z)
        np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-9 * float(np.max(np.abs(z))))
        assert abs(_lag1(fast) - _lag1(slow)) < 1e-10
        d = 0
        while d < 2:  # the identified α: one rounding of 2δ after d differences
            r_fast, r_slow = _lag1(fast), _lag1(slow)
            assert round(2 * r_fast / (1 + r_fast)) == round(2 * r_slow / (1 + r_slow))
            fast, slow, d = np.diff(fast), np.diff(slow), d + 1
