"""Weighted linear least squares with covariance, residual diagnostics and an observability check.

Contents
--------
:class:`LsqSolution`
    Estimate, covariance, residuals (raw and normalised), χ², degrees of freedom, a-posteriori
    variance factor, condition number and rank.
:func:`solve_weighted_lsq`
    Pure solver for z = H·x + n, n ~ N(0, C).

Method
------
With the whitening W = C^{-1/2} (Cholesky, or 1/σᵢ per row) and the column scaling
D = diag(1/‖(W·H)_{:,j}‖), the scaled design Ā = W·H·D is decomposed by SVD (after a QR when it
is tall): Ā = U·S·Vᵀ. Then [1]_ (Eq. numbers below refer to this docstring)::

    x̂   = D·V·S⁻¹·Uᵀ·W·z                                   (1) minimises ‖W(z − Hx)‖²
    Σ_x = D·V·S⁻²·Vᵀ·D = (Hᵀ C⁻¹ H)⁻¹                        (2) covariance for known C
    r   = z − H·x̂,  χ² = ‖W·r‖²,  ν = m − p                  (3)
    σ̂₀² = χ²/ν                                              (4) a-posteriori variance factor
    Σ_r = C − H·Σ_x·Hᵀ = L(I − UUᵀ)Lᵀ,  wᵢ = rᵢ/√(Σ_r)ᵢᵢ      (5) normalised residuals [2]_

Column scaling makes the rank and condition check (:mod:`~imucalib.estimation.observability`)
independent of parameter units and keeps the SVD accurate when columns differ by many orders of
magnitude (a bias in m/s² next to a scale factor multiplied by g). When C is known, σ̂₀² should be
near 1 (E[χ²] = ν) and Σ_x is reported as is (``scale_covariance=False``). When only relative
weights are known (or none), Σ_x is multiplied by σ̂₀² (``scale_covariance=True``; the default
when no noise description is given), which makes the covariance consistent with the scatter of the
residuals but costs ν degrees of freedom of uncertainty in σ̂₀².

References
----------
.. [1] Å. Björck, *Numerical Methods for Least Squares Problems*, SIAM, 1996, §1.2 (weighted
   problems, covariance), §2.7 (SVD solution, column scaling).
.. [2] W. Baarda, *A testing procedure for use in geodetic networks*, Netherlands Geodetic
   Commission, Publ. on Geodesy 2(5), 1968 (normalised residuals, the w-test).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import InvalidInputError
from imucalib.estimation._common import (
    EstimateAccessors,
    Whitener,
    as_design,
    as_names,
    make_whitener,
)
from imucalib.estimation.observability import (
    DEFAULT_COND_LIMIT,
    ObservabilityReport,
    compute_observability,
)

__all__ = ["LsqSolution", "solve_weighted_lsq"]


@dataclass(frozen=True, eq=False)
class LsqSolution(EstimateAccessors):
    """Result of a (weighted) least-squares fit. Arrays are read-only.

    Attributes
    ----------
    param_names : tuple of str
        Order of `estimate` and of the rows/columns of `covariance`.
    estimate : ndarray, shape (p,)
        x̂, Eq. (1) of :mod:`~imucalib.estimation.linear`. [units of the parameters]
    covariance : ndarray, shape (p, p)
        Σ_x, Eq. (2), multiplied by σ̂₀² when `covariance_scaled`.
    std : ndarray, shape (p,)
        √diag(Σ_x).
    residuals : ndarray, shape (m,)
        r = z − H·x̂. [units of z]
    normalized_residuals : ndarray, shape (m,)
        wᵢ = rᵢ/σ(rᵢ), Eq. (5); N(0, 1) under the model (NaN where an observation has leverage 1,
        i.e. it alone determines a parameter).
    chi2 : float
        ‖W·r‖², Eq. (3), with the noise as given (before any scaling).
    dof : int
        ν = m − p.
    variance_factor : float
        σ̂₀² = χ²/ν, Eq. (4); NaN when ν = 0.
    covariance_scaled : bool
        Whether `covariance` includes the factor σ̂₀².
    condition_number : float
        Of the column-scaled, whitened design.
    rank : int
        Numerical rank of the design (= p for any returned solution).
    observability : ObservabilityReport
        The full rank/conditioning report.
    """

    param_names: tuple[str, ...]
    estimate: NDArray[np.float64]
    covariance: NDArray[np.float64]
    std: NDArray[np.float64]
    residuals: NDArray[np.float64]
    normalized_residuals: NDArray[np.float64]
    chi2: float
    dof: int
    variance_factor: float
    covariance_scaled: bool
    condition_number: float
    rank: int
    observability: ObservabilityReport



def solve_weighted_lsq(
    H: ArrayLike,
    z: ArrayLike,
    *,
    param_names: Sequence[str],
    weights: ArrayLike | None = None,
    covariance: ArrayLike | None = None,
    sigma: ArrayLike | None = None,
    scale_covariance: bool | None = None,
    cond_limit: float = DEFAULT_COND_LIMIT,
) -> LsqSolution:
    """Solve z = H·x + n, n ~ N(0, C), by weighted least squares (module docstring).

    Parameters
    ----------
    H : array_like, shape (m, p)
        Design matrix. [units of z per unit of each parameter]
    z : array_like, shape (m,)
        Observations. [units of z]
    param_names : sequence of str, length p
        Parameter names, in column order.
    weights : array_like, shape (m,), optional
        Inverse variances 1/σᵢ² [1/unit²]; at most one of `weights`, `covariance`, `sigma`.
    covariance : float or array_like, shape (m,) or (m, m), optional
        Observation noise covariance C (a common variance, variances, or full SPD). [unit²]
    sigma : float or array_like, shape (m,), optional
        Observation standard deviations. [unit]
    scale_covariance : bool, optional
        Multiply Σ_x by σ̂₀². Default: True when no noise description is given (the noise level is
        unknown and estimated from the residuals), False otherwise (known noise).
    cond_limit : float
        κ_max for the observability check (:func:`compute_observability`).

    Returns
    -------
    LsqSolution
        Estimate, covariance and diagnostics.

    Raises
    ------
    InvalidInputError
        If shapes disagree, a value is NaN or infinite, a weight or variance is ≤ 0, or the
        covariance must be scaled but ν = m − p = 0.
    InsufficientExcitationError
        If the column-scaled design has rank < p or κ > `cond_limit`; it names the parameters
        taking part in the weak directions.

    Examples
    --------
    >>> import numpy as np
    >>> H = np.array([[1.0, 1.0], [1.0, -1.0], [1.0, 0.0]])
    >>> sol = solve_weighted_lsq(H, [3.0, -1.0, 1.0], param_names=["b", "s"], sigma=0.1)
    >>> np.round(sol.estimate, 12).tolist(), np.round(sol.std, 4).tolist()
    ([1.0, 2.0], [0.0577, 0.0707])
    """
    A0 = as_design(H, "H")
    m, p = A0.shape
    names = as_names(param_names, p)
    y = as_array(z, "z", shape=(m,))
    whitener, known = make_whitener(m, weights=weights, covariance=covariance, sigma=sigma)
    scale = (not known) if scale_covariance is None else bool(scale_covariance)
    dof = m - p
    if scale and dof <= 0:
        raise InvalidInputError(
            "scaling the covariance by the a-posteriori variance factor needs more observations "
            f"than parameters; got m = {m}, p = {p} (give the noise, or scale_covariance=False)"
        )
    A = whitener.whiten(A0)
    yw = whitener.whiten(y)
    report = compute_observability(A, names, cond_limit=cond_limit)
    report.raise_if_unobservable("design matrix H")

    U, s, vt = _scaled_svd_factors(A, report.column_norms)
    norms = report.column_norms
    x_hat = (vt.T @ ((U.T @ yw) / s)) / norms  # Eq. (1)
    r = y - A0 @ x_hat  # Eq. (3)
    stats = _fit_statistics(U, s, vt, norms, whitener, r, dof, scale)
    x_hat.setflags(write=False)
    return LsqSolution(
        param_names=names, estimate=x_hat, covariance=stats.covariance, std=stats.std,
        residuals=stats.residuals, normalized_residuals=stats.normalized_residuals,
        chi2=stats.chi2, dof=dof, variance_factor=stats.variance_factor, covariance_scaled=scale,
        condition_number=report.condition_number, rank=report.rank, observability=report,
    )


@dataclass(frozen=True, eq=False)
class _FitStatistics:
    covariance: NDArray[np.float64]
    std: NDArray[np.float64]
    residuals: NDArray[np.float64]
    normalized_residuals: NDArray[np.float64]
    chi2: float
    variance_factor: float


def _scaled_svd_factors(A: NDArray[np.float64], norms: NDArray[np.float64]
                        ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Thin SVD U (m, p), s (p,), Vᵀ (p, p) of the column-scaled A (QR first when tall)."""
    m, p = A.shape
    As = A / norms
    if m > 2 * p:
        Q, R = np.linalg.qr(As)
        Ur, s, vt = np.linalg.svd(R)
        return Q @ Ur, s, vt
    U, s, vt = np.linalg.svd(As, full_matrices=False)
    return U, s, vt


def _fit_statistics(U: NDArray[np.float64], s: NDArray[np.float64], vt: NDArray[np.float64],
                    norms: NDArray[np.float64], whitener: Whitener, r: NDArray[np.float64],
                    dof: int, scale: bool) -> _FitStatistics:
    """Eqs. (2)–(5) of the module docstring from the SVD of the column-scaled whitened design."""
    cov = (vt.T / s**2) @ vt / np.outer(norms, norms)  # Eq. (2)
    cov = 0.5 * (cov + cov.T)
    rw = whitener.whiten(r)
    chi2 = float(rw @ rw)  # Eq. (3)
    var_factor = chi2 / dof if dof > 0 else float("nan")  # Eq. (4)
    factor = var_factor if scale else 1.0
    cov = cov * factor
    # Eq. (5): diag of L(I − UUᵀ)Lᵀ = diag(C) − rowsum((L·U)²)
    LU = whitener.colour(U)
    var_r = (whitener.sigma**2 - np.einsum("ij,ij->i", LU, LU)) * factor
    tiny = 1e-10 * whitener.sigma**2 * factor
    ok = var_r > tiny
    w = np.full(r.shape, np.nan)
    w[ok] = r[ok] / np.sqrt(var_r[ok])
    std = np.sqrt(np.diag(cov))
    r = r.copy()
    for arr in (cov, std, r, w):
        arr.setflags(write=False)
    return _FitStatistics(covariance=cov, std=std, residuals=r, normalized_residuals=w,
                          chi2=chi2, variance_factor=var_factor)
