"""The one weighted least-squares solver (estimation.linear, docs/processing-estimation.md,
"One solver"): full covariance vs σ, GLS by hand, the one misfit rule and its Birge scaling,
a rank-deficient design named, σ against a Monte-Carlo spread."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from imucalib.errors import InsufficientExcitationError
from imucalib.estimation import solve_weighted_lsq
from imucalib.models.fit_quality import MISFIT_QUANTILE, assess_fit


def _line(n: int = 12) -> np.ndarray:
    t = np.linspace(-1.0, 1.0, n)
    return np.column_stack([np.ones(n), t, t**2])


def test_a_diagonal_full_covariance_is_the_same_fit_as_sigma() -> None:
    rng = np.random.default_rng(1)
    H = _line()
    sig = rng.uniform(0.5, 2.0, H.shape[0])
    z = H @ [1.0, -2.0, 0.5] + rng.normal(0.0, sig)
    by_sigma = solve_weighted_lsq(H, z, param_names=list("abc"), sigma=sig, gain=True)
    by_cov = solve_weighted_lsq(H, z, param_names=list("abc"), covariance=np.diag(sig**2),
                                gain=True)
    for name in ("estimate", "covariance", "covariance_noise", "covariance_birge", "residuals",
                 "normalized_residuals", "gain"):
        np.testing.assert_allclose(getattr(by_cov, name), getattr(by_sigma, name), rtol=1e-12,
                                   atol=1e-15, err_msg=name)
    assert by_cov.chi2 == pytest.approx(by_sigma.chi2, rel=1e-12)
    assert by_cov.fit_quality.chi2 == pytest.approx(by_sigma.fit_quality.chi2, rel=1e-12)
    assert by_cov.fit_quality.misfit == by_sigma.fit_quality.misfit
    # the gain maps the observations to the estimate and the noise to the covariance, Eq. (1)
    assert by_sigma.gain is not None
    np.testing.assert_allclose(by_sigma.gain @ z, by_sigma.estimate, rtol=1e-12)
    np.testing.assert_allclose(by_sigma.gain @ np.diag(sig**2) @ by_sigma.gain.T,
                               by_sigma.covariance_noise, rtol=1e-10)


def test_a_correlated_covariance_gives_the_gls_answer_computed_by_hand() -> None:
    """Two observations of one mean, C = [[1, ρ], [ρ, 2]], ρ = 0.5, y = (1, 4).

    C⁻¹ = [[2, −ρ], [−ρ, 1]]/(2 − ρ²), so with H = (1, 1)ᵀ:
    x̂ = ((2 − ρ)·y₁ + (1 − ρ)·y₂)/(3 − 2ρ) = (1.5 + 2)/2 = 1.75,
    var x̂ = (2 − ρ²)/(3 − 2ρ) = 0.875, K = (0.75, 0.25),
    r = (−0.75, 2.25), χ² = rᵀC⁻¹r = (2·0.5625 + 2·0.5·1.6875 + 5.0625)/1.75 = 4.5, ν = 1.
    """
    rho = 0.5
    sol = solve_weighted_lsq([[1.0], [1.0]], [1.0, 4.0], param_names=["mean"],
                             covariance=[[1.0, rho], [rho, 2.0]], gain=True)
    assert sol.estimate[0] == pytest.approx(1.75, rel=1e-14)
    assert sol.covariance_noise[0, 0] == pytest.approx(0.875, rel=1e-14)
    assert sol.gain is not None
    np.testing.assert_allclose(sol.gain, [[0.75, 0.25]], rtol=1e-14)
    np.testing.assert_allclose(sol.residuals, [-0.75, 2.25], rtol=1e-14)
    assert sol.chi2 == pytest.approx(4.5, rel=1e-14) and sol.dof == 1
    # the unweighted mean (2.5) and a fit that ignores ρ (weights 1, 1/2: 2.0) both differ
    ignore_rho = solve_weighted_lsq([[1.0], [1.0]], [1.0, 4.0], param_names=["mean"],
                                    covariance=[1.0, 2.0])
    assert ignore_rho.estimate[0] == pytest.approx(2.0, rel=1e-14)


def test_a_correlated_covariance_matches_the_normal_equations() -> None:
    rng = np.random.default_rng(2)
    H = _line(8)
    lag = np.abs(np.subtract.outer(np.arange(8), np.arange(8)))
    C = 0.3**2 * 0.7**lag                                   # AR(1) correlation
    z = H @ [0.2, 1.0, -0.3] + np.linalg.cholesky(C) @ rng.normal(size=8)
    sol = solve_weighted_lsq(H, z, param_names=list("abc"), covariance=C)
    Ci = np.linalg.inv(C)
    cov = np.linalg.inv(H.T @ Ci @ H)
    x = cov @ H.T @ Ci @ z
    r = z - H @ x
    np.testing.assert_allclose(sol.estimate, x, rtol=1e-10)
    np.testing.assert_allclose(sol.covariance_noise, cov, rtol=1e-10, atol=1e-14 * cov.max())
    assert sol.chi2 == pytest.approx(float(r @ Ci @ r), rel=1e-10)


def test_a_known_misfit_is_flagged_and_its_covariance_birge_scaled() -> None:
    """Four observations of one constant, σ = 1: y = (0, 0, 10, 10) gives x̂ = 5, χ² = 100."""
    sol = solve_weighted_lsq(np.ones((4, 1)), [0.0, 0.0, 10.0, 10.0], param_names=["c"],
                             sigma=1.0, group="const")
    q = sol.fit_quality
    assert sol.estimate[0] == pytest.approx(5.0) and sol.chi2 == pytest.approx(100.0)
    assert q == assess_fit("const", 100.0, 3)
    assert q.misfit and 100.0 > stats.chi2.ppf(MISFIT_QUANTILE, 3)
    assert q.birge_ratio == pytest.approx(math.sqrt(100.0 / 3.0))
    assert sol.variance_factor == pytest.approx(q.reduced_chi2)       # one quantity, σ̂₀² = R_B²
    assert sol.covariance_noise[0, 0] == pytest.approx(0.25)
    assert sol.covariance_birge[0, 0] == pytest.approx(0.25 * 100.0 / 3.0)
    assert sol.std_birge[0] == pytest.approx(0.5 * q.birge_ratio)
    np.testing.assert_array_equal(sol.covariance, sol.covariance_noise)  # known noise: as is
    scaled = solve_weighted_lsq(np.ones((4, 1)), [0.0, 0.0, 10.0, 10.0], param_names=["c"],
                                sigma=1.0, scale_covariance=True)
    assert scaled.covariance_scaled
    np.testing.assert_array_equal(scaled.covariance, sol.covariance_birge)


def test_a_good_fit_is_not_scaled_whatever_its_chi2() -> None:
    """χ²/ν = 2 on ν = 3 lies below χ²₃(0.99) = 11.3: the noise-only σ stand (no scaling)."""
    sol = solve_weighted_lsq(np.ones((4, 1)), [-np.sqrt(1.5), -np.sqrt(1.5), np.sqrt(1.5),
                                               np.sqrt(1.5)], param_names=["c"], sigma=1.0,
                             scale_covariance=True)
    assert sol.chi2 == pytest.approx(6.0) and not sol.fit_quality.misfit
    assert sol.variance_factor == pytest.approx(2.0)
    np.testing.assert_array_equal(sol.covariance_birge, sol.covariance_noise)
    np.testing.assert_array_equal(sol.covariance, sol.covariance_noise)


def test_a_rank_deficient_design_names_the_parameters_it_cannot_separate() -> None:
    t = np.linspace(0.0, 1.0, 6)
    H = np.column_stack([np.ones(6), t, 2.0 * np.ones(6)])      # offset twice: a = −2·c
    with pytest.raises(InsufficientExcitationError, match="add a second reference") as info:
        solve_weighted_lsq(H, t, param_names=["offset", "slope", "bias"], sigma=0.1,
                           context="test design", advice="add a second reference")
    assert set(info.value.unobservable) == {"offset", "bias"}
    assert "the test design cannot determine all parameters" in str(info.value)
    assert "rank 2 of 3" in str(info.value)
    with pytest.raises(InsufficientExcitationError) as info:   # fewer observations than terms
        solve_weighted_lsq(H[:2], t[:2], param_names=["offset", "slope", "bias"], sigma=0.1)
    assert "bias" in info.value.unobservable or "offset" in info.value.unobservable


@pytest.mark.slow
def test_sigma_matches_the_monte_carlo_spread_with_correlated_noise() -> None:
    """500 draws of AR(1)-correlated noise on a quadratic: reported σ vs the spread of x̂."""
    rng = np.random.default_rng(20240601)
    n = 15
    H = _line(n)
    lag = np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
    C = 0.05**2 * 0.6**lag
    L = np.linalg.cholesky(C)
    truth = np.array([0.3, -1.2, 0.8])
    draws, chi2, flagged = [], [], 0
    for _ in range(500):
        sol = solve_weighted_lsq(H, H @ truth + L @ rng.normal(size=n), param_names=list("abc"),
                                 covariance=C)
        draws.append(sol.estimate)
        chi2.append(sol.chi2)
        flagged += sol.fit_quality.misfit
    ratio = np.std(draws, axis=0, ddof=1) / sol.std
    assert np.all(np.abs(ratio - 1.0) < 0.1), ratio               # ±3σ of s/σ at 500 draws
    assert np.mean(chi2) == pytest.approx(n - 3, abs=4 * math.sqrt(2 * (n - 3) / 500))
    assert flagged <= 15                                           # 1 % expected (5 of 500)
    # the same noise taken as independent gives σ that are wrong by more than the MC resolves
    diag = solve_weighted_lsq(H, H @ truth, param_names=list("abc"), sigma=np.sqrt(np.diag(C)))
    assert np.max(np.abs(np.std(draws, axis=0, ddof=1) / diag.std - 1.0)) > 0.2
