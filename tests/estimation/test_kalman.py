"""Tests of imucalib.estimation.kalman: pure functions, stateful twin, agreement with WLS."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation import (
    KalmanFilter,
    build_triad_design,
    kf_predict,
    kf_update,
    refine_with_kalman,
    solve_weighted_lsq,
)


def test_scalar_update_by_hand() -> None:
    # x = 0, P = 4, z = 2, R = 1: K = 0.8, x⁺ = 1.6, P⁺ = 0.8, S = 5, NIS = 4/5
    upd = kf_update([0.0], [[4.0]], [2.0], 1.0, [[1.0]])
    np.testing.assert_allclose(upd.K, [[0.8]])
    np.testing.assert_allclose(upd.x, [1.6])
    np.testing.assert_allclose(upd.P, [[0.8]])
    np.testing.assert_allclose(upd.S, [[5.0]])
    assert upd.nis == pytest.approx(0.8)
    np.testing.assert_allclose(upd.innovation, [2.0])


def test_predict_with_transition_and_process_noise() -> None:
    F = np.array([[1.0, 0.1], [0.0, 1.0]])
    Q = np.diag([1e-4, 1e-2])
    P = np.array([[2.0, 0.3], [0.3, 1.0]])
    x, Pp = kf_predict([1.0, 2.0], P, F, Q)
    np.testing.assert_allclose(x, [1.2, 2.0])
    np.testing.assert_allclose(Pp, F @ P @ F.T + Q)
    x0, P0 = kf_predict([1.0, 2.0], P)  # static state: unchanged
    np.testing.assert_allclose(x0, [1.0, 2.0])
    np.testing.assert_allclose(P0, P)


def test_joseph_update_matches_textbook_form_and_stays_symmetric() -> None:
    rng = np.random.default_rng(0)
    n, k = 5, 3
    A = rng.normal(size=(n, n))
    P = A @ A.T + np.eye(n)
    H = rng.normal(size=(k, n))
    R = np.diag(rng.uniform(0.1, 1.0, k))
    upd = kf_update(rng.normal(size=n), P, rng.normal(size=k), R, H)
    np.testing.assert_allclose(upd.P, (np.eye(n) - upd.K @ H) @ P, rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(upd.P, upd.P.T)
    assert np.linalg.eigvalsh(upd.P).min() > 0


def test_stateful_twin_equals_pure_functions() -> None:
    rng = np.random.default_rng(1)
    F, Q = np.array([[1.0, 0.01], [0.0, 1.0]]), np.eye(2) * 1e-3
    kf = KalmanFilter([0.0, 0.0], np.eye(2), F=F, Q=Q)
    x, P = np.zeros(2), np.eye(2)
    for _ in range(5):
        z, H = rng.normal(size=1), np.array([[1.0, 0.0]])
        kf.predict()
        kf.update(z, 0.5, H)
        x, P = kf_predict(x, P, F, Q)
        upd = kf_update(x, P, z, 0.5, H)
        x, P = upd.x, upd.P
    np.testing.assert_allclose(kf.x, x)
    np.testing.assert_allclose(kf.P, P)
    assert kf.last_update is not None and kf.last_update.nis == pytest.approx(upd.nis)


def _position_blocks(kit: SimpleNamespace, truth, up: np.ndarray, rng: np.random.Generator,
                     sigma: np.ndarray):
    z, x = kit.observations(truth, up, rng, sigma=0.0)
    z = z + rng.normal(0.0, 1.0, z.size) * sigma
    d = build_triad_design(x)
    n = up.shape[0]
    H_blocks = [d.H[3 * k: 3 * k + 3] for k in range(n)]
    z_blocks = [z[3 * k: 3 * k + 3] for k in range(n)]
    R_blocks = [np.diag(sigma[3 * k: 3 * k + 3] ** 2) for k in range(n)]
    return d, z, H_blocks, z_blocks, R_blocks


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_diffuse_static_filter_agrees_with_wls(kit: SimpleNamespace, truth, six_up,
                                               seed: int) -> None:
    rng = np.random.default_rng(seed)
    up = np.vstack([six_up, six_up[rng.permutation(6)]])  # 12 positions, shuffled repeat
    sigma = kit.SIGMA * rng.uniform(0.5, 2.0, 3 * up.shape[0])
    d, z, Hb, zb, Rb = _position_blocks(kit, truth, up, rng, sigma)
    wls = solve_weighted_lsq(d.H, z, param_names=d.param_names, sigma=sigma)
    kf = refine_with_kalman(Hb, zb, Rb, param_names=d.param_names)
    assert kf.diffuse_prior
    # agreement far inside the uncertainty (the diffuse prior holds 1e-8 of the information)
    assert np.max(np.abs(kf.estimate - wls.estimate) / wls.std) < 1e-5
    np.testing.assert_allclose(kf.std, wls.std, rtol=1e-5)
    np.testing.assert_allclose(kf.covariance, wls.covariance, rtol=1e-4,
                               atol=1e-6 * np.abs(wls.covariance).max())
    # Σ NIS over the blocks is the WLS χ²
    assert kf.nis_total == pytest.approx(wls.chi2, rel=1e-4)
    assert kf.nis.shape == (12,) and np.all(kf.nis_dof == 3)
    np.testing.assert_allclose(kf.estimate_history[-1], kf.estimate)
    # block order does not matter for a static state
    order = rng.permutation(len(Hb))
    kf2 = refine_with_kalman([Hb[i] for i in order], [zb[i] for i in order],
                             [Rb[i] for i in order], param_names=d.param_names)
    assert np.max(np.abs(kf2.estimate - kf.estimate) / wls.std) < 1e-5


def test_informative_prior_equals_wls_with_prior_pseudo_observations(kit: SimpleNamespace,
                                                                     truth, six_up) -> None:
    rng = np.random.default_rng(3)
    sigma = np.full(18, kit.SIGMA)
    d, z, Hb, zb, Rb = _position_blocks(kit, truth, six_up, rng, sigma)
    x0 = kit.truth_vector(truth) + rng.normal(0, 1e-4, 12)
    sd0 = np.full(12, 1e-4)
    kf = refine_with_kalman(Hb, zb, Rb, param_names=d.param_names, prior_mean=x0,
                            prior_covariance=sd0**2)
    H_aug = np.vstack([d.H, np.eye(12)])
    z_aug = np.concatenate([z, x0])
    wls = solve_weighted_lsq(H_aug, z_aug, param_names=d.param_names,
                             sigma=np.concatenate([sigma, sd0]))
    np.testing.assert_allclose(kf.estimate, wls.estimate, rtol=0, atol=1e-9 * wls.std.min())
    np.testing.assert_allclose(kf.covariance, wls.covariance, rtol=1e-8,
                               atol=1e-10 * np.abs(wls.covariance).max())
    assert not kf.diffuse_prior


def test_process_noise_inflates_uncertainty(kit: SimpleNamespace, truth, six_up) -> None:
    rng = np.random.default_rng(4)
    sigma = np.full(18, kit.SIGMA)
    d, _, Hb, zb, Rb = _position_blocks(kit, truth, six_up, rng, sigma)
    static = refine_with_kalman(Hb, zb, Rb, param_names=d.param_names)
    tiny = refine_with_kalman(Hb, zb, Rb, param_names=d.param_names,
                              process_noise=np.full(12, 1e-30))
    wander = refine_with_kalman(Hb, zb, Rb, param_names=d.param_names,
                                process_noise=(0.5 * static.std) ** 2)
    np.testing.assert_allclose(tiny.estimate, static.estimate, rtol=0,
                               atol=1e-4 * static.std.min())
    assert np.all(wander.std > static.std)


@pytest.mark.slow
def test_nis_is_chi2_distributed(kit: SimpleNamespace, truth, six_up) -> None:
    rng = np.random.default_rng(5)
    sigma = np.full(36, kit.SIGMA)
    up = np.vstack([six_up, six_up])
    nis = []
    for _ in range(200):
        d, _, Hb, zb, Rb = _position_blocks(kit, truth, up, rng, sigma)
        x0 = kit.truth_vector(truth) + rng.normal(0, 2e-4, 12) * np.r_[[kit.G] * 3, [1] * 9]
        P0 = np.diag((2e-4 * np.r_[[kit.G] * 3, [1] * 9]) ** 2)
        res = refine_with_kalman(Hb, zb, Rb, param_names=d.param_names, prior_mean=x0,
                                 prior_covariance=P0)
        nis.append(res.nis)
    nis_arr = np.array(nis)
    # with a correct prior every block's NIS is χ²(3): mean 3, variance 6
    assert nis_arr.mean() == pytest.approx(3.0, abs=4 * np.sqrt(6.0 / nis_arr.size))


def test_diffuse_prior_with_rank_deficient_blocks_raises(kit: SimpleNamespace, truth,
                                                         six_up) -> None:
    sigma = np.full(12, kit.SIGMA)
    d, _, Hb, zb, Rb = _position_blocks(kit, truth, six_up[[0, 1, 4, 5]],
                                        np.random.default_rng(0), sigma)
    with pytest.raises(InsufficientExcitationError,
                       match=r"stacked Kalman measurement design .*rank 9 of 12.*"
                             r"unobservable: M_xx, M_yx, M_zx$"):
        refine_with_kalman(Hb, zb, Rb, param_names=d.param_names)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: kf_update([0.0, 1.0], np.eye(3), [1.0], 1.0, [[1.0, 0.0]]),
         r"`P` must have shape \(2, 2\); got \(3, 3\)"),
        (lambda: kf_update([0.0], [[1.0]], [1.0, 2.0], 1.0, [[1.0]]),
         r"`H` must have shape \(2, 1\); got \(1, 1\)"),
        (lambda: kf_update([0.0], [[1.0]], [1.0], [[-2.0]], [[1.0]]),
         r"innovation covariance S = H·P·Hᵀ \+ R must be positive definite"),
        (lambda: kf_update([0.0], [[1.0]], [np.nan], 1.0, [[1.0]]), r"`z` must be finite"),
        (lambda: kf_update([0.0], [[1.0]], [1.0], [1.0, 2.0], [[1.0]]),
         r"`R` must have shape \(1,\) or \(1, 1\); got \(2,\)"),
        (lambda: kf_predict([0.0], [[1.0]], np.eye(2)), r"`F` must have shape \(1, 1\)"),
        (lambda: refine_with_kalman([np.eye(2)], [[1.0, 2.0]], [], param_names=["a", "b"]),
         r"must have the same length; got 1, 1, 0"),
        (lambda: refine_with_kalman([], [], [], param_names=[]), r"at least one block; got none"),
        (lambda: refine_with_kalman([np.eye(2), np.eye(3)], [[1, 2], [1, 2, 3]], [1.0, 1.0],
                                    param_names=["a", "b"]),
         r"`H_blocks\[1\]` must have 2 columns; got 3"),
        (lambda: refine_with_kalman([np.eye(2)], [[1.0, 2.0]], [[[1.0, 2.0], [2.0, 1.0]]],
                                    param_names=["a", "b"]),
         r"`R_blocks\[0\]` must be positive definite; got smallest eigenvalue -1"),
        (lambda: refine_with_kalman([np.eye(2)], [[1.0, 2.0]], [1.0], param_names=["a", "b"],
                                    prior_covariance=[[1.0, 0.0], [0.0, -1.0]]),
         r"`prior_covariance` must be positive definite; got smallest eigenvalue -1"),
    ],
)
def test_bad_inputs_raise_with_messages(call, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        call()
