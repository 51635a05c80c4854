"""The one weighted linear least-squares solver: estimate, covariance, χ² and the misfit test.

Every linear fit of the project above the ``models`` layer (P1, the procedures' fits, the
temperature models, the linear steps of the Gauss–Newton fits) solves through
:func:`solve_weighted_lsq`, so the solution, its covariance and the decision on a misfit are made
one way (docs/processing-estimation.md, "One solver").

Contents
--------
:class:`LsqSolution` (the fields of :class:`LsqStatistics`, shared with the nonlinear solver)
    Estimate, covariance (noise-only and Birge-scaled), residuals (raw and normalised), χ²,
    degrees of freedom, a-posteriori variance factor, the
    :class:`~imucalib.models.fit_quality.FitQuality`, condition number and rank.
:func:`solve_weighted_lsq`
    Pure solver for z = H·x + n, n ~ N(0, C), C given as σ per observation, weights, or full.
:func:`solve_step`
    x̂ of Eq. (1) alone, by the same operations (a Gauss–Newton step: no diagnostics).

Method
------
With the whitening W = C^{-1/2} (Cholesky C = L·Lᵀ, W = L⁻¹, or 1/σᵢ per row) and the column
scaling D = diag(1/‖(W·H)_{:,j}‖), the scaled design Ā = W·H·D is decomposed by SVD (after a QR
when it is tall): Ā = U·S·Vᵀ. Then [1]_ (Eq. numbers below refer to this docstring)::

    x̂   = D·V·S⁻¹·Uᵀ·W·z = K·z                             (1) minimises ‖W(z − Hx)‖²
    Σ_x = D·V·S⁻²·Vᵀ·D = (Hᵀ C⁻¹ H)⁻¹                        (2) noise-only covariance
    r   = z − H·x̂,  χ² = ‖W·r‖² = rᵀC⁻¹r,  ν = m − p         (3)
    σ̂₀² = χ²/ν                                              (4) a-posteriori variance factor
    Σ_r = C − H·Σ_x·Hᵀ = L(I − UUᵀ)Lᵀ,  wᵢ = rᵢ/√(Σ_r)ᵢᵢ      (5) normalised residuals [2]_
    misfit  ⇔  χ² > χ²_ν⁻¹(q),  q = 0.99                     (6) the one misfit rule [3]_
    R_B = √(χ²/ν) = σ̂₀;  Σ_x^B = R_B²·Σ_x on a misfit, Σ_x otherwise   (7) Birge scaling

(6)–(7) are Eqs. (2)–(3) of :mod:`imucalib.models.fit_quality` (docs/processing-estimation.md,
(G2)–(G3)): the solution carries them as :attr:`LsqSolution.fit_quality` and
:attr:`LsqSolution.covariance_birge`. K = D·V·S⁻¹·Uᵀ·W of (1) is the estimator's linear operator
(the *gain*, returned on request): x̂ = K·z, Σ_x = K·C·Kᵀ.

Column scaling makes the rank and condition check (:mod:`~imucalib.estimation.observability`)
independent of parameter units and keeps the SVD accurate when columns differ by many orders of
magnitude (a bias in m/s² next to a scale factor multiplied by g). A rank-deficient or
ill-conditioned design raises :class:`~imucalib.errors.InsufficientExcitationError` naming the
parameters of its weak directions.

Which covariance is reported as :attr:`LsqSolution.covariance`:

- the noise is *known* (σ, weights or C given): Σ_x of (2) as is; with ``scale_covariance=True``
  Σ_x^B of (7), i.e. scaled by R_B² only when (6) flags a misfit (σ̂₀² ≈ 1 is a check, not a
  factor);
- the noise is *unknown* (no description given): the observations are weighted alike and their
  variance is estimated from the residuals, Σ_x·σ̂₀² (needs ν > 0). That is an estimate of the
  noise, not a misfit verdict: nothing is left to test, and the :class:`FitQuality` then reads
  χ² = ν against the estimated noise (no misfit).

References
----------
.. [1] Å. Björck, *Numerical Methods for Least Squares Problems*, SIAM, 1996, §1.2 (weighted
   problems, covariance), §2.7 (SVD solution, column scaling).
.. [2] W. Baarda, *A testing procedure for use in geodetic networks*, Netherlands Geodetic
   Commission, Publ. on Geodesy 2(5), 1968 (normalised residuals, the w-test).
.. [3] R. T. Birge, "The calculation of errors by the method of least squares", Phys. Rev. 40,
   207 (1932); Particle Data Group, *Review of Particle Physics*, "Introduction", §5.2.2 (the
   scale factor S).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

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
    report_from_svd,
)
from imucalib.models.fit_quality import MISFIT_QUANTILE, FitQuality, assess_fit

__all__ = ["LsqSolution", "LsqStatistics", "solve_step", "solve_weighted_lsq"]


@dataclass(frozen=True, eq=False)
class LsqStatistics(EstimateAccessors):
    """What a least-squares solution carries, Eqs. (1)–(7) of the module. Arrays are read-only.

    The base of :class:`LsqSolution` and of
    :class:`~imucalib.estimation.nonlinear.NlsSolution` (whose design is the Jacobian at x̂).

    Attributes
    ----------
    param_names : tuple of str
        Order of `estimate` and of the rows/columns of `covariance`.
    estimate : ndarray, shape (p,)
        x̂, Eq. (1) of :mod:`~imucalib.estimation.linear`. [units of the parameters]
    covariance : ndarray, shape (p, p)
        The reported covariance: `covariance_noise`, or with `covariance_scaled` the scaled one
        (module docstring: Σ_x^B of Eq. (7) for known noise, Σ_x·σ̂₀² for unknown noise).
    std : ndarray, shape (p,)
        √diag(`covariance`).
    residuals : ndarray, shape (m,)
        r = z − H·x̂. [units of z]
    normalized_residuals : ndarray, shape (m,)
        wᵢ = rᵢ/σ(rᵢ), Eq. (5), with the noise `covariance` is built on; N(0, 1) under the
        model (NaN where an observation has leverage 1, i.e. it alone determines a parameter).
    chi2 : float
        ‖W·r‖², Eq. (3), with the noise as given (unit weights when none; before any scaling).
    dof : int
        ν = m − p.
    variance_factor : float
        σ̂₀² = χ²/ν, Eq. (4) (= R_B², the square of the Birge ratio of Eq. (7)); NaN when ν = 0.
    covariance_scaled : bool
        Whether `covariance` is the scaled covariance rather than Σ_x of Eq. (2).
    condition_number : float
        Of the column-scaled, whitened design.
    rank : int
        Numerical rank of the design (= p for any returned solution).
    observability : ObservabilityReport
        The full rank/conditioning report.
    covariance_noise : ndarray, shape (p, p)
        Σ_x of Eq. (2) from the noise as given (× σ̂₀² when the noise is unknown and estimated).
    covariance_birge : ndarray, shape (p, p)
        Σ_x^B of Eq. (7): `covariance_noise` × R_B² when `fit_quality` flags a misfit, else
        `covariance_noise`.
    std_birge : ndarray, shape (p,)
        √diag(`covariance_birge`).
    fit_quality : FitQuality
        χ², ν, the expected range of χ²/ν, the misfit flag (6) and the Birge ratio (7)
        (:func:`~imucalib.models.fit_quality.assess_fit`).
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
    covariance_noise: NDArray[np.float64]
    covariance_birge: NDArray[np.float64]
    std_birge: NDArray[np.float64]
    fit_quality: FitQuality


@dataclass(frozen=True, eq=False)
class LsqSolution(LsqStatistics):
    """Result of a (weighted) linear least-squares fit, Eqs. (1)–(7) of the module.

    Attributes
    ----------
    param_names, estimate, covariance, std, residuals, normalized_residuals, chi2, dof
        As in :class:`LsqStatistics`.
    variance_factor, covariance_scaled, condition_number, rank, observability
        As in :class:`LsqStatistics`.
    covariance_noise, covariance_birge, std_birge, fit_quality
        As in :class:`LsqStatistics`.
    noise_known : bool
        Whether a noise description was given (else the noise level was estimated).
    gain : ndarray, shape (p, m), or None
        K of Eq. (1) (x̂ = K·z), when asked for (``gain=True``).
    """

    noise_known: bool
    gain: NDArray[np.float64] | None = None


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
    group: str = "fit",
    quantile: float = MISFIT_QUANTILE,
    context: str = "design matrix H",
    advice: str | None = None,
    gain: bool = False,
) -> LsqSolution:
    """Solve z = H·x + n, n ~ N(0, C), by weighted least squares, Eqs. (1)–(7) of the module.

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
        Observation noise covariance C (a common variance, variances, or full SPD: GLS through
        its Cholesky factor). [unit²]
    sigma : float or array_like, shape (m,), optional
        Observation standard deviations. [unit]
    scale_covariance : bool, optional
        Report the scaled covariance as `covariance` (module docstring). Default: True when no
        noise description is given (the noise level is unknown and estimated from the
        residuals), False otherwise (known noise: the noise-only Σ_x; the Birge-scaled one is
        `covariance_birge` either way).
    cond_limit : float
        κ_max for the observability check (:func:`compute_observability`).
    group : str
        What is fitted, the `group` of the :class:`FitQuality` (``"accel"``, ``"gyro x"`` …).
    quantile : float
        The χ² quantile q of the misfit rule, Eq. (6).
    context : str
        What the design is, for the message of a rank-deficient design.
    advice : str, optional
        What would make the parameters observable, appended to that message.
    gain : bool
        Also return K of Eq. (1) (x̂ = K·z), shape (p, m).

    Returns
    -------
    LsqSolution
        Estimate, covariances and diagnostics.

    Raises
    ------
    InvalidInputError
        If shapes disagree, a value is NaN or infinite, a weight or variance is ≤ 0, a full
        covariance is not symmetric positive definite, or the noise must be estimated but
        ν = m − p = 0.
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
    >>> sol.fit_quality.misfit, sol.dof
    (False, 1)
    """
    A0, y, names, whitener, known = _checked(H, z, param_names, weights, covariance, sigma)
    m, p = A0.shape
    scale = (not known) if scale_covariance is None else bool(scale_covariance)
    dof = m - p
    if scale and not known and dof <= 0:
        raise InvalidInputError(
            "estimating the noise level from the residuals needs more observations than "
            f"parameters; got m = {m}, p = {p} (give the noise, or scale_covariance=False)"
        )
    A = whitener.whiten(A0)
    yw = whitener.whiten(y)
    U, s, vt, report = _factorise(A, names, cond_limit)
    report.raise_if_unobservable(context, advice)
    norms = report.column_norms
    x_hat = (vt.T @ ((U.T @ yw) / s)) / norms  # Eq. (1)
    r = y - A0 @ x_hat  # Eq. (3)
    stats = _fit_statistics(U, s, vt, norms, whitener, r, dof, scale=scale,
                            estimated=not known and scale, group=group, quantile=quantile)
    k = None
    if gain:
        k = whitener.whiten_transpose((U / s) @ vt / norms).T  # Eq. (1): K = D·V·S⁻¹·Uᵀ·W
        k.setflags(write=False)
    x_hat.setflags(write=False)
    return LsqSolution(
        param_names=names, estimate=x_hat, dof=dof, covariance_scaled=scale,
        condition_number=report.condition_number, rank=report.rank, observability=report,
        noise_known=known, gain=k, **stats,
    )


def solve_step(
    H: ArrayLike,
    z: ArrayLike,
    *,
    param_names: Sequence[str],
    weights: ArrayLike | None = None,
    covariance: ArrayLike | None = None,
    sigma: ArrayLike | None = None,
    cond_limit: float = DEFAULT_COND_LIMIT,
    context: str = "design matrix H",
    advice: str | None = None,
) -> NDArray[np.float64]:
    """Return x̂ of Eq. (1) alone: :func:`solve_weighted_lsq`'s estimate, bit for bit.

    The lean solve of an iteration (a Gauss–Newton step), whose caller reads only the estimate:
    the same argument checks, whitening, column scaling, SVD and operations for x̂ as
    :func:`solve_weighted_lsq`, and the same errors (a rank-deficient or ill-conditioned design
    gets the same :class:`~imucalib.errors.InsufficientExcitationError`), but neither the
    observability report of an observable design nor the covariance, residuals and fit
    statistics of Eqs. (2)–(7) (Björck 1996, §2.7; docs/performance.md, "Field calibration:
    the fits' fixed costs").

    Parameters
    ----------
    H, z, param_names, weights, covariance, sigma, cond_limit, context, advice
        As for :func:`solve_weighted_lsq`.

    Returns
    -------
    ndarray, shape (p,)
        x̂ (read-only). [units of the parameters]

    Raises
    ------
    InvalidInputError
        As :func:`solve_weighted_lsq` for the arguments (not the ν = 0 rule of an estimated
        noise level, which concerns the covariance).
    InsufficientExcitationError
        As :func:`solve_weighted_lsq`.
    """
    A0, y, names, whitener, _ = _checked(H, z, param_names, weights, covariance, sigma)
    U, s, vt, norms = _factorise_checked(whitener.whiten(A0), names, cond_limit, context,
                                         advice)
    x_hat = (vt.T @ ((U.T @ whitener.whiten(y)) / s)) / norms  # Eq. (1)
    x_hat.setflags(write=False)
    return x_hat


def _checked(H: ArrayLike, z: ArrayLike, param_names: Sequence[str], weights: ArrayLike | None,
             covariance: ArrayLike | None, sigma: ArrayLike | None
             ) -> tuple[NDArray[np.float64], NDArray[np.float64], tuple[str, ...], Whitener, bool]:
    """Check the arguments of :func:`solve_weighted_lsq`: design, observations, names, noise."""
    A0 = as_design(H, "H")
    m, p = A0.shape
    names = as_names(param_names, p)
    y = as_array(z, "z", shape=(m,))
    whitener, known = make_whitener(m, weights=weights, covariance=covariance, sigma=sigma)
    return A0, y, names, whitener, known


@dataclass(frozen=True, eq=False)
class _KnownFit:
    """What the internal core :func:`_solve_known` returns: Eqs. (1)–(3) and, asked, K."""

    estimate: NDArray[np.float64]
    covariance_noise: NDArray[np.float64]
    chi2: float
    dof: int
    gain: NDArray[np.float64] | None
    residuals: NDArray[np.float64] | None = None  # r of Eq. (3)


def _solve_known(A0: NDArray[np.float64], y: NDArray[np.float64], whitener: Whitener,
                 names: tuple[str, ...], *, cond_limit: float = DEFAULT_COND_LIMIT,
                 context: str = "design matrix H", advice: str | None = None,
                 gain: bool = False, yw: NDArray[np.float64] | None = None) -> _KnownFit:
    """Solve as :func:`solve_weighted_lsq` does, for arguments :func:`_checked` accepts.

    The same operations as :func:`solve_weighted_lsq` with known noise and the noise-only
    covariance (``scale_covariance`` False), so the same bits for x̂ (Eq. (1)), Σ_x (Eq. (2)),
    χ² (Eq. (3)) and K, and the same :class:`~imucalib.errors.InsufficientExcitationError` for
    an unobservable design; what a caller of this path does not read (the observability
    report of an observable design, the normalised residuals, the Birge-scaled covariance, the
    :class:`FitQuality`) is not made (r of Eq. (3) is returned, not copied). `A0` (m, p) and
    `y` (m,) finite float64, `names` of p distinct strings, `whitener` from
    :func:`make_whitener`; `yw` = W·y when the caller has it.
    """
    m, p = A0.shape
    A = whitener.whiten(A0)
    if yw is None:
        yw = whitener.whiten(y)
    U, s, vt, norms = _factorise_checked(A, names, cond_limit, context, advice)
    x_hat = (vt.T @ ((U.T @ yw) / s)) / norms  # Eq. (1)
    r = y - A0 @ x_hat  # Eq. (3)
    rw = whitener.whiten(r)
    k = whitener.whiten_transpose((U / s) @ vt / norms).T if gain else None
    return _KnownFit(estimate=x_hat, covariance_noise=_covariance(s, vt, norms),
                     chi2=float(rw @ rw), dof=m - p, gain=k, residuals=r)


def _factorise_checked(A: NDArray[np.float64], names: tuple[str, ...], cond_limit: float,
                       context: str, advice: str | None
                       ) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                  NDArray[np.float64], NDArray[np.float64]]:
    """:func:`_factorise` and the observability check, the report made only when it fails.

    The check is :meth:`ObservabilityReport.is_observable` of :func:`report_from_svd`'s
    report (the same rank tolerance and condition number); a design that fails it gets that
    report and its error.
    """
    m, p = A.shape
    if m >= p:
        norms = np.sqrt(np.einsum("ij,ij->j", A, A))
        U, s, vt = _scaled_svd_factors(A, np.where(norms > 0.0, norms, 1.0))
        s1 = float(s[0])
        if s1 > 0:
            rank = int(np.count_nonzero(s > max(m, p) * _EPS * s1))
            if rank == p and s1 / float(s[-1]) <= cond_limit:
                return U, s, vt, norms
    U, s, vt, report = _factorise(A, names, cond_limit)
    report.raise_if_unobservable(context, advice)
    return U, s, vt, report.column_norms


_EPS = float(np.finfo(float).eps)


def _covariance(s: NDArray[np.float64], vt: NDArray[np.float64], norms: NDArray[np.float64]
                ) -> NDArray[np.float64]:
    """Σ_x of Eq. (2), symmetrised, from the SVD of the column-scaled whitened design."""
    cov = (vt.T / s**2) @ vt / np.outer(norms, norms)
    return 0.5 * (cov + cov.T)


def _factorise(A: NDArray[np.float64], names: tuple[str, ...], cond_limit: float
               ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
                          ObservabilityReport]:
    """Thin SVD of the column-scaled whitened design and its observability report (one SVD)."""
    m, p = A.shape
    if m < p:  # rank-deficient whatever the values: the report says which parameters
        report = compute_observability(A, names, cond_limit=cond_limit)
        return np.zeros((m, p)), np.ones(p), np.eye(p), report
    norms = np.sqrt(np.einsum("ij,ij->j", A, A))
    U, s, vt = _scaled_svd_factors(A, np.where(norms > 0.0, norms, 1.0))
    return U, s, vt, report_from_svd(s, vt, norms, names, (m, p), cond_limit=cond_limit)


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
                    dof: int, *, scale: bool, estimated: bool, group: str = "fit",
                    quantile: float = MISFIT_QUANTILE) -> dict[str, Any]:
    """Eqs. (2)–(7) of the module docstring from the SVD of the column-scaled whitened design.

    `estimated`: the noise level is unknown and estimated from the residuals (σ̂₀²); else the
    noise is as given and (6)–(7) decide on a misfit. `scale`: report the scaled covariance.
    Returns the :class:`LsqStatistics` fields that depend on the noise, by name.
    """
    cov = _covariance(s, vt, norms)  # Eq. (2)
    rw = whitener.whiten(r)
    chi2 = float(rw @ rw)  # Eq. (3)
    var_factor = chi2 / dof if dof > 0 else float("nan")  # Eq. (4)
    if estimated:  # the noise is σ̂₀²·(unit weights): χ² against it is ν, nothing to test
        quality = assess_fit(group, float(dof), dof, quantile=quantile)
        cov = cov * var_factor
        factor = var_factor
    else:
        quality = assess_fit(group, chi2, dof, quantile=quantile)  # Eq. (6)
        factor = quality.sigma_scale**2 if scale else 1.0
    birge = cov * quality.sigma_scale**2  # Eq. (7)
    reported = birge if scale else cov
    # Eq. (5): diag of L(I − UUᵀ)Lᵀ = diag(C) − rowsum((L·U)²)
    LU = whitener.colour(U)
    var_r = (whitener.sigma**2 - np.einsum("ij,ij->i", LU, LU)) * factor
    tiny = 1e-10 * whitener.sigma**2 * factor
    ok = var_r > tiny
    w = np.full(r.shape, np.nan)
    w[ok] = r[ok] / np.sqrt(var_r[ok])
    std = np.sqrt(np.diag(reported))
    std_birge = np.sqrt(np.diag(birge))
    r = r.copy()
    for arr in (cov, birge, reported, std, std_birge, r, w):
        arr.setflags(write=False)
    return {"covariance": reported, "std": std, "residuals": r, "normalized_residuals": w,
            "chi2": chi2, "variance_factor": var_factor, "covariance_noise": cov,
            "covariance_birge": birge, "std_birge": std_birge, "fit_quality": quality}
