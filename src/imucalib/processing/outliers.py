"""Outlier rejection by the 3σ rule and by the Grubbs test (P1 processing rule 1, docs/p1.md).

Contents
--------
:class:`OutlierResult`
    Cleaned values, the mask of flagged samples, counts per column, final location and scale.
:func:`reject_outliers_3sigma`
    Iterated n·σ rule with a robust (median / MAD) or classical (mean / standard deviation) scale.
:func:`reject_outliers_grubbs`
    Iterated two-sided Grubbs test, or Rosner's generalised ESD when `max_outliers` is given.

Both work per column of an (n,) or (n, k) array of samples from a *stationary* window (a static
position or a constant-rate step); remove trends first if the window has one. Flagged samples are
either replaced by linear interpolation between the nearest kept neighbours of the same column
(``method="interpolate"``; against `time_s` when given, else the sample index; the nearest kept
value at either end) or removed (``method="drop"``: a row is removed when any of its columns is
flagged, so that the columns stay aligned with their time stamps; `kept` says which rows stay).

3σ rule
-------
Flag |xᵢ − c| > n_σ·s, remove, recompute c and s from the kept samples, and repeat until nothing
new is flagged. With ``robust=True`` (default) c is the median and s = 1.4826·MAD (the median
absolute deviation scaled to σ for Gaussian data [1]_): one gross outlier can inflate the
classical standard deviation so much that it hides itself and others (*masking*), while the
MAD has a 50 % breakdown point. With ``robust=False`` c is the mean and s the sample standard
deviation (ddof = 1), the textbook rule P1 names; iteration mitigates but does not remove the
masking. If the MAD is zero (heavily quantised data) the standard deviation is used instead. On
clean Gaussian data about 0.3 % of the samples are flagged at n_σ = 3, as the rule implies.

Grubbs test
-----------
For the n kept samples, G = maxᵢ|xᵢ − x̄|/s (s with ddof = 1) is compared with [2]_, [3]_::

    G_crit(n) = (n − 1)/√n · √( t² / (n − 2 + t²) ),   t = t_{α/(2n), n−2}        (1)

the upper α/(2n) quantile of Student's t with n − 2 degrees of freedom (two-sided test at level
α). While G > G_crit the most extreme sample is removed and the test repeated (n ≥ 3). On clean
Gaussian data the first test rejects with probability ≈ α. The iterated test can be masked by
two similar outliers; with ``max_outliers = r`` Rosner's generalised extreme Studentised deviate
procedure [4]_ is used instead: the r most extreme samples are removed one at a time, giving
statistics R₁ … R_r and critical values λᵢ = G_crit(n − i + 1) (Eq. (1) for the sample size at
step i), and the number of outliers is the largest i with Rᵢ > λᵢ. The computation sorts each
column once and updates sums, so it costs O(n log n) however many outliers there are.

References
----------
.. [1] P. J. Rousseeuw and C. Croux, "Alternatives to the median absolute deviation", J. Amer.
   Statist. Assoc. 88(424):1273–1283, 1993.
.. [2] F. E. Grubbs, "Procedures for detecting outlying observations in samples",
   Technometrics 11(1):1–21, 1969.
.. [3] NIST/SEMATECH e-Handbook of Statistical Methods, §1.3.5.17 "Grubbs' test for outliers".
.. [4] B. Rosner, "Percentage points for a generalized ESD many-outlier procedure",
   Technometrics 25(2):165–172, 1983.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import stats

from imucalib._checks import check_positive
from imucalib.errors import InvalidInputError
from imucalib.processing._common import as_columns, as_time, restore_shape

__all__ = [
    "MAD_TO_SIGMA",
    "OutlierMethod",
    "OutlierResult",
    "grubbs_critical_value",
    "reject_outliers_3sigma",
    "reject_outliers_grubbs",
]

OutlierMethod = Literal["interpolate", "drop"]
#: 1/Φ⁻¹(3/4): the MAD of Gaussian data times this is σ.
MAD_TO_SIGMA = 1.482602218505602
_MIN_SAMPLES = 3


@dataclass(frozen=True, eq=False)
class OutlierResult:
    """Result of an outlier rejection. Arrays are read-only.

    Attributes
    ----------
    values : ndarray, shape like the input, or (n_kept,) / (n_kept, k) for ``method="drop"``
        Cleaned samples. [units of the input]
    outlier_mask : ndarray of bool, shape like the input
        True where the test flagged a sample.
    kept : ndarray of bool, shape (n,)
        Rows present in `values` (all True for ``method="interpolate"``).
    n_outliers : ndarray of int, shape (k,)
        Flagged samples per column (k = 1 for a 1-D input).
    center : ndarray, shape (k,)
        Final location estimate of the kept samples (median or mean). [units of the input]
    scale : ndarray, shape (k,)
        Final scale estimate (1.4826·MAD or standard deviation). [units of the input]
    n_iterations : ndarray of int, shape (k,)
        Passes (3σ) or tests (Grubbs) performed per column.
    test : str
        ``"3sigma"``, ``"3sigma-robust"``, ``"grubbs"`` or ``"generalized-esd"``.
    method : str
        ``"interpolate"`` or ``"drop"``.
    """

    values: NDArray[np.float64]
    outlier_mask: NDArray[np.bool_]
    kept: NDArray[np.bool_]
    n_outliers: NDArray[np.int64]
    center: NDArray[np.float64]
    scale: NDArray[np.float64]
    n_iterations: NDArray[np.int64]
    test: str
    method: str

    @property
    def n_removed_rows(self) -> int:
        """Rows dropped from `values` (0 for ``method="interpolate"``)."""
        return int(self.kept.size - np.count_nonzero(self.kept))


def reject_outliers_3sigma(
    values: ArrayLike,
    *,
    n_sigma: float = 3.0,
    robust: bool = True,
    method: OutlierMethod = "interpolate",
    time_s: ArrayLike | None = None,
    max_iterations: int = 50,
) -> OutlierResult:
    """Flag and replace or drop samples farther than n_σ·s from the centre (module docstring).

    Parameters
    ----------
    values : array_like, shape (n,) or (n, k)
        Samples of a stationary window, one column per channel. [any unit]
    n_sigma : float
        Threshold in units of the scale estimate, > 0 (3 for the 3σ rule).
    robust : bool
        Median and 1.4826·MAD (default) instead of mean and standard deviation.
    method : {"interpolate", "drop"}
        What to do with flagged samples.
    time_s : array_like, shape (n,), optional
        Strictly increasing sample times used for the interpolation. [s]
    max_iterations : int
        Upper bound on the passes per column, ≥ 1.

    Returns
    -------
    OutlierResult
        Cleaned values, mask, counts per column and the final centre and scale.

    Raises
    ------
    InvalidInputError
        If `values` has fewer than 3 rows, is not 1-D/2-D, or holds NaN or infinite values;
        `time_s` does not match or is not strictly increasing; `method` or a number is invalid.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.array([0.1, -0.2, 0.0, 0.3, -0.1, 8.0, 0.2, -0.3, 0.1, 0.0])
    >>> res = reject_outliers_3sigma(x)
    >>> res.n_outliers.tolist(), round(float(res.values[5]), 12)
    ([1], 0.05)
    """
    cols, one_d = as_columns(values, "values", min_samples=_MIN_SAMPLES)
    n_s = check_positive(n_sigma, "n_sigma")
    _check_method(method)
    max_it = _check_count(max_iterations, "max_iterations", 1)
    t = None if time_s is None else as_time(time_s, "time_s", cols.shape[0])
    n, k = cols.shape
    mask = np.zeros((n, k), dtype=bool)
    center = np.empty(k)
    scale = np.empty(k)
    iters = np.zeros(k, dtype=np.int64)
    for j in range(k):
        x = cols[:, j]
        keep = np.ones(n, dtype=bool)
        for _ in range(max_it):
            iters[j] += 1
            c, s = _location_scale(x[keep], robust)
            new = keep & (np.abs(x - c) > n_s * s)
            if not new.any():
                break
            keep &= ~new
        center[j], scale[j] = _location_scale(x[keep], robust)
        mask[:, j] = ~keep
    test = "3sigma-robust" if robust else "3sigma"
    return _finish(cols, one_d, mask, center, scale, iters, test, method, t)


def reject_outliers_grubbs(
    values: ArrayLike,
    *,
    alpha: float = 0.05,
    max_outliers: int | None = None,
    method: OutlierMethod = "interpolate",
    time_s: ArrayLike | None = None,
) -> OutlierResult:
    """Flag outliers by the iterated two-sided Grubbs test or the generalised ESD.

    Parameters
    ----------
    values : array_like, shape (n,) or (n, k)
        Samples of a stationary window, one column per channel, n ≥ 3. [any unit]
    alpha : float
        Significance level of each test, in (0, 1).
    max_outliers : int, optional
        Upper bound r for Rosner's generalised ESD (robust to masking); when omitted the classic
        iterated Grubbs test (stop at the first non-significant test) is used.
    method : {"interpolate", "drop"}
        What to do with flagged samples.
    time_s : array_like, shape (n,), optional
        Strictly increasing sample times used for the interpolation. [s]

    Returns
    -------
    OutlierResult
        Cleaned values, mask, counts per column, and the mean and standard deviation of the kept
        samples.

    Raises
    ------
    InvalidInputError
        If `values` has fewer than 3 rows or non-finite values, `alpha` is outside (0, 1),
        `max_outliers` is not in [1, n − 2], or `method` / `time_s` is invalid.
    """
    cols, one_d = as_columns(values, "values", min_samples=_MIN_SAMPLES)
    a = check_positive(alpha, "alpha")
    if a >= 1.0:
        raise InvalidInputError(f"`alpha` must be in (0, 1); got {a}")
    _check_method(method)
    t = None if time_s is None else as_time(time_s, "time_s", cols.shape[0])
    n, k = cols.shape
    r_max = None
    if max_outliers is not None:
        r_max = _check_count(max_outliers, "max_outliers", 1)
        if r_max > n - 2:
            raise InvalidInputError(f"`max_outliers` must be ≤ n − 2 = {n - 2}; got {r_max}")
    mask = np.zeros((n, k), dtype=bool)
    center = np.empty(k)
    scale = np.empty(k)
    iters = np.zeros(k, dtype=np.int64)
    for j in range(k):
        flagged, iters[j] = _grubbs_column(cols[:, j], a, r_max)
        mask[flagged, j] = True
        kept = cols[~mask[:, j], j]
        center[j] = kept.mean()
        scale[j] = kept.std(ddof=1)
    test = "grubbs" if r_max is None else "generalized-esd"
    return _finish(cols, one_d, mask, center, scale, iters, test, method, t)


def grubbs_critical_value(n_samples: int | NDArray[np.int64], alpha: float
                          ) -> float | NDArray[np.float64]:
    """Return G_crit of Eq. (1) (module docstring): the two-sided Grubbs critical value.

    Parameters
    ----------
    n_samples : int or array of int
        Sample size n ≥ 3.
    alpha : float
        Significance level in (0, 1).

    Returns
    -------
    float or ndarray
        G_crit(n) [–] (in units of the sample standard deviation).

    Examples
    --------
    >>> print(f"{grubbs_critical_value(10, 0.05):.3f}")   # NIST e-Handbook table: 2.290
    2.290
    """
    n = np.asarray(n_samples, dtype=np.float64)
    t = stats.t.isf(alpha / (2.0 * n), n - 2.0)  # Eq. (1)
    g = (n - 1.0) / np.sqrt(n) * np.sqrt(t**2 / (n - 2.0 + t**2))
    return float(g) if np.ndim(g) == 0 else np.asarray(g, dtype=np.float64)


def _grubbs_column(x: NDArray[np.float64], alpha: float, r_max: int | None
                   ) -> tuple[NDArray[np.int64], int]:
    """Return the indices flagged in one column and the number of tests performed."""
    n = x.size
    order = np.argsort(x, kind="stable")
    xs = x[order] - np.median(x)  # centred: the running sums below keep their precision
    s1 = np.concatenate([[0.0], np.cumsum(xs)])
    s2 = np.concatenate([[0.0], np.cumsum(xs * xs)])
    lo, hi = 0, n - 1
    limit = n - 2 if r_max is None else r_max
    removed: list[int] = []
    significant: list[bool] = []
    while len(removed) < limit and hi - lo + 1 >= _MIN_SAMPLES:
        m = hi - lo + 1
        tot1 = s1[hi + 1] - s1[lo]
        tot2 = s2[hi + 1] - s2[lo]
        mean = tot1 / m
        var = max((tot2 - tot1 * mean) / (m - 1), 0.0)
        if var == 0.0:
            break
        d_lo, d_hi = mean - xs[lo], xs[hi] - mean
        g = max(d_lo, d_hi) / np.sqrt(var)
        crit = float(grubbs_critical_value(m, alpha))
        significant.append(g > crit)
        if r_max is None and not significant[-1]:
            break
        if d_hi >= d_lo:
            removed.append(hi)
            hi -= 1
        else:
            removed.append(lo)
            lo += 1
    n_tests = len(significant)
    if r_max is None:
        n_out = n_tests - 1 if n_tests and not significant[-1] else n_tests
    else:  # generalised ESD: the largest i with R_i > λ_i
        hits = np.flatnonzero(significant)
        n_out = int(hits[-1]) + 1 if hits.size else 0
    return order[np.asarray(removed[:n_out], dtype=np.int64)], n_tests


def _location_scale(x: NDArray[np.float64], robust: bool) -> tuple[float, float]:
    """(median, 1.4826·MAD) or (mean, standard deviation); the latter scale when the MAD is 0."""
    if not robust:
        return float(np.mean(x)), float(np.std(x, ddof=1))
    c = float(np.median(x))
    s = MAD_TO_SIGMA * float(np.median(np.abs(x - c)))
    return c, (s if s > 0.0 else float(np.std(x, ddof=1)))


def _finish(cols: NDArray[np.float64], one_d: bool, mask: NDArray[np.bool_],
            center: NDArray[np.float64], scale: NDArray[np.float64], iters: NDArray[np.int64],
            test: str, method: str, t: NDArray[np.float64] | None) -> OutlierResult:
    n = cols.shape[0]
    if method == "drop":
        kept = np.asarray(~mask.any(axis=1), dtype=bool)
        out = cols[kept].copy()
    else:
        kept = np.ones(n, dtype=bool)
        out = cols.copy()
        axis = np.arange(n, dtype=np.float64) if t is None else t
        for j in np.flatnonzero(mask.any(axis=0)):
            good = ~mask[:, j]
            out[mask[:, j], j] = np.interp(axis[mask[:, j]], axis[good], cols[good, j])
    n_out = mask.sum(axis=0).astype(np.int64)
    values = restore_shape(out, one_d)
    mask_out = mask[:, 0].copy() if one_d else mask
    for arr in (values, mask_out, kept, n_out, center, scale, iters):
        arr.setflags(write=False)
    return OutlierResult(values=values, outlier_mask=mask_out, kept=kept, n_outliers=n_out,
                         center=center, scale=scale, n_iterations=iters, test=test,
                         method=method)


def _check_method(method: str) -> None:
    if method not in ("interpolate", "drop"):
        raise InvalidInputError(f"`method` must be 'interpolate' or 'drop'; got {method!r}")


def _check_count(value: object, name: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise InvalidInputError(f"`{name}` must be an integer ≥ {minimum}; got {value!r}")
    return int(value)
