"""The gyro drift model on static positions, fitted by generalised least squares.

Shared by the g-sensitivity test (docs/g-sensitivity.md, "The model and the fit") and the
random-drift test (docs/random-drift.md, "Processing"), which fits it once per repetition. Per
gyro axis i and static window k (docs/g-sensitivity.md, equations (1)–(4)):

    d_ik = ȳ_ik − [(I + M)·ω_k]_i = D0_i + D1_i·f_xk + D2_i·f_yk + D3_i·f_zk + e_ik        (1)

ω_k the reference Earth rate and f_k the reference specific force in the body frame, M the gyro
scale-misalignment taken as known (nominal: zero). Its error δm_i (row i, each element of
standard deviation σ_M, Type B) acts on the Earth rate as δm_i·ω_k, the same error in every
window through ω_k, so the observations' covariance is full:

    C_i = diag(σ_ik²) + σ_M²·Ω·Ωᵀ,  Ω the (n, 3) matrix of the ω_k                           (2)
    x̂_i = (AᵀC_i⁻¹A)⁻¹·AᵀC_i⁻¹·d_i,  cov x̂_i = (AᵀC_i⁻¹A)⁻¹,  A = [1, f_x, f_y, f_z]           (3)
    χ²_i = rᵀC_i⁻¹r with ν = n − 4; on a misfit (99 % quantile) cov x̂_i is scaled by R_B²    (4)

(3)–(4) are :func:`~imucalib.estimation.linear.solve_weighted_lsq` with the full covariance (2)
(its Eqs. (1), (2), (6), (7)). The three axes are independent (their noise and their δm_i are).
:func:`fit_windows` fits the model to the static windows of
:func:`~imucalib.procedures.common.static_windows.extract_static_windows` with the options of
:class:`GSensitivityOptions` (M taken as known, nominal zero, with a Type B standard
uncertainty per element, 1e-3 by default).

Contents
--------
:class:`GSensitivityOptions`, :class:`DriftFit`, :func:`fit_drift_model`, :func:`fit_windows`,
:func:`drift_parameter_names`
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.linear import solve_weighted_lsq
from imucalib.models.fit_quality import FitQuality
from imucalib.procedures.common.static_windows import StaticWindow

__all__ = ["DriftFit", "GSensitivityOptions", "drift_parameter_names", "fit_drift_model",
           "fit_windows"]

_F64 = NDArray[np.float64]
_AXES = "xyz"


def drift_parameter_names() -> list[str]:
    """Return the 12 triad names, row-major: gyro_bias_i, gyro_G_ix, gyro_G_iy, gyro_G_iz."""
    return [n for i in _AXES for n in (f"gyro_bias_{i}", *(f"gyro_G_{i}{j}" for j in _AXES))]


@dataclass(frozen=True)
class GSensitivityOptions:
    """Options of the drift-model fit (module docstring): the g-sensitivity and random-drift ones.

    Attributes
    ----------
    gravity_mps2 : float, optional
        Local g; normal gravity at the recorded latitude when omitted. [m/s²]
    scale_misalignment : 3×3 nested sequence, optional
        The gyro M (y = (I + M)·ω, rows sensor axes) taken as known; zero when omitted.
    scale_misalignment_std : float
        Type B standard uncertainty of each element of M. [1]
    noise_block_s : float
        Block length of the white-noise estimate. [s]
    """

    gravity_mps2: float | None = None
    scale_misalignment: Any = None
    scale_misalignment_std: float = 1e-3
    noise_block_s: float = 1.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.scale_misalignment_std) and self.scale_misalignment_std >= 0):
            raise InvalidInputError(f"`scale_misalignment_std` must be ≥ 0; got "
                                    f"{self.scale_misalignment_std!r}")
        if self.scale_misalignment is not None and np.shape(self.scale_misalignment) != (3, 3):
            raise InvalidInputError(f"`scale_misalignment` must be 3×3; got shape "
                                    f"{np.shape(self.scale_misalignment)}")


@dataclass(frozen=True)
class DriftFit:
    """The fitted drift model of the triad (module docstring).

    Attributes
    ----------
    coefficients : ndarray, shape (3, 4)
        Row i: D0_i [rad/s], D1_i, D2_i, D3_i [rad/s per m/s²].
    covariance : ndarray, shape (12, 12)
        Of the coefficients in row-major order (σ scaled by R_B on a misfit).
    fits : tuple of FitQuality
        χ²/ν per gyro axis.
    residuals : ndarray, shape (n, 3)
        d − A·x̂. [rad/s]
    """

    coefficients: _F64
    covariance: _F64
    fits: tuple[FitQuality, ...]
    residuals: _F64

    @property
    def std(self) -> _F64:
        """Standard uncertainties, shape (3, 4)."""
        return np.asarray(np.sqrt(np.diag(self.covariance)).reshape(3, 4), dtype=np.float64)


def _check(name: str, a: _F64, n: int) -> None:
    if a.shape != (n, 3) or not np.all(np.isfinite(a)):
        raise InvalidInputError(f"`{name}` must be a finite ({n}, 3) array; got shape "
                                f"{a.shape}{'' if np.all(np.isfinite(a)) else ' with NaN'}")


def fit_drift_model(omega_ref_rps: _F64, force_mps2: _F64, gyro_mean_rps: _F64,
                    gyro_se_rps: _F64, *, scale_misalignment: _F64 | None = None,
                    scale_misalignment_std: float = 0.0) -> DriftFit:
    """Fit (1) by (3) with the covariance (2); χ² and the Birge scaling (4).

    Parameters
    ----------
    omega_ref_rps, force_mps2, gyro_mean_rps, gyro_se_rps : ndarray, shape (n, 3)
        Reference Earth rate, reference specific force, window means and their standard errors.
    scale_misalignment : ndarray, shape (3, 3), optional
        The gyro M taken as known (zero when omitted).
    scale_misalignment_std : float
        σ_M, the standard uncertainty of every element of M (Type B). [1]

    Raises
    ------
    InvalidInputError
        Inconsistent shapes, NaN, a non-positive standard error.
    InsufficientExcitationError
        Fewer than 4 windows, or forces that do not excite every component (rank < 4).
    """
    w = np.asarray(omega_ref_rps, dtype=np.float64)
    n = w.shape[0] if w.ndim == 2 else -1
    f = np.asarray(force_mps2, dtype=np.float64)
    y = np.asarray(gyro_mean_rps, dtype=np.float64)
    se = np.asarray(gyro_se_rps, dtype=np.float64)
    for name, a in (("omega_ref_rps", w), ("force_mps2", f), ("gyro_mean_rps", y),
                    ("gyro_se_rps", se)):
        _check(name, a, n)
    if np.any(se <= 0):
        raise InvalidInputError("`gyro_se_rps` must be positive; got a zero or negative value")
    names = [f"gyro_{p}_{a}" for a in _AXES for p in ("D0", "D1", "D2", "D3")]
    A = np.column_stack([np.ones(n), f])
    if n < 4 or np.linalg.matrix_rank(A / np.abs(A).max(axis=0)) < 4:
        raise InsufficientExcitationError(
            names, f"the drift model needs at least 4 positions whose gravity directions span "
                   f"3-D (rank 4 of [1, f]); got {n} window(s) of rank "
                   f"{np.linalg.matrix_rank(A) if n else 0}")
    m = np.zeros((3, 3)) if scale_misalignment is None else np.asarray(scale_misalignment, float)
    d = y - w @ (np.eye(3) + m).T
    coef, cov, fits, res = np.zeros((3, 4)), np.zeros((12, 12)), [], np.zeros((n, 3))
    for i in range(3):
        sol = solve_weighted_lsq(
            A, d[:, i], covariance=np.diag(se[:, i] ** 2) + scale_misalignment_std**2 * (w @ w.T),
            param_names=names[4 * i:4 * i + 4], group=f"gyro {_AXES[i]}",
            context="drift-model design [1, f]")                                  # (2), (3)
        coef[i], res[:, i] = sol.estimate, sol.residuals
        cov[4 * i:4 * i + 4, 4 * i:4 * i + 4] = sol.covariance_birge                # (4)
        fits.append(sol.fit_quality)
    return DriftFit(coef, cov, tuple(fits), res)


def fit_windows(windows: list[StaticWindow], opt: GSensitivityOptions) -> DriftFit:
    """Fit the drift model (1)–(4) to static windows."""
    return fit_drift_model(np.array([w.omega_ref_b_rps for w in windows]),
                           np.array([w.force_ref_b_mps2 for w in windows]),
                           np.array([w.mean[:3] for w in windows]),
                           np.array([w.se[:3] for w in windows]),
                           scale_misalignment=None if opt.scale_misalignment is None
                           else np.asarray(opt.scale_misalignment, dtype=np.float64),
                           scale_misalignment_std=opt.scale_misalignment_std)
