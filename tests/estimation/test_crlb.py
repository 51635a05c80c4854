"""Tests of imucalib.estimation.crlb: generic bound vs the closed forms of docs/equations.md §12."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from imucalib import units
from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation import (
    SIX_POSITION_UP_B,
    build_triad_design,
    compute_crlb,
    compute_rate_table_gyro_crlb,
    compute_six_position_accel_crlb,
    compute_sphere_accel_crlb,
)

G = units.G0_MPS2
SIGMA = 67.1 * units.UG  # 150 µg/√Hz over 5 s (docs/equations.md §12 worked example)


def test_generic_bound_equals_six_position_closed_form() -> None:
    d = build_triad_design(G * SIX_POSITION_UP_B)
    bound = compute_crlb(d.H, SIGMA**2, param_names=d.param_names)
    closed = compute_six_position_accel_crlb(SIGMA, gravity_mps2=G)
    np.testing.assert_allclose(bound.std[:3], closed.bias_std_mps2, rtol=1e-12)
    np.testing.assert_allclose(bound.std[3:], closed.scale_misalignment_std, rtol=1e-12)
    # the worked example: 27.4 µg and 47.4 ppm = 9.8 arcsec
    assert closed.bias_std_mps2 / units.UG == pytest.approx(27.4, abs=0.05)
    assert closed.scale_misalignment_std / units.PPM == pytest.approx(47.4, abs=0.05)
    assert closed.scale_misalignment_std / units.ARCSEC == pytest.approx(9.8, abs=0.05)
    # information and bound are inverse; F = HᵀH/σ²
    np.testing.assert_allclose(bound.information @ bound.covariance, np.eye(12), atol=1e-9)
    np.testing.assert_allclose(bound.fisher_information, d.H.T @ d.H / SIGMA**2, rtol=1e-12,
                               atol=1e-12 * bound.fisher_information.max())
    assert bound.std_dict()["M_yz"] == pytest.approx(closed.scale_misalignment_std, rel=1e-12)


def _cube_vertices() -> np.ndarray:
    return np.array(list(itertools.product([-1.0, 1.0], repeat=3))) / np.sqrt(3.0)


def _icosahedron() -> np.ndarray:
    phi = (1 + np.sqrt(5.0)) / 2
    v = []
    for a, b in itertools.product([-1.0, 1.0], repeat=2):
        v += [[0, a, b * phi], [a, b * phi, 0], [b * phi, 0, a]]
    v = np.array(v, dtype=float)
    return v / np.linalg.norm(v, axis=1, keepdims=True)


@pytest.mark.parametrize("up", [SIX_POSITION_UP_B, _cube_vertices(), _icosahedron()],
                         ids=["octahedron", "cube", "icosahedron"])
def test_generic_bound_equals_spherical_design_closed_form(up: np.ndarray) -> None:
    d = build_triad_design(G * up)
    bound = compute_crlb(d.H, SIGMA**2, param_names=d.param_names)
    closed = compute_sphere_accel_crlb(SIGMA, up.shape[0], gravity_mps2=G)
    np.testing.assert_allclose(bound.std[:3], closed.bias_std_mps2, rtol=1e-12)
    np.testing.assert_allclose(bound.std[3:], closed.scale_misalignment_std, rtol=1e-12)


def test_fibonacci_24_is_close_to_sphere_closed_form() -> None:
    k = 24
    i = np.arange(k) + 0.5
    polar, azim = np.arccos(1 - 2 * i / k), np.pi * (1 + np.sqrt(5.0)) * i
    up = np.column_stack([np.sin(polar) * np.cos(azim), np.sin(polar) * np.sin(azim),
                          np.cos(polar)])
    d = build_triad_design(G * up)
    bound = compute_crlb(d.H, SIGMA**2, param_names=d.param_names)
    closed = compute_sphere_accel_crlb(SIGMA, k, gravity_mps2=G)
    # docs/equations.md §12: 13.7 µg and 23.7 ppm
    assert closed.bias_std_mps2 / units.UG == pytest.approx(13.7, abs=0.05)
    assert closed.scale_misalignment_std / units.PPM == pytest.approx(23.7, abs=0.05)
    np.testing.assert_allclose(bound.std[:3], closed.bias_std_mps2, rtol=0.02)
    np.testing.assert_allclose(bound.std[3:], closed.scale_misalignment_std, rtol=0.05)


@pytest.mark.parametrize(
    ("rates_dps", "dwell_s"),
    [([100.0, -100.0], 10.0), ([-100, -50, 0, 50, 100], [10, 12, 20, 12, 10]),
     ([5.0, 12.5, 60.0], [30.0, 20.0, 10.0])],
)
def test_generic_bound_equals_rate_table_closed_form(rates_dps, dwell_s) -> None:
    n_density = 0.005 * units.DEG  # 0.005 (°/s)/√Hz
    w = np.asarray(rates_dps, dtype=float) * units.DEG
    t = np.broadcast_to(np.asarray(dwell_s, dtype=float), w.shape)
    closed = compute_rate_table_gyro_crlb(n_density, w, dwell_s)
    H = np.column_stack([np.ones_like(w), w])  # y = b + (1 + s)·ω: ∂/∂b = 1, ∂/∂s = ω
    bound = compute_crlb(H, n_density**2 / t, param_names=["b", "s"])
    np.testing.assert_allclose(bound.std, [closed.bias_std_rps, closed.scale_std], rtol=1e-10)


def test_symmetric_rate_design_reduces_to_n_over_root_t() -> None:
    n_density, rate = 0.005 * units.DEG, 100 * units.DEG
    closed = compute_rate_table_gyro_crlb(n_density, [rate, -rate], 10.0)
    assert closed.bias_std_rps == pytest.approx(n_density / np.sqrt(20.0), rel=1e-12)
    assert closed.scale_std == pytest.approx(n_density / (rate * np.sqrt(20.0)), rel=1e-12)
    assert closed.scale_std / units.PPM == pytest.approx(11.2, abs=0.05)  # "about 11 ppm"


# docs/equations.md §12, unknown orientation: σ(bias) µg, σ(scale) ppm, σ(non-orthogonality) µrad
UNKNOWN_ORIENTATION_TABLE = {24: (23.7, 33.5, 53.0), 36: (19.4, 27.3, 43.0),
                             50: (16.4, 23.2, 37.0)}


def _unknown_orientation_jacobian(k: int) -> tuple[np.ndarray, list[str]]:
    i = np.arange(k) + 0.5
    polar, azim = np.arccos(1 - 2 * i / k), np.pi * (1 + np.sqrt(5.0)) * i
    J = np.zeros((3 * k, 9 + 2 * k))
    for j in range(k):
        sp, cp, sa, ca = np.sin(polar[j]), np.cos(polar[j]), np.sin(azim[j]), np.cos(azim[j])
        f = G * np.array([sp * ca, sp * sa, cp])
        rows = slice(3 * j, 3 * j + 3)
        J[rows, :3] = np.eye(3)
        J[rows, 3:6] = np.diag(f)
        J[3 * j, 6], J[3 * j, 7], J[3 * j + 1, 8] = f[1], f[2], f[2]
        J[rows, 9 + j] = G * np.array([cp * ca, cp * sa, -sp])
        J[rows, 9 + k + j] = G * np.array([-sp * sa, sp * ca, 0.0])
    names = ["b_x", "b_y", "b_z", "s_x", "s_y", "s_z", "a_yz", "a_zy", "a_zx",
             *(f"polar_{j}" for j in range(k)), *(f"azim_{j}" for j in range(k))]
    return J, names


@pytest.mark.parametrize("k", sorted(UNKNOWN_ORIENTATION_TABLE))
def test_unknown_orientation_bound_reproduces_standards_table(k: int) -> None:
    J, names = _unknown_orientation_jacobian(k)
    bound = compute_crlb(J, SIGMA**2, param_names=names, nuisance=names[9:])
    assert bound.param_names == tuple(names[:9])
    assert bound.nuisance_names == tuple(names[9:])
    want_b, want_s, want_n = UNKNOWN_ORIENTATION_TABLE[k]
    assert bound.std[:3].mean() / units.UG == pytest.approx(want_b, rel=0.01)
    assert bound.std[3:6].mean() / units.PPM == pytest.approx(want_s, rel=0.01)
    assert bound.std[6:].mean() / units.URAD == pytest.approx(want_n, rel=0.02)


def test_unknown_orientation_six_poses_rank_18_of_21() -> None:
    J, names = _unknown_orientation_jacobian(6)
    with pytest.raises(InsufficientExcitationError, match=r"got rank 18 of 21"):
        compute_crlb(J, SIGMA**2, param_names=names, nuisance=names[9:])


def test_schur_complement_and_nuisance_cost() -> None:
    rng = np.random.default_rng(0)
    J = rng.normal(size=(30, 5))
    C = np.diag(rng.uniform(0.5, 2.0, 30))
    names = ["a", "b", "c", "n1", "n2"]
    full = compute_crlb(J, C, param_names=names)
    part = compute_crlb(J, C, param_names=names, nuisance=["n1", "n2"])
    F = J.T @ np.linalg.solve(C, J)
    schur = F[:3, :3] - F[:3, 3:] @ np.linalg.solve(F[3:, 3:], F[3:, :3])
    np.testing.assert_allclose(part.information, schur, rtol=1e-10)
    np.testing.assert_allclose(part.covariance, full.covariance[:3, :3], rtol=1e-10)
    # knowing the nuisance parameters would give the smaller bound F_θθ⁻¹
    known = np.sqrt(np.diag(np.linalg.inv(F[:3, :3])))
    assert np.all(part.std >= known - 1e-15)


def test_positively_correlated_noise_raises_bias_bound() -> None:
    # flicker-like correlation between position means raises the bound on the common bias
    d = build_triad_design(G * SIX_POSITION_UP_B)
    white = compute_crlb(d.H, SIGMA**2, param_names=d.param_names)
    C = SIGMA**2 * (np.eye(18) + 0.5 * np.kron(np.ones((6, 6)), np.eye(3)))  # common offset
    coloured = compute_crlb(d.H, C, param_names=d.param_names)
    np.testing.assert_allclose(coloured.covariance,
                               np.linalg.inv(d.H.T @ np.linalg.solve(C, d.H)), rtol=1e-9,
                               atol=1e-12 * coloured.covariance.max())
    assert np.all(coloured.std[:3] > white.std[:3] * 1.5)  # var 1/6 + 1/2: ×2 in σ
    np.testing.assert_allclose(coloured.std[3:], white.std[3:], rtol=1e-9)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: compute_crlb(np.eye(2), 1.0, param_names=["a", "b"], nuisance=["c"]),
         r"`nuisance` must name columns of `param_names`; got unknown \['c'\]"),
        (lambda: compute_crlb(np.eye(2), 1.0, param_names=["a", "b"], nuisance=["a", "b"]),
         r"at least one parameter must not be nuisance; got all 2 columns"),
        (lambda: compute_crlb(np.eye(2), -1.0, param_names=["a", "b"]),
         r"`covariance` must be > 0"),
        (lambda: compute_six_position_accel_crlb(0.0), r"`sigma_mps2` must be > 0; got 0.0"),
        (lambda: compute_sphere_accel_crlb(1e-4, 3), r"`n_positions` must be an integer ≥ 4; "
                                                      r"got 3"),
        (lambda: compute_rate_table_gyro_crlb(1e-4, [1.0, 1.0], 10.0),
         r"at least two distinct rates .*; got 1 distinct value"),
        (lambda: compute_rate_table_gyro_crlb(1e-4, [1.0, -1.0], [10.0, 0.0]),
         r"`dwell_s` must be > 0; got min 0"),
        (lambda: compute_rate_table_gyro_crlb(1e-4, [1.0, -1.0], [10.0, 1.0, 1.0]),
         r"`dwell_s` must be a scalar or have shape \(2,\); got \(3,\)"),
    ],
)
def test_bad_inputs_raise_with_messages(call, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        call()


def test_rank_deficient_design_names_parameters() -> None:
    d = build_triad_design(G * SIX_POSITION_UP_B[:4])  # no Y positions
    with pytest.raises(InsufficientExcitationError,
                       match=r"unobservable: M_xy, M_yy, M_zy$") as info:
        compute_crlb(d.H, SIGMA**2, param_names=d.param_names)
    assert info.value.unobservable == ("M_xy", "M_yy", "M_zy")
