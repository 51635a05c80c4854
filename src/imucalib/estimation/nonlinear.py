"""Nonlinear least squares with covariance from the Jacobian at the solution.

Contents
--------
:class:`NlsSolution`
    Estimate, covariance, residuals, χ², variance factor, conditioning, solver diagnostics.
:func:`solve_nonlinear_lsq`
    Pure solver for min ‖W·r(x)‖² on :func:`scipy.optimize.least_squares`.

Method
------
The residual function r(x) (observation minus model, or the reverse, in observation units) is
whitened by W = C^{-1/2} and minimised with the trust-region reflective method [1]_. At the
solution x̂ the whitened Jacobian J = W·∂r/∂x (analytic when `jac` is given, otherwise central
differences) is checked like a linear design (:mod:`~imucalib.estimation.observability`) and
gives the Gauss–Newton covariance [2]_::

    Σ_x = (Jᵀ J)⁻¹ (× σ̂₀² = χ²/ν when the noise level is unknown)               (1)

the same expressions as Eqs. (2)–(7) of :mod:`~imucalib.estimation.linear` with H replaced by J
(the same misfit rule and Birge-scaled covariance: the linear solver's statistics are reused).
Eq. (1) is the inverse Fisher information at x̂ (the Cramér–Rao bound of the linearised model,
:mod:`~imucalib.estimation.crlb`); it is accurate when the model is close to linear over a few
standard deviations of x̂ — the closed-loop tests check it against Monte-Carlo spreads.

References
----------
.. [1] M. A. Branch, T. F. Coleman and Y. Li, "A subspace, interior, and conjugate gradient
   method for large-scale bound-constrained minimization problems", SIAM J. Sci. Comput.
   21(1):1–23, 1999 (scipy's ``method="trf"``).
.. [2] G. A. F. Seber and C. J. Wild, *Nonlinear Regression*, Wiley, 1989, §2.1 (asymptotic
   covariance (JᵀJ)⁻¹σ²).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.optimize
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import ConvergenceError, InvalidInputError
from imucalib.estimation._common import as_names, make_whitener
from imucalib.estimation.linear import LsqStatistics, _factorise, _fit_statistics
from imucalib.estimation.observability import DEFAULT_COND_LIMIT

__all__ = ["NlsSolution", "ResidualFunction", "solve_nonlinear_lsq"]

#: r(x) -> residuals, shape (m,), in observation units.
ResidualFunction = Callable[[NDArray[np.float64]], ArrayLike]


@dataclass(frozen=True, eq=False)
class NlsSolution(LsqStatistics):
    """Result of a nonlinear least-squares fit. Arrays are read-only.

    The statistics are those of :class:`~imucalib.estimation.linear.LsqStatistics` with the
    design H replaced by the Jacobian at x̂: `covariance` is Eq. (1) of
    :mod:`~imucalib.estimation.nonlinear` (the scaled one when `covariance_scaled`).

    Attributes
    ----------
    param_names, estimate, covariance, std, residuals, normalized_residuals, chi2, dof
        As in :class:`~imucalib.estimation.linear.LsqStatistics` (r = r(x̂)).
    variance_factor, covariance_scaled, condition_number, rank, observability
        As there, for the whitened Jacobian at x̂.
    covariance_noise, covariance_birge, std_birge, fit_quality
        As there (noise-only covariance, Birge-scaled covariance on a misfit, the one misfit
        rule).
    jacobian : ndarray, shape (m, p)
        ∂r/∂x at x̂ (not whitened).
    n_evaluations : int
        Residual-function evaluations used by the optimiser (finite differences excluded).
    message : str
        The optimiser's termination message.
    """

    jacobian: NDArray[np.float64]
    n_evaluations: int
    message: str


def solve_nonlinear_lsq(
    residual_fn: ResidualFunction,
    x0: ArrayLike,
    *,
    param_names: Sequence[str],
    jac: Callable[[NDArray[np.float64]], ArrayLike] | None = None,
    sigma: ArrayLike | None = None,
    covariance: ArrayLike | None = None,
    scale_covariance: bool | None = None,
    bounds: tuple[ArrayLike, ArrayLike] | None = None,
    cond_limit: float = DEFAULT_COND_LIMIT,
    x_tol: float = 1e-12,
    f_tol: float = 1e-12,
    max_evaluations: int | None = None,
) -> NlsSolution:
    """Minimise ‖W·r(x)‖² and report the covariance at the solution (module docstring).

    Parameters
    ----------
    residual_fn : callable
        r(x) for x of shape (p,), returning shape (m,) with m fixed. [observation units]
    x0 : array_like, shape (p,)
        Starting point. [parameter units]
    param_names : sequence of str, length p
        Parameter names.
    jac : callable, optional
        ∂r/∂x, returning shape (m, p); central differences when omitted.
    sigma : float or array_like, shape (m,), optional
        Standard deviation of each residual [observation units]; at most one of `sigma`,
        `covariance`.
    covariance : float or array_like, shape (m,) or (m, m), optional
        Residual noise covariance. [observation units²]
    scale_covariance : bool, optional
        Report the scaled covariance; default True when no noise is given (unknown level,
        estimated by σ̂₀²), else False (:func:`~imucalib.estimation.linear.solve_weighted_lsq`).
    bounds : (array_like, array_like), optional
        Lower and upper bounds of x (each shape (p,) or scalar). The covariance ignores them: a
        solution on a bound has no meaningful Gaussian covariance.
    cond_limit : float
        κ_max for the observability check of the Jacobian at x̂.
    x_tol, f_tol : float
        Relative tolerances on the step and on the cost (``xtol``, ``ftol`` of scipy).
    max_evaluations : int, optional
        Limit on residual evaluations (scipy's default 100·p when omitted).

    Returns
    -------
    NlsSolution
        The solution and its diagnostics.

    Raises
    ------
    InvalidInputError
        If `x0` or the residuals are not finite, have the wrong shape, the names do not match, or
        the covariance must be scaled with ν = 0.
    InsufficientExcitationError
        If the Jacobian at x̂ is rank-deficient or κ > `cond_limit`; names the parameters involved.
    ConvergenceError
        If the optimiser stops on its evaluation limit.
    """
    x_start = as_array(x0, "x0")
    if x_start.ndim != 1 or x_start.size < 1:
        raise InvalidInputError(f"`x0` must have shape (p,) with p ≥ 1; got {x_start.shape}")
    p = x_start.size
    names = as_names(param_names, p)
    r0 = _call_residuals(residual_fn, x_start, None)
    m = r0.size
    whitener, known = make_whitener(m, covariance=covariance, sigma=sigma)
    scale = (not known) if scale_covariance is None else bool(scale_covariance)
    dof = m - p
    if scale and not known and dof <= 0:
        raise InvalidInputError(
            "estimating the noise level from the residuals needs more residuals "
            f"than parameters; got m = {m}, p = {p} (give the noise, or scale_covariance=False)"
        )

    def fun(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return whitener.whiten(_call_residuals(residual_fn, x, m))

    jac_arg: Callable[[NDArray[np.float64]], NDArray[np.float64]] | str = "3-point"
    if jac is not None:
        def jac_w(x: NDArray[np.float64]) -> NDArray[np.float64]:
            return whitener.whiten(_call_jacobian(jac, x, m, p))
        jac_arg = jac_w
    lsq_bounds: tuple[ArrayLike, ArrayLike] = (-np.inf, np.inf) if bounds is None else bounds
    res = scipy.optimize.least_squares(
        fun, x_start, jac=jac_arg, bounds=lsq_bounds, method="trf", x_scale="jac",
        xtol=x_tol, ftol=f_tol, gtol=1e-15, max_nfev=max_evaluations,
    )
    if res.status <= 0:
        raise ConvergenceError(
            f"nonlinear least squares did not converge (expected status 1–4; got {res.status}: "
            f"{res.message}) after {res.nfev} evaluations"
        )
    x_hat = np.asarray(res.x, dtype=np.float64)
    J = np.asarray(res.jac, dtype=np.float64)  # whitened
    if not np.all(np.isfinite(J)):
        raise InvalidInputError("the Jacobian at the solution must be finite; got NaN or inf")
    U, s, vt, report = _factorise(J, names, cond_limit)
    report.raise_if_unobservable("Jacobian at the solution")
    r = _call_residuals(residual_fn, x_hat, m)
    stats = _fit_statistics(U, s, vt, report.column_norms, whitener, r, dof, scale=scale,
                            estimated=scale and not known)
    J_raw = whitener.colour(J)
    for arr in (x_hat, J_raw):
        arr.setflags(write=False)
    return NlsSolution(
        param_names=names, estimate=x_hat, dof=dof, covariance_scaled=scale,
        condition_number=report.condition_number, rank=report.rank, observability=report,
        jacobian=J_raw, n_evaluations=int(res.nfev), message=str(res.message), **stats,
    )


def _call_residuals(fn: ResidualFunction, x: NDArray[np.float64], m: int | None
                    ) -> NDArray[np.float64]:
    r = np.asarray(fn(np.array(x, dtype=np.float64)), dtype=np.float64)
    if r.ndim != 1 or (m is not None and r.size != m) or r.size < 1:
        want = "(m,)" if m is None else f"({m},)"
        raise InvalidInputError(f"`residual_fn` must return shape {want}; got {r.shape}")
    if not np.all(np.isfinite(r)):
        raise InvalidInputError(
            f"`residual_fn` must return finite values; got {int(np.sum(~np.isfinite(r)))} NaN or "
            f"infinite value(s) at x = {np.array2string(x, precision=6)}"
        )
    return r


def _call_jacobian(fn: Callable[[NDArray[np.float64]], ArrayLike], x: NDArray[np.float64],
                   m: int, p: int) -> NDArray[np.float64]:
    J = np.asarray(fn(np.array(x, dtype=np.float64)), dtype=np.float64)
    if J.shape != (m, p):
        raise InvalidInputError(f"`jac` must return shape ({m}, {p}); got {J.shape}")
    if not np.all(np.isfinite(J)):
        raise InvalidInputError("`jac` must return finite values; got NaN or inf")
    return J
