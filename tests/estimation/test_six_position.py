"""The nominal six-position accelerometer fit (estimation/six_position.py, Eqs. (F.11)–(F.12))."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.six_position import fit_six_position, nominal_directions

G = 9.80665
B = np.array([0.05, -0.03, 0.08])
M = np.array([[2e-3, 1e-3, -2e-3], [-1.5e-3, -1e-3, 3e-3], [2.5e-3, -0.5e-3, 1.5e-3]])
FACES = np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]], float)


def _outputs(d: np.ndarray, m: np.ndarray = M) -> np.ndarray:
    return B + (G * d) @ (np.eye(3) + m).T


def test_noise_free_faces_give_the_truth_and_the_nearest_axes():
    y = _outputs(FACES)
    np.testing.assert_array_equal(nominal_directions(y), FACES)
    fit = fit_six_position(y, np.full_like(y, 1e-4), FACES, G)
    np.testing.assert_allclose(fit.bias, B, atol=1e-12)
    np.testing.assert_allclose(fit.scale_misalignment, M, atol=1e-12)
    assert fit.quality.chi2 == pytest.approx(0.0, abs=1e-12)


def test_sigma_matches_the_monte_carlo_spread_and_g_type_b_is_carried():
    rng = np.random.default_rng(3)
    sy = np.full((6, 3), 2e-4)
    values, sigmas = [], []
    for _ in range(400):
        y = _outputs(FACES) + rng.normal(0.0, 2e-4, (6, 3))
        fit = fit_six_position(y, sy, FACES, G)
        values.append(fit.values)
        sigmas.append(np.sqrt(np.diag(fit.covariance_noise)))
    spread = np.std(values, axis=0, ddof=1)
    np.testing.assert_allclose(spread / np.mean(sigmas, axis=0), 1.0, atol=0.15)
    with_g = fit_six_position(_outputs(FACES), sy, FACES, G, gravity_std_mps2=0.01)
    # ∂M/∂g = −(I + M)/g: the diagonal gains (0.01/g)² of variance, the bias nothing
    extra = np.diag(with_g.covariance) - np.diag(fit_six_position(_outputs(FACES), sy, FACES,
                                                                  G).covariance)
    np.testing.assert_allclose(extra[[3, 7, 11]], ((1 + np.diag(M)) * 0.01 / G) ** 2,
                               rtol=1e-6)
    assert np.all(np.abs(extra[:3]) < 1e-18)


def test_a_pose_off_its_face_is_a_misfit_and_the_scaled_sigma_grow():
    tilt = np.radians(0.5)
    d_true = FACES.copy()
    d_true[2] = [np.cos(tilt), 0.0, np.sin(tilt)]
    y = _outputs(d_true)
    fit = fit_six_position(y, np.full((6, 3), 2e-5), FACES, G)
    assert fit.quality.misfit
    np.testing.assert_allclose(np.diag(fit.covariance),
                               np.diag(fit.covariance_noise) * fit.quality.reduced_chi2)


def test_bad_designs_and_inputs_are_refused():
    y = _outputs(FACES[:4])
    with pytest.raises(InsufficientExcitationError, match="do not separate"):
        fit_six_position(y, np.full_like(y, 1e-4), FACES[:4], G)
    y6 = _outputs(FACES)
    with pytest.raises(InvalidInputError, match="unit vectors"):
        fit_six_position(y6, np.full_like(y6, 1e-4), 2 * FACES, G)
    with pytest.raises(InvalidInputError, match="nearest axis"):
        nominal_directions(_outputs(np.array([[0.6, 0.0, 0.8]])))


def test_k2_is_separated_by_the_six_faces():
    k2 = np.array([1e-4, -5e-5, 8e-5])
    y = _outputs(FACES) + k2 * (G * FACES) ** 2
    y7 = np.vstack([y, y[0]])
    faces7 = np.vstack([FACES, FACES[0]])
    fit = fit_six_position(y7, np.full((7, 3), 1e-4), faces7, G, k2=True)
    np.testing.assert_allclose(fit.bias, B, atol=1e-10)
    np.testing.assert_allclose(fit.k2, k2, atol=1e-12)
    plain = fit_six_position(y, np.full((6, 3), 1e-5), FACES, G)
    np.testing.assert_allclose(plain.bias, B + k2 * G**2 / 3, atol=1e-10)   # K2 in the bias
    with pytest.raises(InsufficientExcitationError, match="K2_x"):
        keep = [0, 1, 2, 2, 4, 5]                                    # no −x face
        fit_six_position(y[keep], np.full((6, 3), 1e-4), FACES[keep], G, k2=True)
