"""The rate-transfer fits of one gyro axis (docs/rate-transfer.md, eqs. (RT-5)–(RT-9)).

Pure maths on whole-revolution means: x_j the input rate about the vertical (the table rate plus
the vertical Earth rate Ω_U, eq. (RT-1)), y_j the gyro's mean output, σ_j its standard error.

1. the IEEE straight line (RT-5) y = E0 + E·x, weighted least squares; the scale-factor
   nonlinearity (RT-6) is the largest deviation of a mean from that line, in ppm of the
   full-scale output |E|·max|x| of the rates tested (IEEE Std 952-2020, "scale factor
   nonlinearity"), its σ propagated from the means' σ at the largest deviation (RT-6a)
   (:func:`nonlinearity_noise_std`);
2. the second fit (RT-7) y = E0′ + E′·x + A·|x| + E2·x²: separate slopes K± = E′ ± A for
   positive and negative rates, the asymmetry (RT-8) (K₊ − K₋)/((K₊ + K₋)/2) = 2A/E′ and the
   quadratic coefficient E2.

Both fits are solved by :func:`~imucalib.estimation.linear.solve_weighted_lsq` (Eqs. (1)–(7)
there) as generalized least squares with the means' covariance C (RT-4c): θ̂ = (AᵀC⁻¹A)⁻¹AᵀC⁻¹y,
Cov θ̂ = (AᵀC⁻¹A)⁻¹ (Aitken 1935), which is weighted least squares by 1/σ_j² when C = diag σ_j²
(``covariance`` omitted). Its χ² = rᵀC⁻¹r over ν = n − m is assessed by the one misfit rule
(Eq. (6) there, :func:`~imucalib.models.fit_quality.assess_fit`) and on a misfit the σ are
scaled by the Birge ratio (Eq. (7) there: the covariance reported here is the solver's
``covariance_birge``).

Contents
--------
:class:`LineFit`, :func:`fit_line`, :func:`fit_rate_transfer`, :class:`TransferFit`,
:func:`nonlinearity_noise_std`
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation.linear import LsqSolution, solve_weighted_lsq
from imucalib.models.fit_quality import FitQuality

__all__ = ["LineFit", "TransferFit", "fit_line", "fit_rate_transfer", "nonlinearity_noise_std"]

_F64 = NDArray[np.float64]


def _solve(design: _F64, y: _F64, cov: _F64, names: tuple[str, ...], group: str) -> LsqSolution:
    """Fit the means to (RT-5) or (RT-7) by GLS with their covariance, with the one solver."""
    return solve_weighted_lsq(design, y, param_names=names, covariance=cov, group=group,
                              context=f"{group} rate-transfer design",
                              advice=f"the {design.shape[0]} means' rates cannot separate the "
                                     f"{design.shape[1]} terms of the model")


@dataclass(frozen=True)
class LineFit:
    """The straight line (RT-5) and the nonlinearity (RT-6).

    Attributes
    ----------
    bias_rps, scale_factor : float
        E0 [rad/s] and E [1].
    cov : ndarray (2, 2)
        Their covariance (Birge-scaled on a misfit).
    residuals_rps : ndarray
        y − (E0 + E·x) of each mean. [rad/s]
    nonlinearity_ppm : float
        max |residual| / (|E|·max|x|) · 10⁶. [ppm of full scale]
    quality : FitQuality
        χ²/ν of the line.
    nonlinearity_noise_std_ppm : float
        The nonlinearity's σ from the means' σ alone, (RT-6a) (:func:`nonlinearity_noise_std`;
        not Birge-scaled: the line's misfit is the nonlinearity itself). [ppm of full scale]
    """

    bias_rps: float
    scale_factor: float
    cov: _F64
    residuals_rps: _F64
    nonlinearity_ppm: float
    quality: FitQuality
    nonlinearity_noise_std_ppm: float = float("nan")


@dataclass(frozen=True)
class TransferFit:
    """The second fit (RT-7)–(RT-8): y = E0′ + E′·x + A·|x| + E2·x².

    Attributes
    ----------
    params : ndarray (4,)
        E0′ [rad/s], E′ [1], A [1], E2 [s/rad].
    cov : ndarray (4, 4)
        Their covariance (Birge-scaled on a misfit).
    residuals_rps : ndarray
        Residuals of the means. [rad/s]
    quality : FitQuality
        χ²/ν of the fit.
    """

    params: _F64
    cov: _F64
    residuals_rps: _F64
    quality: FitQuality

    @property
    def asymmetry(self) -> tuple[float, float]:
        """(K₊ − K₋)/mean K = 2A/E′ and its σ (RT-8, first-order propagation). [1]"""
        e, a = float(self.params[1]), float(self.params[2])
        jac = np.array([0.0, -2.0 * a / e ** 2, 2.0 / e, 0.0])
        return 2.0 * a / e, float(np.sqrt(jac @ self.cov @ jac))

    @property
    def slopes(self) -> tuple[float, float]:
        """K₊ = E′ + A and K₋ = E′ − A, the scale factors of positive and negative rates."""
        return float(self.params[1] + self.params[2]), float(self.params[1] - self.params[2])

    def std(self, i: int) -> float:
        """Return the standard uncertainty of parameter `i`."""
        return float(np.sqrt(self.cov[i, i]))


def _inputs(x_rps: ArrayLike, y_rps: ArrayLike, se_rps: ArrayLike,
            covariance: ArrayLike | None = None) -> tuple[_F64, _F64, _F64]:
    """Return x, y and the means' covariance C: `covariance`, else diag σ_j² (RT-4)."""
    x, y, se = (np.asarray(v, dtype=np.float64).ravel() for v in (x_rps, y_rps, se_rps))
    if not (x.size == y.size == se.size) or x.size < 2:
        raise InvalidInputError(f"x, y and σ must be equal-length with ≥ 2 means; got sizes "
                                f"{x.size}, {y.size}, {se.size}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y)) and np.all(se > 0)):
        raise InvalidInputError("rates and means must be finite and σ > 0")
    if covariance is None:
        return x, y, np.diag(se * se)
    cov = np.asarray(covariance, dtype=np.float64)
    if cov.shape != (x.size, x.size) or not np.all(np.isfinite(cov)):
        raise InvalidInputError(f"the means' covariance must be finite with shape "
                                f"({x.size}, {x.size}); got {cov.shape}")
    return x, y, 0.5 * (cov + cov.T)


def fit_line(x_rps: ArrayLike, y_rps: ArrayLike, se_rps: ArrayLike, *,
             group: str = "gyro", covariance: ArrayLike | None = None) -> LineFit:
    """Fit the straight line (RT-5) and return it with the nonlinearity (RT-6).

    `covariance` is the means' covariance C (RT-4c), shape (n, n) [(rad/s)²]: GLS; omitted,
    diag `se_rps`² (weighted least squares).

    Raises
    ------
    InsufficientExcitationError
        Rates that cannot separate E0 from E (all means at one rate).
    """
    x, y, cov = _inputs(x_rps, y_rps, se_rps, covariance)
    sol = _solve(np.column_stack([np.ones_like(x), x]), y, cov, ("E0", "E"), group)
    p, r = sol.estimate, sol.residuals
    full = abs(float(p[1])) * float(np.max(np.abs(x)))
    return LineFit(bias_rps=float(p[0]), scale_factor=float(p[1]), cov=sol.covariance_birge,
                   residuals_rps=r, nonlinearity_ppm=float(np.max(np.abs(r)) / full * 1e6),
                   quality=sol.fit_quality,
                   nonlinearity_noise_std_ppm=nonlinearity_noise_std(
                       x, y, se_rps, covariance=cov) * 1e6)


def nonlinearity_noise_std(x_rps: ArrayLike, y_rps: ArrayLike, se_rps: ArrayLike, *,
                           covariance: ArrayLike | None = None) -> float:
    """Return the σ of the nonlinearity (RT-6) from the means' σ, first order, (RT-6a). [1]

    N = |r_j*|/(|E|·X), r = y − E0 − E·x the residuals of the weighted line (RT-5), j* the
    largest |r_j|, X = max|x|. Both r = R·y (R = I − A·P, P = (AᵀΣ⁻¹A)⁻¹AᵀΣ⁻¹, A = [1, x],
    Σ the means' covariance: `covariance`, else diag σ_j²) and E = P₂·y are linear in the
    means, so with j* held fixed

        ∇N = sign(r_j*)·R_j*/(|E|·X) − (N/E)·P₂,   σ_N² = ∇Nᵀ·Σ·∇N                   (RT-6a)

    — the σ of the residual at the largest deviation, √(σ_j*² − a_j*ᵀC_p a_j*) with C_p the
    line's noise-only covariance, over the full scale (the E term is ~10⁻⁶ of it). It is the
    spread of N when one deviation stands out from the others by several σ; where two tie (the
    +ω and −ω means of an even nonlinearity: the quadratic term, the asymmetry) the maximum
    of the two scatters less (≈ 0.83σ for two equal independent ones), and with no
    nonlinearity N is the largest of the noisy residuals: there σ_N is an upper bound of the
    spread (tests/procedures/test_result_contract_classical_a.py, against a Monte Carlo).
    Not Birge-scaled here (see :attr:`~imucalib.procedures.rate_transfer.analysis.
    AxisTransfer.nonlinearity`).

    Parameters
    ----------
    x_rps, y_rps, se_rps : array_like, shape (n,)
        Inputs x_j, means y_j and their σ_j. [rad/s]
    covariance : array_like, shape (n, n), optional
        The means' covariance (RT-4c) instead of diag σ_j². [(rad/s)²]
    """
    x, y, cov = _inputs(x_rps, y_rps, se_rps, covariance)
    A = np.column_stack([np.ones_like(x), x])
    Aw = np.linalg.solve(cov, A)  # Σ⁻¹A
    P = np.linalg.solve(A.T @ Aw, Aw.T)  # (2, n): the (generalized) least squares' operator
    R = np.eye(x.size) - A @ P
    r = R @ y
    j = int(np.argmax(np.abs(r)))
    e = float(P[1] @ y)
    full = abs(e) * float(np.max(np.abs(x)))
    n = abs(float(r[j])) / full
    grad = math.copysign(1.0, float(r[j])) * R[j] / full - (n / e) * P[1]
    return float(np.sqrt(max(float(grad @ cov @ grad), 0.0)))


def fit_rate_transfer(x_rps: ArrayLike, y_rps: ArrayLike, se_rps: ArrayLike, *,
                      group: str = "gyro", covariance: ArrayLike | None = None) -> TransferFit:
    """Fit (RT-7): y = E0′ + E′·x + A·|x| + E2·x², by GLS with `covariance` (as :func:`fit_line`).

    Raises
    ------
    InsufficientExcitationError
        Fewer than three distinct rate magnitudes, or rates of one sign only.
    """
    x, y, cov = _inputs(x_rps, y_rps, se_rps, covariance)
    mags = np.unique(np.round(np.abs(x), 9))
    if mags.size < 3 or not (np.any(x > 0) and np.any(x < 0)):
        raise InsufficientExcitationError(
            [f"{group} asymmetry", f"{group} E2"],
            f"{group}: the asymmetry and quadratic terms need rates of both signs at ≥ 3 "
            f"magnitudes; got {mags.size} magnitude(s)")
    design = np.column_stack([np.ones_like(x), x, np.abs(x), x * x])
    sol = _solve(design, y, cov, ("E0'", "E'", "A", "E2"), group)
    return TransferFit(params=sol.estimate, cov=sol.covariance_birge,
                       residuals_rps=sol.residuals, quality=sol.fit_quality)
