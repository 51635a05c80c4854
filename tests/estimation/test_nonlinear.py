"""Tests of imucalib.estimation.nonlinear on P1's per-axis model and a gravity-norm calibration."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from imucalib import units
from imucalib.errors import ConvergenceError, InsufficientExcitationError, InvalidInputError
from imucalib.estimation import compute_crlb, solve_nonlinear_lsq

G = units.G0_MPS2
SIGMA = 67.1 * units.UG
N_MC = 300


# -- P1 step 1 model for one axis (docs/p1.md): a_out = K·(a_ref + b) ---------------------------
A_REF = G * np.array([1.0, -1.0, 0.0, 0.0, 0.0, 0.0])  # the axis up, down, and horizontal (4×)
K_TRUE, B_TRUE = 1.0 + 250e-6, 0.8 * units.MG


def p1_residuals(a_out: np.ndarray):
    def fn(x: np.ndarray) -> np.ndarray:
        return a_out - x[0] * (A_REF + x[1])
    return fn


def p1_jac(x: np.ndarray) -> np.ndarray:
    return -np.column_stack([A_REF + x[1], np.full(A_REF.size, x[0])])


def test_p1_axis_model_noise_free_exact_and_analytic_jacobian_matches_fd() -> None:
    a_out = K_TRUE * (A_REF + B_TRUE)
    fd = solve_nonlinear_lsq(p1_residuals(a_out), [1.0, 0.0], param_names=["K", "b"], sigma=SIGMA)
    an = solve_nonlinear_lsq(p1_residuals(a_out), [1.0, 0.0], param_names=["K", "b"], sigma=SIGMA,
                             jac=p1_jac)
    np.testing.assert_allclose(an.estimate, [K_TRUE, B_TRUE], rtol=1e-12)
    np.testing.assert_allclose(fd.estimate, [K_TRUE, B_TRUE], rtol=1e-10)
    np.testing.assert_allclose(fd.covariance, an.covariance, rtol=1e-6)
    # closed form at the solution: J columns (a_ref + b, K); σ_K = σ/(g√2), σ_b = σ/(K√6)
    np.testing.assert_allclose(an.std, [SIGMA / (G * np.sqrt(2)), SIGMA / (K_TRUE * np.sqrt(6))],
                               rtol=1e-6)
    assert an.chi2 < 1e-16 and an.dof == 4 and an.rank == 2
    assert an.as_dict()["K"] == pytest.approx(K_TRUE, rel=1e-12)
    assert an.std_dict()["b"] == pytest.approx(an.std[1])
    np.testing.assert_allclose(an.jacobian, p1_jac(an.estimate), rtol=1e-12)


@pytest.mark.slow
def test_p1_axis_model_monte_carlo_matches_reported_covariance() -> None:
    rng = np.random.default_rng(77)
    est = np.empty((N_MC, 2))
    for k in range(N_MC):
        a_out = K_TRUE * (A_REF + B_TRUE) + rng.normal(0.0, SIGMA, A_REF.size)
        sol = solve_nonlinear_lsq(p1_residuals(a_out), [1.0, 0.0], param_names=["K", "b"],
                                  sigma=SIGMA, jac=p1_jac)
        est[k] = sol.estimate
    err = (est - [K_TRUE, B_TRUE]) / sol.std
    assert np.all(np.abs(err.mean(axis=0)) < 4.0 / np.sqrt(N_MC))
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], N_MC - 1) / (N_MC - 1)
    ratio = err.var(axis=0, ddof=1)
    assert np.all((ratio > lo) & (ratio < hi)), ratio


# -- gravity-norm (Tedaldi / Shin) accelerometer calibration, docs/equations.md §12 --------------
def fibonacci_up(k: int) -> np.ndarray:
    i = np.arange(k) + 0.5
    polar = np.arccos(1.0 - 2.0 * i / k)
    azim = np.pi * (1.0 + np.sqrt(5.0)) * i
    return np.column_stack([np.sin(polar) * np.cos(azim), np.sin(polar) * np.sin(azim),
                            np.cos(polar)])


def norm_model_matrix(x: np.ndarray) -> np.ndarray:
    """I + diag(s) + upper-triangular non-orthogonality (α_yz, α_zy, α_zx)."""
    A = np.eye(3) + np.diag(x[3:6])
    A[0, 1], A[0, 2], A[1, 2] = x[6], x[7], x[8]
    return A


def norm_residuals(y: np.ndarray):
    def fn(x: np.ndarray) -> np.ndarray:
        f = np.linalg.solve(norm_model_matrix(x), (y - x[:3]).T).T
        return np.linalg.norm(f, axis=1) - G
    return fn


NORM_NAMES = ["b_x", "b_y", "b_z", "s_x", "s_y", "s_z", "a_yz", "a_zy", "a_zx"]
NORM_TRUTH = np.array([2e-3, -1e-3, 3e-3, 400e-6, -300e-6, 200e-6, 0.5e-3, -0.3e-3, 0.2e-3]) \
    * np.array([G, G, G, 1, 1, 1, 1, 1, 1])


def norm_data(k: int, rng: np.random.Generator | None) -> np.ndarray:
    f = G * fibonacci_up(k)
    y = (norm_model_matrix(NORM_TRUTH) @ f.T).T + NORM_TRUTH[:3]
    return y if rng is None else y + rng.normal(0.0, SIGMA, y.shape)


def test_gravity_norm_covariance_equals_crlb_with_unknown_orientations() -> None:
    # At the truth, the norm model's covariance is the Schur-complement CRLB of the full model
    # with two nuisance angles per pose (the norm keeps only the radial noise component).
    k = 24
    up = fibonacci_up(k)
    sol = solve_nonlinear_lsq(norm_residuals(norm_data(k, None)), np.zeros(9),
                              param_names=NORM_NAMES, sigma=SIGMA)
    np.testing.assert_allclose(sol.estimate, NORM_TRUTH, rtol=1e-7, atol=1e-12)
    # linearise y = A·g·u(angles) + b about the truth; columns: 9 parameters + 2 angles per pose
    polar = np.arccos(up[:, 2])
    azim = np.arctan2(up[:, 1], up[:, 0])
    A = norm_model_matrix(NORM_TRUTH)
    J = np.zeros((3 * k, 9 + 2 * k))
    for j in range(k):
        f = G * up[j]
        rows = slice(3 * j, 3 * j + 3)
        J[rows, :3] = np.eye(3)
        J[rows, 3:6] = np.diag(f)
        J[3 * j, 6], J[3 * j, 7], J[3 * j + 1, 8] = f[1], f[2], f[2]
        d_polar = G * np.array([np.cos(polar[j]) * np.cos(azim[j]),
                                np.cos(polar[j]) * np.sin(azim[j]), -np.sin(polar[j])])
        d_azim = G * np.array([-np.sin(polar[j]) * np.sin(azim[j]),
                               np.sin(polar[j]) * np.cos(azim[j]), 0.0])
        J[rows, 9 + j] = A @ d_polar
        J[rows, 9 + k + j] = A @ d_azim
    names = [*NORM_NAMES, *(f"polar_{j}" for j in range(k)), *(f"azim_{j}" for j in range(k))]
    bound = compute_crlb(J, SIGMA**2, param_names=names, nuisance=names[9:])
    np.testing.assert_allclose(sol.std, bound.std, rtol=2e-3)


@pytest.mark.slow
def test_gravity_norm_monte_carlo_closed_loop() -> None:
    rng = np.random.default_rng(8)
    n = 200
    err = np.empty((n, 9))
    for r in range(n):
        sol = solve_nonlinear_lsq(norm_residuals(norm_data(24, rng)), np.zeros(9),
                                  param_names=NORM_NAMES, sigma=SIGMA)
        err[r] = (sol.estimate - NORM_TRUTH) / sol.std
    assert np.all(np.abs(err) < 5.0)
    assert np.all(np.abs(err.mean(axis=0)) < 4.0 / np.sqrt(n))
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n - 1) / (n - 1)
    ratio = err.var(axis=0, ddof=1)
    assert np.all((ratio > lo) & (ratio < hi)), ratio


def test_gravity_norm_six_poses_is_not_identifiable() -> None:
    y = norm_data(6, np.random.default_rng(0))
    with pytest.raises(InsufficientExcitationError,
                       match=r"Jacobian at the solution cannot determine all parameters "
                             r"\(expected full rank 9 .*got rank 6 of 9") as info:
        solve_nonlinear_lsq(norm_residuals(y), np.zeros(9), param_names=NORM_NAMES, sigma=SIGMA)
    assert len(info.value.unobservable) >= 3


def test_unknown_noise_scales_by_variance_factor() -> None:
    rng = np.random.default_rng(4)
    y = norm_data(40, rng)
    known = solve_nonlinear_lsq(norm_residuals(y), np.zeros(9), param_names=NORM_NAMES,
                                sigma=SIGMA)
    unknown = solve_nonlinear_lsq(norm_residuals(y), np.zeros(9), param_names=NORM_NAMES)
    assert unknown.covariance_scaled and not known.covariance_scaled
    np.testing.assert_allclose(unknown.std, known.std * np.sqrt(known.variance_factor),
                               rtol=1e-5)
    assert known.variance_factor == pytest.approx(1.0, abs=0.6)


def test_evaluation_limit_raises_convergence_error() -> None:
    y = norm_data(24, np.random.default_rng(1))
    with pytest.raises(ConvergenceError, match=r"did not converge \(expected status 1–4; got 0"):
        solve_nonlinear_lsq(norm_residuals(y), np.zeros(9), param_names=NORM_NAMES, sigma=SIGMA,
                            max_evaluations=2)


def test_bounds_are_respected() -> None:
    a_out = K_TRUE * (A_REF + B_TRUE)
    sol = solve_nonlinear_lsq(p1_residuals(a_out), [1.0, 0.0], param_names=["K", "b"],
                              sigma=SIGMA, bounds=([0.5, -1.0], [1.0 + 100e-6, 1.0]))
    assert sol.estimate[0] <= 1.0 + 100e-6 + 1e-15


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"x0": [[1.0, 0.0]]}, r"`x0` must have shape \(p,\) with p ≥ 1; got \(1, 2\)"),
        ({"x0": [1.0, np.nan]}, r"`x0` must be finite"),
        ({"param_names": ["K"]}, r"`param_names` must have 2 entries"),
        ({"fn": lambda x: np.array([np.nan, 1.0, 2.0])},
         r"`residual_fn` must return finite values; got 1 NaN"),
        ({"fn": lambda x: np.ones((3, 2))},
         r"`residual_fn` must return shape \(m,\); got \(3, 2\)"),
        ({"jac": lambda x: np.ones((6, 3))}, r"`jac` must return shape \(6, 2\); got \(6, 3\)"),
        ({"sigma": [1.0, 2.0]}, r"`sigma` must be a scalar or have shape \(6,\); got \(2,\)"),
        ({"sigma": None, "fn": lambda x: np.array([x[0] - 1.0, x[1]])},
         r"needs more residuals than parameters; got m = 2, p = 2"),
    ],
)
def test_bad_inputs_raise_with_messages(kwargs: dict, match: str) -> None:
    a_out = K_TRUE * (A_REF + B_TRUE)
    args = {"fn": p1_residuals(a_out), "x0": [1.0, 0.0], "param_names": ["K", "b"],
            "sigma": SIGMA}
    args.update(kwargs)
    fn, x0 = args.pop("fn"), args.pop("x0")
    with pytest.raises(InvalidInputError, match=match):
        solve_nonlinear_lsq(fn, x0, **args)
