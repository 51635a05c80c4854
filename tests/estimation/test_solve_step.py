"""The lean solve of an iteration (estimation.linear.solve_step) and the solver's core
residuals: the one solver's estimate, covariance, residuals and χ² bit for bit, its errors the
same (docs/performance.md, "Field calibration: the fits' fixed costs")."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.gravity_norm import fit_gravity_norm
from imucalib.estimation.linear import _checked, _solve_known, solve_step, solve_weighted_lsq
from imucalib.estimation.six_position import fit_six_position, nominal_directions


def _problem(m: int, p: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    # columns many orders of magnitude apart, as a Jacobian's (biases next to angles)
    H = rng.normal(size=(m, p)) * np.logspace(-3, 3, p)
    sig = rng.uniform(0.1, 3.0, m)
    z = H @ rng.normal(size=p) + rng.normal(0.0, sig)
    return H, z, sig


@pytest.mark.parametrize(("m", "p"), [(5, 5), (9, 6), (40, 9), (200, 15)])
@pytest.mark.parametrize("noise", ["sigma", "weights", "variances", "full", "none"])
def test_the_step_is_the_solvers_estimate_bit_for_bit(m: int, p: int, noise: str) -> None:
    H, z, sig = _problem(m, p, 7 * m + p)
    names = [f"x{i}" for i in range(p)]
    rng = np.random.default_rng(m)
    a = rng.normal(size=(m, m)) * 0.1
    kw = {"sigma": {"sigma": sig}, "weights": {"weights": sig**-2},
          "variances": {"covariance": sig**2},
          "full": {"covariance": np.diag(sig**2) + a @ a.T}, "none": {}}[noise]
    full = solve_weighted_lsq(H, z, param_names=names, scale_covariance=False, **kw)
    step = solve_step(H, z, param_names=names, **kw)
    assert step.tobytes() == full.estimate.tobytes()
    assert not step.flags.writeable


def test_the_core_returns_the_solvers_residuals_and_chi2_bit_for_bit() -> None:
    H, z, sig = _problem(30, 7, 3)
    names = [f"x{i}" for i in range(7)]
    full = solve_weighted_lsq(H, z, param_names=names, sigma=sig)
    args = _checked(H, z, names, None, None, sig)
    core = _solve_known(args[0], args[1], args[3], args[2])
    assert core.residuals is not None
    assert core.residuals.tobytes() == full.residuals.tobytes()
    assert core.covariance_noise.tobytes() == full.covariance_noise.tobytes()
    assert core.chi2 == full.chi2


def test_the_step_refuses_what_the_solver_refuses_with_the_same_message() -> None:
    H, z, sig = _problem(12, 4, 5)
    names = ["a", "b", "c", "d"]
    H[:, 3] = 2.0 * H[:, 1]  # two columns that only their sum is seen of
    with pytest.raises(InsufficientExcitationError) as full:
        solve_weighted_lsq(H, z, param_names=names, sigma=sig, context="the design",
                           advice="add poses")
    with pytest.raises(InsufficientExcitationError) as step:
        solve_step(H, z, param_names=names, sigma=sig, context="the design", advice="add poses")
    assert str(step.value) == str(full.value)
    assert "add poses" in str(step.value)
    bad = z.copy()
    bad[3] = np.nan
    with pytest.raises(InvalidInputError, match="finite"):
        solve_step(H[:, :3], bad, param_names=names[:3], sigma=sig)
    with pytest.raises(InvalidInputError):
        solve_step(H[:, :3], z, param_names=names[:3], sigma=-sig)


def _gravity_poses(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    up = rng.normal(size=(n, 3))
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    g = 9.80665
    b, s = np.array([0.05, -0.03, 0.08]), np.array([2e-3, -1e-3, 3e-3])
    y = g * up / (1.0 + s) + b + rng.normal(0.0, 1e-3, (n, 3))
    return y, np.full((n, 3), 1e-3)


def _reference_gravity_fit(y: np.ndarray, sy: np.ndarray, g: float) -> tuple[np.ndarray, ...]:
    """(F.2) by Gauss–Newton with the full solver at every step: the code before the lean step."""
    from imucalib.estimation.gravity_norm import PARAMETERS, _jacobian

    p = np.zeros(9)
    for _ in range(50):
        a, j = _jacobian(p, y)
        u = a / np.linalg.norm(a, axis=1, keepdims=True)
        sr = np.sqrt(np.sum((u * sy) ** 2, axis=1))
        r = np.linalg.norm(a, axis=1) - g
        step = solve_weighted_lsq(j, -r, sigma=sr, param_names=PARAMETERS,
                                  context="gravity-norm Jacobian").estimate
        p = p + step
        if np.max(np.abs(step)) < 1e-12:
            break
    a, j = _jacobian(p, y)
    u = a / np.linalg.norm(a, axis=1, keepdims=True)
    sr = np.sqrt(np.sum((u * sy) ** 2, axis=1))
    r = np.linalg.norm(a, axis=1) - g
    cov = solve_weighted_lsq(j, -r, sigma=sr, param_names=PARAMETERS).covariance_noise
    return p, cov, r


def test_the_gravity_norm_fit_is_the_full_solvers_bit_for_bit() -> None:
    y, sy = _gravity_poses(24, 11)
    fit = fit_gravity_norm(y, sy, 9.80665)
    p, cov, r = _reference_gravity_fit(y, sy, 9.80665)
    assert fit.values.tobytes() == p.tobytes()
    assert fit.covariance_noise.tobytes() == cov.tobytes()
    assert fit.residuals.tobytes() == r.tobytes()
    # and against the truth it was made from (σ of the mean outputs 1e-3 m/s²)
    np.testing.assert_allclose(fit.values[:3], [0.05, -0.03, 0.08], atol=5 * 1e-3)


def test_the_six_position_fit_is_the_full_solvers_bit_for_bit() -> None:
    g = 9.80665
    faces = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1],
                      [1, 0, 0]], dtype=float)
    rng = np.random.default_rng(2)
    m = np.array([[2e-3, 1e-4, 0.0], [0.0, -1e-3, 2e-4], [0.0, 0.0, 3e-3]])
    y = np.array([0.05, -0.02, 0.1]) + g * faces @ (np.eye(3) + m).T
    y = y + rng.normal(0.0, 1e-3, y.shape)
    sy = np.full(y.shape, 1e-3)
    d = nominal_directions(y)
    fit = fit_six_position(y, sy, d, g, k2=False)
    a = np.column_stack([np.ones(len(y)), g * d])
    for i in range(3):
        ref = solve_weighted_lsq(a, y[:, i] - g * d[:, i], sigma=sy[:, i],
                                 param_names=["b", "m0", "m1", "m2"])
        idx = [i, 3 + 3 * i, 4 + 3 * i, 5 + 3 * i]
        assert fit.values[idx].tobytes() == ref.estimate.tobytes()
        assert fit.covariance_noise[np.ix_(idx, idx)].tobytes() == \
            ref.covariance_noise.tobytes()
        assert fit.residuals[:, i].tobytes() == ref.residuals.tobytes()
    np.testing.assert_allclose(fit.bias, [0.05, -0.02, 0.1], atol=5e-3)
