"""Shared input checks and noise whitening of the estimation package (private).

A measurement model z = H·x + n with n ~ N(0, C) is *whitened* by W = L⁻¹, C = L·Lᵀ (Cholesky):
W·z = W·H·x + e with e ~ N(0, I). Diagonal C reduces to dividing each row by its σ.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg.lapack import dtrtrs as _dtrtrs

from imucalib._checks import as_array
from imucalib.errors import InsufficientExcitationError, InvalidInputError

__all__ = ["EstimateAccessors", "Whitener", "as_design", "as_names", "check_rank",
           "make_whitener"]


class EstimateAccessors:
    """Named views of a solution's estimate, uncertainty and correlation (linear and nonlinear)."""

    param_names: tuple[str, ...]
    estimate: NDArray[np.float64]
    covariance: NDArray[np.float64]
    std: NDArray[np.float64]

    def as_dict(self) -> Mapping[str, float]:
        """Return {name: estimate}."""
        return dict(zip(self.param_names, self.estimate.tolist(), strict=True))

    def std_dict(self) -> Mapping[str, float]:
        """Return {name: standard uncertainty}."""
        return dict(zip(self.param_names, self.std.tolist(), strict=True))

    def correlation(self) -> NDArray[np.float64]:
        """Return the correlation matrix of the estimate, shape (p, p)."""
        d = np.where(self.std > 0, self.std, 1.0)
        return np.asarray(self.covariance / np.outer(d, d), dtype=np.float64)


def as_design(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """Return a finite float64 matrix of shape (m, p) with m ≥ 1 and p ≥ 1."""
    arr = as_array(value, name, shape=(None, None))
    if arr.shape[0] < 1 or arr.shape[1] < 1:
        raise InvalidInputError(
            f"`{name}` must have at least one row and one column; got {arr.shape}"
        )
    return arr


def as_names(names: Sequence[str], n_params: int, name: str = "param_names") -> tuple[str, ...]:
    """Return `names` as a tuple of `n_params` distinct non-empty strings."""
    if isinstance(names, str):
        raise InvalidInputError(f"`{name}` must be a sequence of strings; got the string {names!r}")
    out = tuple(names)
    if len(out) != n_params:
        raise InvalidInputError(
            f"`{name}` must have {n_params} entries (one per column); got {len(out)}"
        )
    if not all(isinstance(s, str) and s for s in out):
        raise InvalidInputError(f"`{name}` must hold non-empty strings; got {list(out)!r}")
    if len(set(out)) != len(out):
        dup = sorted({s for s in out if out.count(s) > 1})
        raise InvalidInputError(f"`{name}` must be distinct; got duplicates {dup}")
    return out


@dataclass(frozen=True, eq=False)
class Whitener:
    """Noise whitening W = C^{-1/2} (Cholesky factor) for m observations.

    Attributes
    ----------
    sigma : ndarray, shape (m,)
        Standard deviation of each observation (square root of diag C).
    chol : ndarray, shape (m, m), or None
        Lower Cholesky factor L of a full C; None when C is diagonal.
    """

    sigma: NDArray[np.float64]
    chol: NDArray[np.float64] | None

    def whiten(self, a: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return W·a for a of shape (m,) or (m, p)."""
        if self.chol is None:
            return a / (self.sigma if a.ndim == 1 else self.sigma[:, None])
        return _solve_lower(self.chol, a, transposed=False)

    def whiten_transpose(self, a: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return Wᵀ·a = L⁻ᵀ·a for a of shape (m,) or (m, p) (the gain Kᵀ = Wᵀ·U·S⁻¹·Vᵀ·D)."""
        if self.chol is None:
            return a / (self.sigma if a.ndim == 1 else self.sigma[:, None])
        return _solve_lower(self.chol, a, transposed=True)

    def colour(self, a: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return L·a (the inverse of :meth:`whiten`) for a of shape (m,) or (m, p)."""
        if self.chol is None:
            return a * (self.sigma if a.ndim == 1 else self.sigma[:, None])
        return self.chol @ a


def _solve_lower(chol: NDArray[np.float64], a: NDArray[np.float64], *, transposed: bool
                 ) -> NDArray[np.float64]:
    """Return L⁻¹·a (or L⁻ᵀ·a) for the lower-triangular L by LAPACK's ``dtrtrs``.

    The call :func:`scipy.linalg.solve_triangular` makes (the same routine, arguments and
    results), without its per-call validation and dispatch, which cost about ten times the
    solve for the small systems of a fit (a P2 unit makes some 300 of them): a C-ordered L is
    passed as the upper-triangular Lᵀ in Fortran order with the transposition flipped.
    """
    if chol.flags.f_contiguous:
        x, info = _dtrtrs(chol, a, lower=1, trans=int(transposed))
    else:
        x, info = _dtrtrs(chol.T, a, lower=0, trans=int(not transposed))
    if info != 0:  # a Cholesky factor of a positive-definite matrix has no zero on its diagonal
        raise InvalidInputError(f"the covariance's Cholesky factor is singular (dtrtrs info "
                                f"{info})")
    return np.asarray(x, dtype=np.float64)


def make_whitener(m: int, *, weights: ArrayLike | None = None,
                  covariance: ArrayLike | None = None,
                  sigma: ArrayLike | None = None) -> tuple[Whitener, bool]:
    """Build the whitening of m observations from at most one noise description.

    Parameters
    ----------
    m : int
        Number of observations.
    weights : array_like, shape (m,), optional
        Inverse variances 1/σᵢ² [1/unit²], all > 0.
    covariance : float or array_like, shape (m,) or (m, m), optional
        A common variance, per-observation variances, or the full symmetric positive-definite
        covariance [unit²].
    sigma : float or array_like, shape (m,), optional
        A common standard deviation or one per observation [unit], all > 0.

    Returns
    -------
    Whitener
        The whitening.
    bool
        True when a noise description was given (the noise level is *known*).

    Raises
    ------
    InvalidInputError
        If more than one description is given, a shape differs from (m,) / (m, m), a value is not
        positive, or the covariance is not symmetric positive definite.
    """
    given = [n for n, v in (("weights", weights), ("covariance", covariance), ("sigma", sigma))
             if v is not None]
    if len(given) > 1:
        raise InvalidInputError(
            f"give at most one of `weights`, `covariance`, `sigma`; got {given}"
        )
    if weights is not None:
        w = _vector(weights, "weights", m)
        return Whitener(1.0 / np.sqrt(w), None), True
    if sigma is not None:
        return Whitener(_vector(sigma, "sigma", m), None), True
    if covariance is None:
        return Whitener(np.ones(m), None), False
    cov = as_array(covariance, "covariance")
    if cov.ndim <= 1:
        return Whitener(np.sqrt(_vector(cov, "covariance", m)), None), True
    if cov.shape != (m, m):
        raise InvalidInputError(
            f"`covariance` must be a scalar or have shape ({m},) or ({m}, {m}); got {cov.shape}"
        )
    # symmetric to rounding: |C_ij − C_ji| ≤ 1e-10·√(C_ii·C_jj) (a product such as P·C·Pᵀ is
    # symmetric only to rounding, also where an element should be zero)
    bound = 1e-10 * np.sqrt(np.abs(np.outer(np.diag(cov), np.diag(cov))))
    if np.any(np.abs(cov - cov.T) > bound):
        raise InvalidInputError("`covariance` must be symmetric; got max |C - Cᵀ| = "
                                f"{np.abs(cov - cov.T).max():.3g}")
    try:
        chol = np.linalg.cholesky(cov)
    except np.linalg.LinAlgError as exc:
        raise InvalidInputError("`covariance` must be positive definite; its Cholesky "
                                "factorisation failed") from exc
    return Whitener(np.sqrt(np.diag(cov)).copy(), np.asarray(chol, dtype=np.float64)), True


def _vector(value: ArrayLike, name: str, m: int) -> NDArray[np.float64]:
    arr = as_array(value, name)
    if arr.ndim == 0:
        arr = np.full(m, float(arr))
    if arr.shape != (m,):
        raise InvalidInputError(f"`{name}` must be a scalar or have shape ({m},); got {arr.shape}")
    if np.any(arr <= 0):
        raise InvalidInputError(f"`{name}` must be > 0; got {int(np.sum(arr <= 0))} value(s) ≤ 0 "
                                f"(min {arr.min():.6g})")
    return arr


def check_rank(jw: NDArray[np.float64], names: Sequence[str], *, subject: str, advice: str,
               weak_column: float = 0.0, weak_singular: float = 1e-6) -> None:
    """Refuse a rank-deficient whitened Jacobian `jw` (m, p), naming the parameters it misses.

    A column whose norm is at most `weak_column` times the largest is not excited at all; then
    the columns, each scaled to unit norm, must have no singular value under `weak_singular`
    times the largest (each weak right singular vector names its largest entry's parameter).

    Raises
    ------
    InsufficientExcitationError
        ``"{subject} do not excite [...] at all ({advice})"`` or ``"{subject} cannot separate
        [...] (the design is rank-deficient: {advice})"``.
    """
    scale = np.linalg.norm(jw, axis=0)
    dead = scale <= weak_column * scale.max()
    if np.any(dead):
        missing = [names[int(i)] for i in np.flatnonzero(dead)]
        raise InsufficientExcitationError(
            missing, f"{subject} do not excite {missing} at all ({advice})")
    _, s, vt = np.linalg.svd(jw / scale, full_matrices=False)
    weak = s < weak_singular * s[0]
    if weak.any():
        missing = sorted({names[int(np.argmax(np.abs(row)))] for row in vt[weak]})
        raise InsufficientExcitationError(
            missing, f"{subject} cannot separate {missing} (the design is rank-deficient: "
                     f"{advice})")
