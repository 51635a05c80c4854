"""Rank and conditioning of a (whitened) linear or linearised design, naming what it cannot see.

Contents
--------
:class:`ObservabilityReport`
    Singular values, numerical rank and condition number of the column-scaled design, the
    (near-)null directions and the parameters that take part in them.
:func:`compute_observability`
    Pure function building that report; :meth:`ObservabilityReport.raise_if_unobservable` turns a
    bad report into :class:`~imucalib.errors.InsufficientExcitationError`.

Method
------
The whitened design A = C^{-1/2}·H (m × p) is first *column-scaled*, Ā = A·D with
D = diag(1/‖A_{:,j}‖) (a zero column keeps scale 1), so that the result does not depend on the
units of the parameters (a bias in m/s² next to a dimensionless scale factor) [1]_. The singular
value decomposition Ā = U·S·Vᵀ gives:

- the numerical rank r = #{sᵢ > max(m, p)·ε·s₁} (the tolerance of ``numpy.linalg.matrix_rank``);
- the condition number κ = s₁/s_p (∞ when r < p);
- the *weak* subspace spanned by the right singular vectors vᵢ with sᵢ ≤ s₁/κ_max (this
  includes the exact null space) — moving the scaled parameters along vᵢ changes the fit by at
  most s₁/κ_max relative to the best-determined direction;
- the participation of parameter j in that subspace, πⱼ = Σᵢ vᵢⱼ² (the j-th diagonal element of
  the orthogonal projector onto it; it does not depend on the choice of basis, πⱼ ∈ [0, 1]).
  πⱼ = 1: the parameter alone is unobservable; a null vector (1, −1)/√2 gives π = ½ to each of
  the two parameters whose sum is all the data can determine.

The design fails when r < p or κ > κ_max; the parameters with πⱼ ≥ ``participation_threshold``
are reported as unobservable, with each weak direction spelled out in the message.

References
----------
.. [1] Å. Björck, *Numerical Methods for Least Squares Problems*, SIAM, 1996, §2.7 (column
   scaling and condition) and §1.3 (rank determination by SVD).
.. [2] G. H. Golub and C. F. Van Loan, *Matrix Computations*, 4th ed., 2013, §5.4.1.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import check_positive
from imucalib.errors import InsufficientExcitationError, InvalidInputError
from imucalib.estimation._common import as_design, as_names

__all__ = ["DEFAULT_COND_LIMIT", "ObservabilityReport", "compute_observability",
           "report_from_svd"]

#: Default largest acceptable condition number of the column-scaled, whitened design. A value
#: of 1e10 still leaves about 6 significant digits in double precision.
DEFAULT_COND_LIMIT = 1e10

_MAX_DIRECTIONS_SHOWN = 4
_MAX_TERMS_SHOWN = 6


@dataclass(frozen=True, eq=False)
class ObservabilityReport:
    """Rank and conditioning of a column-scaled, whitened design.

    Attributes
    ----------
    param_names : tuple of str
        Parameter (column) names.
    singular_values : ndarray, shape (p,)
        Singular values of the column-scaled design, descending (zeros appended when m < p).
    rank : int
        Numerical rank.
    condition_number : float
        s₁/s_p of the column-scaled design; ``inf`` when rank-deficient.
    cond_limit : float
        The limit κ_max it was checked against.
    column_norms : ndarray, shape (p,)
        ‖A_{:,j}‖ of the whitened design (the inverse of the column scaling).
    weak_directions : ndarray, shape (p, q)
        Unit right singular vectors (in column-scaled parameters) with sᵢ ≤ s₁/κ_max, weakest last.
    participation : ndarray, shape (p,)
        πⱼ, each parameter's share of the weak subspace (module docstring), in [0, 1].
    unobservable : tuple of str
        Names of the parameters with πⱼ ≥ the participation threshold.
    """

    param_names: tuple[str, ...]
    singular_values: NDArray[np.float64]
    rank: int
    condition_number: float
    cond_limit: float
    column_norms: NDArray[np.float64]
    weak_directions: NDArray[np.float64]
    participation: NDArray[np.float64]
    unobservable: tuple[str, ...]

    @property
    def is_observable(self) -> bool:
        """True when the design has full rank and κ ≤ κ_max."""
        p = len(self.param_names)
        return self.rank == p and self.condition_number <= self.cond_limit

    def describe(self) -> str:
        """Return a one-paragraph account: rank, condition and each weak direction."""
        p = len(self.param_names)
        text = (f"rank {self.rank} of {p}, condition number {self.condition_number:.3g} "
                f"(limit {self.cond_limit:.3g})")
        if self.weak_directions.shape[1] == 0:
            return text
        parts = []
        for k in range(min(self.weak_directions.shape[1], _MAX_DIRECTIONS_SHOWN)):
            parts.append(_direction_text(self.weak_directions[:, k], self.param_names))
        extra = self.weak_directions.shape[1] - len(parts)
        more = f"; and {extra} more" if extra > 0 else ""
        return text + "; weak direction(s) in column-scaled parameters: " + "; ".join(parts) + more

    def raise_if_unobservable(self, context: str = "design", advice: str | None = None) -> None:
        """Raise :class:`InsufficientExcitationError` when the design fails the check.

        Parameters
        ----------
        context : str
            What the design is, for the message (``"design"``, ``"Jacobian at the solution"`` …).
        advice : str, optional
            What would make the parameters observable, appended to the message.

        Raises
        ------
        InsufficientExcitationError
            If rank < p or κ > κ_max; ``unobservable`` holds the parameter names involved.
        """
        if self.is_observable:
            return
        p = len(self.param_names)
        expected = (f"expected full rank {p} and condition number ≤ {self.cond_limit:.3g}")
        message = (f"the {context} cannot determine all parameters ({expected}; got "
                   f"{self.describe()}); unobservable: {', '.join(self.unobservable)}")
        if advice:
            message += f" — {advice}"
        raise InsufficientExcitationError(self.unobservable, message)


def compute_observability(
    design: ArrayLike,
    param_names: Sequence[str],
    *,
    cond_limit: float = DEFAULT_COND_LIMIT,
    participation_threshold: float = 0.01,
) -> ObservabilityReport:
    """Check the rank and conditioning of a whitened design (module docstring).

    Parameters
    ----------
    design : array_like, shape (m, p)
        Whitened design or Jacobian C^{-1/2}·H [1] (row weighting does not change the rank, but
        it changes the conditioning).
    param_names : sequence of str, length p
        Column names.
    cond_limit : float
        κ_max, the largest acceptable condition number of the column-scaled design, > 1.
    participation_threshold : float
        Smallest share πⱼ ∈ (0, 1] of the weak subspace for which a parameter is named.

    Returns
    -------
    ObservabilityReport
        The report; it does not raise (see :meth:`ObservabilityReport.raise_if_unobservable`).

    Raises
    ------
    InvalidInputError
        If `design` is not a finite (m, p) matrix, the names do not match its columns, or a
        limit is out of range.
    """
    A = as_design(design, "design")
    names = as_names(param_names, A.shape[1])
    kmax = check_positive(cond_limit, "cond_limit")
    if kmax <= 1.0:
        raise InvalidInputError(f"`cond_limit` must be > 1; got {kmax}")
    thr = check_positive(participation_threshold, "participation_threshold")
    if thr > 1.0:
        raise InvalidInputError(f"`participation_threshold` must be in (0, 1]; got {thr}")
    s, vt, norms = _scaled_svd(A)
    return _report(s, vt, norms, names, kmax, thr, A.shape)


def report_from_svd(s: NDArray[np.float64], vt: NDArray[np.float64], norms: NDArray[np.float64],
                    names: tuple[str, ...], shape: tuple[int, int], *,
                    cond_limit: float = DEFAULT_COND_LIMIT,
                    participation_threshold: float = 0.01) -> ObservabilityReport:
    """Build the report from an SVD already computed (for a solver that needs it anyway).

    Parameters
    ----------
    s : ndarray, shape (p,)
        Singular values of the column-scaled design A·D, descending (m ≥ p).
    vt : ndarray, shape (p, p)
        Its right singular vectors Vᵀ.
    norms : ndarray, shape (p,)
        ‖A_{:,j}‖ of the unscaled columns (D = diag(1/norms), a zero column scaled by 1).
    names : tuple of str
        Column names.
    shape : tuple of int
        (m, p) of A, for the rank tolerance.
    cond_limit, participation_threshold : float
        As for :func:`compute_observability`.

    Returns
    -------
    ObservabilityReport
        The same report as :func:`compute_observability` of A.
    """
    kmax = check_positive(cond_limit, "cond_limit")
    if kmax <= 1.0:
        raise InvalidInputError(f"`cond_limit` must be > 1; got {kmax}")
    return _report(np.array(s, dtype=np.float64), np.array(vt, dtype=np.float64),
                   np.array(norms, dtype=np.float64), names, kmax, participation_threshold,
                   shape)


def _scaled_svd(A: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                                   NDArray[np.float64]]:
    """Singular values (length p, descending, zero-padded), Vᵀ (p, p) and column norms of A."""
    m, p = A.shape
    norms = np.sqrt(np.einsum("ij,ij->j", A, A))
    scale = np.where(norms > 0.0, norms, 1.0)
    As = A / scale
    if m > 2 * p:  # R of a QR has the singular values and right vectors of As, at O(m·p²)
        As = np.asarray(np.linalg.qr(As, mode="r"), dtype=np.float64)
    _, s, vt = np.linalg.svd(As, full_matrices=True)
    s_full = np.zeros(p)
    s_full[: s.size] = s
    return s_full, vt, norms


def _report(s: NDArray[np.float64], vt: NDArray[np.float64], norms: NDArray[np.float64],
            names: tuple[str, ...], kmax: float, thr: float,
            shape: tuple[int, ...]) -> ObservabilityReport:
    p = len(names)
    s1 = float(s[0]) if s.size else 0.0
    tol = max(shape) * np.finfo(float).eps * s1
    rank = int(np.count_nonzero(s > tol)) if s1 > 0 else 0
    cond = float(s1 / s[-1]) if rank == p else float("inf")
    weak = s <= s1 / kmax if s1 > 0 else np.ones(p, dtype=bool)
    V = vt.T[:, weak]
    participation = np.einsum("ij,ij->i", V, V) if V.size else np.zeros(p)
    unobs = tuple(n for n, pj in zip(names, participation, strict=True) if pj >= thr)
    for arr in (s, norms, V, participation):
        arr.setflags(write=False)
    return ObservabilityReport(
        param_names=names, singular_values=s, rank=rank, condition_number=cond,
        cond_limit=kmax, column_norms=norms, weak_directions=V, participation=participation,
        unobservable=unobs,
    )


def _direction_text(v: NDArray[np.float64], names: tuple[str, ...]) -> str:
    order = np.argsort(-np.abs(v))
    big = [int(j) for j in order if v[j] ** 2 >= 1e-4][:_MAX_TERMS_SHOWN]
    sign = 1.0 if v[big[0]] >= 0 else -1.0  # first term positive, for a stable message
    terms = [f"{sign * v[j]:+.2f}·{names[j]}" for j in big]
    return " ".join(terms)
