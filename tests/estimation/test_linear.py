"""Tests of imucalib.estimation.linear: exactness, closed loop, covariance vs Monte Carlo."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation import (
    TRIAD_PARAMETER_NAMES,
    build_triad_design,
    compute_six_position_accel_crlb,
    solve_weighted_lsq,
)

N_MC = 400


def test_noise_free_six_position_recovers_truth_exactly(kit: SimpleNamespace, truth,
                                                        six_up) -> None:
    z, x = kit.observations(truth, six_up, np.random.default_rng(0), sigma=0.0)
    d = build_triad_design(x)
    sol = solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=kit.SIGMA)
    np.testing.assert_allclose(sol.estimate, kit.truth_vector(truth), rtol=0, atol=1e-15 * kit.G)
    assert sol.rank == 12 and sol.dof == 6
    assert sol.chi2 < 1e-20
    assert sol.param_names == TRIAD_PARAMETER_NAMES


def test_docstring_example_by_hand() -> None:
    # b + s·x for x = 1, −1, 0: normal equations give var(b) = σ²/3, var(s) = σ²/2
    H = np.array([[1.0, 1.0], [1.0, -1.0], [1.0, 0.0]])
    sol = solve_weighted_lsq(H, [3.1, -1.0, 1.0], param_names=["b", "s"], sigma=0.1)
    np.testing.assert_allclose(sol.std, [0.1 / np.sqrt(3), 0.1 / np.sqrt(2)], rtol=1e-12)
    np.testing.assert_allclose(sol.estimate, [3.1 / 3, 4.1 / 2], rtol=1e-12)
    np.testing.assert_allclose(sol.residuals, [3.1 - sol.estimate @ [1, 1],
                                               -1.0 - sol.estimate @ [1, -1],
                                               1.0 - sol.estimate[0]], atol=1e-14)
    assert sol.as_dict()["s"] == pytest.approx(2.05)
    assert sol.std_dict()["b"] == pytest.approx(0.1 / np.sqrt(3))
    assert not sol.covariance_scaled


@pytest.mark.slow
def test_monte_carlo_spread_matches_covariance_and_crlb(kit: SimpleNamespace, truth,
                                                        six_up) -> None:
    rng = np.random.default_rng(2024)
    est = np.empty((N_MC, 12))
    chi2 = np.empty(N_MC)
    wres = []
    for k in range(N_MC):
        z, x = kit.observations(truth, six_up, rng)
        d = build_triad_design(x)
        sol = solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=kit.SIGMA)
        est[k], chi2[k] = sol.estimate, sol.chi2
        wres.append(sol.normalized_residuals)
    # the reported covariance is the CRLB closed form (docs/equations.md §12)
    bound = compute_six_position_accel_crlb(kit.SIGMA, gravity_mps2=kit.G)
    np.testing.assert_allclose(sol.std[:3], bound.bias_std_mps2, rtol=1e-9)
    np.testing.assert_allclose(sol.std[3:], bound.scale_misalignment_std, rtol=1e-9)
    err = (est - kit.truth_vector(truth)) / sol.std
    # unbiased: the mean normalised error of N_MC runs has sd 1/√N_MC
    assert np.all(np.abs(err.mean(axis=0)) < 4.0 / np.sqrt(N_MC))
    # spread: sample variance / reported variance ~ χ²(N−1)/(N−1); 99.9 % two-sided bounds
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], N_MC - 1) / (N_MC - 1)
    ratio = err.var(axis=0, ddof=1)
    assert np.all((ratio > lo) & (ratio < hi)), ratio
    # χ² of the fit has mean ν = 6
    assert chi2.mean() == pytest.approx(6.0, abs=4 * np.sqrt(12.0 / N_MC))
    w = np.concatenate(wres)
    assert np.nanstd(w) == pytest.approx(1.0, abs=0.05)


def test_unknown_noise_scales_covariance_by_variance_factor(kit: SimpleNamespace, truth,
                                                            six_up) -> None:
    rng = np.random.default_rng(5)
    z, x = kit.observations(truth, np.vstack([six_up] * 4), rng)
    d = build_triad_design(x)
    known = solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=kit.SIGMA)
    unknown = solve_weighted_lsq(d.H, z, param_names=d.param_names)
    assert unknown.covariance_scaled and not known.covariance_scaled
    np.testing.assert_allclose(unknown.estimate, known.estimate, rtol=1e-10, atol=1e-16)
    # σ̂₀² with unit weights is the residual variance; it estimates σ²
    assert unknown.variance_factor == pytest.approx(known.variance_factor * kit.SIGMA**2, rel=1e-9)
    assert unknown.variance_factor == pytest.approx(kit.SIGMA**2, rel=0.5)
    np.testing.assert_allclose(unknown.std, known.std * np.sqrt(known.variance_factor), rtol=1e-9)
    # known noise: scaling follows the one misfit rule (Birge ratio only on a misfit)
    forced = solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=kit.SIGMA,
                                scale_covariance=True)
    assert forced.covariance_scaled and not forced.fit_quality.misfit
    np.testing.assert_array_equal(forced.std, known.std_birge)
    np.testing.assert_allclose(forced.std, known.std, rtol=1e-12)
    # unknown noise: σ̂₀² estimates it; nothing is left to test
    assert unknown.fit_quality.chi2 == unknown.dof and not unknown.fit_quality.misfit
    np.testing.assert_array_equal(unknown.covariance_birge, unknown.covariance)


def test_weights_sigma_and_diagonal_covariance_agree(kit: SimpleNamespace, truth, six_up) -> None:
    rng = np.random.default_rng(9)
    z, x = kit.observations(truth, six_up, rng)
    d = build_triad_design(x)
    sig = kit.SIGMA * rng.uniform(0.5, 2.0, z.size)
    a = solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=sig)
    b = solve_weighted_lsq(d.H, z, param_names=d.param_names, weights=1 / sig**2)
    c = solve_weighted_lsq(d.H, z, param_names=d.param_names, covariance=sig**2)
    e = solve_weighted_lsq(d.H, z, param_names=d.param_names, covariance=np.diag(sig**2))
    for other in (b, c, e):
        np.testing.assert_allclose(other.estimate, a.estimate, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(other.covariance, a.covariance, rtol=1e-9,
                                   atol=1e-12 * np.abs(a.covariance).max())
        np.testing.assert_allclose(other.normalized_residuals, a.normalized_residuals,
                                   rtol=1e-7, atol=1e-9)


@pytest.mark.slow
def test_correlated_noise_gls_matches_monte_carlo() -> None:
    # AR(1)-correlated observations of a line: GLS covariance must match the MC spread
    rng = np.random.default_rng(11)
    m = 40
    t = np.linspace(-1.0, 1.0, m)
    H = np.column_stack([np.ones(m), t])
    rho, sig = 0.8, 0.3
    C = sig**2 * rho ** np.abs(np.subtract.outer(np.arange(m), np.arange(m)))
    L = np.linalg.cholesky(C)
    truth = np.array([1.5, -0.7])
    est = np.empty((N_MC, 2))
    for k in range(N_MC):
        z = H @ truth + L @ rng.standard_normal(m)
        sol = solve_weighted_lsq(H, z, param_names=["a", "b"], covariance=C)
        est[k] = sol.estimate
    expected = np.linalg.inv(H.T @ np.linalg.solve(C, H))
    np.testing.assert_allclose(sol.covariance, expected, rtol=1e-10, atol=1e-12 * expected.max())
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], N_MC - 1) / (N_MC - 1)
    ratio = np.var(est, axis=0, ddof=1) / np.diag(expected)
    assert np.all((ratio > lo) & (ratio < hi)), ratio
    # normalised residuals are N(0, 1) under correlated noise too
    assert np.nanstd(sol.normalized_residuals) == pytest.approx(1.0, abs=0.5)


def test_gross_error_has_largest_normalized_residual(kit: SimpleNamespace, truth, six_up) -> None:
    rng = np.random.default_rng(3)
    z, x = kit.observations(truth, np.vstack([six_up, six_up]), rng)
    z[7] += 8 * kit.SIGMA
    d = build_triad_design(x)
    sol = solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=kit.SIGMA)
    assert int(np.nanargmax(np.abs(sol.normalized_residuals))) == 7
    assert abs(sol.normalized_residuals[7]) > 3.0


def test_leverage_one_observation_has_nan_normalized_residual() -> None:
    H = np.array([[1.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    sol = solve_weighted_lsq(H, [1.0, 1.1, 0.9, 5.0], param_names=["a", "b"], sigma=0.1)
    assert np.isnan(sol.normalized_residuals[3])
    assert np.all(np.isfinite(sol.normalized_residuals[:3]))


def test_column_scaling_makes_units_irrelevant() -> None:
    rng = np.random.default_rng(1)
    H = rng.normal(size=(30, 4))
    z = H @ np.array([1.0, 2.0, -1.0, 0.5]) + rng.normal(0, 0.01, 30)
    base = solve_weighted_lsq(H, z, param_names=list("abcd"), sigma=0.01)
    scales = np.array([1e-8, 1.0, 1e6, 1e12])  # same parameters in wildly different units
    scaled = solve_weighted_lsq(H * scales, z, param_names=list("abcd"), sigma=0.01)
    np.testing.assert_allclose(scaled.estimate * scales, base.estimate, rtol=1e-9)
    np.testing.assert_allclose(scaled.std * scales, base.std, rtol=1e-9)
    assert scaled.condition_number == pytest.approx(base.condition_number, rel=1e-9)


def test_six_positions_missing_both_x_positions_names_x_column(kit: SimpleNamespace, truth,
                                                              six_up) -> None:
    up = six_up[[0, 1, 4, 5]]  # Z up/down, Y up/down: f_x = 0 everywhere
    z, x = kit.observations(truth, up, np.random.default_rng(0))
    d = build_triad_design(x)
    with pytest.raises(InsufficientExcitationError,
                       match=r"expected full rank 12 .* got rank 9 of 12.*unobservable: "
                             r"M_xx, M_yx, M_zx$") as info:
        solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=kit.SIGMA)
    assert info.value.unobservable == ("M_xx", "M_yx", "M_zx")


def test_three_positions_name_the_bias_scale_combination(kit: SimpleNamespace, truth,
                                                         six_up) -> None:
    up = six_up[[0, 2, 4]]  # Z, X, Y up only: b_i and row i of M are confounded
    z, x = kit.observations(truth, up, np.random.default_rng(0))
    d = build_triad_design(x)
    with pytest.raises(InsufficientExcitationError, match=r"rank 9 of 12") as info:
        solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=kit.SIGMA)
    assert set(info.value.unobservable) == set(TRIAD_PARAMETER_NAMES)
    assert "weak direction" in str(info.value)


def test_ill_conditioned_design_raises_with_condition_number() -> None:
    t = np.linspace(0, 1, 20)
    H = np.column_stack([t, t + 1e-12 * np.sin(7 * t), np.ones(20)])
    with pytest.raises(InsufficientExcitationError,
                       match=r"condition number ≤ 1e\+10; got rank 3 of 3, condition number "
                             r"[0-9.e+]+ .*unobservable: a, b$"):
        solve_weighted_lsq(H, t, param_names=["a", "b", "c"], sigma=1.0)
    # a looser limit accepts it
    sol = solve_weighted_lsq(H, t, param_names=["a", "b", "c"], sigma=1.0, cond_limit=1e15)
    assert sol.condition_number > 1e10


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"H": [[1.0, np.nan], [0.0, 1.0]]}, r"`H` must be finite; got 1 NaN"),
        ({"H": [1.0, 2.0]}, r"`H` must have shape \(n, n\); got \(2,\)"),
        ({"z": [1.0, 2.0, 3.0]}, r"`z` must have shape \(2\); got \(3,\)"),
        ({"z": [1.0, np.inf]}, r"`z` must be finite"),
        ({"param_names": ["a"]}, r"`param_names` must have 2 entries \(one per column\); got 1"),
        ({"param_names": ["a", "a"]}, r"`param_names` must be distinct; got duplicates \['a'\]"),
        ({"param_names": "ab"}, r"must be a sequence of strings; got the string 'ab'"),
        ({"weights": [1.0, -1.0]}, r"`weights` must be > 0; got 1 value\(s\) ≤ 0"),
        ({"sigma": [1.0, 1.0, 1.0]}, r"`sigma` must be a scalar or have shape \(2,\); got \(3,\)"),
        ({"sigma": 1.0, "weights": [1.0, 1.0]},
         r"give at most one of `weights`, `covariance`, `sigma`; got \['weights', 'sigma'\]"),
        ({"covariance": [[1.0, 0.5], [0.4, 1.0]]}, r"`covariance` must be symmetric"),
        ({"covariance": [[1.0, 2.0], [2.0, 1.0]]}, r"`covariance` must be positive definite"),
        ({"covariance": np.eye(3)}, r"`covariance` must be a scalar or have shape \(2,\) or "
                                    r"\(2, 2\); got \(3, 3\)"),
        ({}, r"needs more observations than parameters; got m = 2, p = 2"),
    ],
)
def test_bad_inputs_raise_with_messages(kwargs: dict, match: str) -> None:
    args = {"H": np.eye(2), "z": [1.0, 2.0], "param_names": ["a", "b"]}
    args.update(kwargs)
    H = args.pop("H")
    z = args.pop("z")
    with pytest.raises(InvalidInputError, match=match):
        solve_weighted_lsq(H, z, **args)


def test_result_is_read_only(kit: SimpleNamespace, truth, six_up) -> None:
    z, x = kit.observations(truth, six_up, np.random.default_rng(0))
    d = build_triad_design(x)
    sol = solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=kit.SIGMA)
    with pytest.raises(ValueError, match="read-only"):
        sol.estimate[0] = 1.0
    corr = sol.correlation()
    np.testing.assert_allclose(np.diag(corr), 1.0)
    assert np.all(np.abs(corr) <= 1.0 + 1e-12)
