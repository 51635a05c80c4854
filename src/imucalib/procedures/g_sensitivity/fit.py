"""The drift model of a gyro triad on static positions, by generalised least squares.

Per gyro axis i and static window k (docs/g-sensitivity.md, equations (1)–(4)):

    d_ik = ȳ_ik − [(I + M)·ω_k]_i = D0_i + D1_i·f_xk + D2_i·f_yk + D3_i·f_zk + e_ik        (1)

ω_k the reference Earth rate and f_k the reference specific force in the body frame, M the gyro
scale-misalignment taken as known (nominal: zero). Its error δm_i (row i, each element of
standard deviation σ_M, Type B) acts on the Earth rate as δm_i·ω_k, the same error in every
window through ω_k, so the observations' covariance is full:

    C_i = diag(σ_ik²) + σ_M²·Ω·Ωᵀ,  Ω the (n, 3) matrix of the ω_k                           (2)
    x̂_i = (AᵀC_i⁻¹A)⁻¹·AᵀC_i⁻¹·d_i,  cov x̂_i = (AᵀC_i⁻¹A)⁻¹,  A = [1, f_x, f_y, f_z]           (3)
    χ²_i = rᵀC_i⁻¹r with ν = n − 4; on a misfit (99 % quantile) cov x̂_i is scaled by R_B²    (4)

The three axes are independent (their noise and their δm_i are). The closed form of the six
axis-up positions (:func:`six_position_closed_form`) is (1) solved exactly:
D0_i = (1/6)·Σ d_ik and D_ji = (d_i(+j) − d_i(−j))/(2g).

Contents
--------
:class:`DriftFit`, :func:`fit_drift_model`, :func:`six_position_closed_form`
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.models.fit_quality import FitQuality, assess_fit

__all__ = ["DriftFit", "fit_drift_model", "six_position_closed_form"]

_F64 = NDArray[np.float64]
_AXES = "xyz"


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
        c = np.diag(se[:, i] ** 2) + scale_misalignment_std**2 * (w @ w.T)
        ci = np.linalg.inv(c)
        normal = A.T @ ci @ A
        cov_i = np.linalg.inv(normal)
        x = cov_i @ (A.T @ ci @ d[:, i])
        r = d[:, i] - A @ x
        fit = assess_fit(f"gyro {_AXES[i]}", float(r @ ci @ r), n - 4)
        coef[i], res[:, i] = x, r
        cov[4 * i:4 * i + 4, 4 * i:4 * i + 4] = cov_i * fit.sigma_scale**2
        fits.append(fit)
    return DriftFit(coef, cov, tuple(fits), res)


def six_position_closed_form(gyro_mean_rps: _F64, omega_ref_rps: _F64, gravity_mps2: float
                             ) -> _F64:
    """Return (3, 4) coefficients from the six axis-up positions.

    In the order +z, −z, +x, −x, +y, −y (module docstring; M taken as zero).
    """
    d = np.asarray(gyro_mean_rps, float) - np.asarray(omega_ref_rps, float)
    if d.shape != (6, 3):
        raise InvalidInputError(f"the closed form takes the 6 axis-up positions; got shape "
                                f"{d.shape}")
    out = np.zeros((3, 4))
    out[:, 0] = d.mean(axis=0)
    for j, (up, down) in enumerate(((2, 3), (4, 5), (0, 1))):
        out[:, 1 + j] = (d[up] - d[down]) / (2.0 * gravity_mps2)
    return out
