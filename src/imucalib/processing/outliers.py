"""Outlier rejection: a robust single-pass rule, the 3σ rule and the Grubbs test (docs/p1.md).

Contents
--------
:func:`reject_outliers_robust`
    One pass against a robust running median, with a threshold that grows with the window length
    so that Gaussian data loses essentially nothing (P1's default).
:class:`OutlierResult`
    Cleaned values, the mask of flagged samples, counts per column, final location and scale.
:func:`reject_outliers_3sigma`
    Iterated n·σ rule with a robust (median / MAD) or classical (mean / standard deviation) scale.
:func:`reject_outliers_grubbs`
    Iterated two-sided Grubbs test, or Rosner's generalised ESD when `max_outliers` is given.

All work per column of an (n,) or (n, k) array of samples from a *stationary* window (a static
position or a constant-rate step); remove trends first if the window has one. Flagged samples are
either replaced by linear interpolation between the nearest kept neighbours of the same column
(``method="interpolate"``; against `time_s` when given, else the sample index; the nearest kept
value at either end) or removed (``method="drop"``: a row is removed when any of its columns is
flagged, so that the columns stay aligned with their time stamps; `kept` says which rows stay).

Robust rule
-----------
The centre of sample i is the running median ĉᵢ of its 2h neighbours x_{i−h} … x_{i+h}, xᵢ left
out (a Hampel identifier [5]_; h = 4 by default; leaving xᵢ out keeps the deviations Gaussian
for Gaussian data, so that the MAD measures their tails). A slowly varying signal in the window
— the once-per-revolution harmonic that g-sensitivity, Earth rate and gravity put into a rate
window — is followed and not flagged, while a cluster of up to h − 1 outliers cannot move it.
For the first and last h samples ĉ is extrapolated along the line through ĉ_h and ĉ_{2h} (at
the end: ĉ_{n−1−h} and ĉ_{n−1−2h}), so that a slope does not bias the edges. The scale is one
number per column, s = 1.4826·MAD of the deviations rᵢ = xᵢ − ĉᵢ [1]_ (their standard
deviation if the MAD is 0). One pass flags [6]_::

    |rᵢ| > k(n)·s + mᵢ,   k(n) = max(k_min, Φ⁻¹(1 − α_n/2)),   α_n = 1 − (1 − α)^{1/n}          (2)

so that a window of n Gaussian samples loses any sample at all with probability α (≈ α/(2n)
per tail and sample: the Šidák/Bonferroni form of Chauvenet's criterion). With α = 0.01:
k = 4.42 for n = 10³, 4.89 for 10⁴, 5.33 for 10⁵ and 5.73 for 10⁶ (k_min = 3.5 for n < 22).
A single pass suffices: the median and the MAD are not inflated by the outliers they seek, and
iterating would only erode the Gaussian tails. The running median follows a smooth signal
exactly where it is monotone over 2h + 1 samples; at an extremum of a sinusoid of amplitude A and
period P samples it cuts the peak by about A·(πh/P)²/2 (A = 100 σ at P = 200 samples, h = 4:
0.2 σ), and the straight edge extrapolation misses the curvature by up to 16·A·(πh/P)² (6 σ).
The margin mᵢ covers both: |Δ²ᵢ|/4 inside, with Δ²ᵢ = ĉ_{i−h} − 2ĉᵢ + ĉ_{i+h} (≈ 2× the cut),
and on the i-th edge sample |Δ²|·(h − i)(2h − i)/(2h²), the quadratic term the line leaves out;
on noise alone it is a fraction of s.

3σ rule
-------
Flag |xᵢ − c| > n_σ·s, remove, recompute c and s from the kept samples, and repeat until nothing
new is flagged. With ``robust=True`` (default) c is the median and s = 1.4826·MAD (the median
absolute deviation scaled to σ for Gaussian data [1]_): one gross outlier can inflate the
classical standard deviation so much that it hides itself and others (*masking*), while the
MAD has a 50 % breakdown point. With ``robust=False`` c is the mean and s the sample standard
deviation (ddof = 1), the textbook rule P1 names; iteration mitigates but does not remove the
masking. If the MAD is zero (heavily quantised data) the standard deviation is used instead. On
clean Gaussian data about 0.3 % of the samples are flagged at n_σ = 3, as the rule implies, and
each further pass flags about as many again (the scale of the kept samples shrinks): three passes
remove ≈ 1 % of purely Gaussian data, truncating its distribution and biasing every noise figure
computed afterwards. P1 names this rule; :func:`reject_outliers_robust` is the default there.

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
.. [5] R. K. Pearson, "Outliers in process modeling and identification", IEEE Trans. Control
   Systems Technology 10(1):55–63, 2002 (the Hampel filter).
.. [6] L. Davies and U. Gather, "The identification of multiple outliers", J. Amer. Statist.
   Assoc. 88(423):782–792, 1993 (the α_n = 1 − (1 − α)^{1/n} outlier region).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import stats

from imucalib._checks import check_positive
from imucalib.errors import InvalidInputError
from imucalib.processing._common import as_columns, as_time, restore_shape
from imucalib.processing._flag_kernel import flag_far, residuals
from imucalib.processing._flag_kernel import kernels as flag_kernels
from imucalib.processing._median_kernel import curvature_margin, neighbour_median
from imucalib.processing._select_kernel import median, median_abs_deviation

__all__ = [
    "MAD_TO_SIGMA",
    "OutlierMethod",
    "OutlierResult",
    "grubbs_critical_value",
    "reject_outliers_3sigma",
    "reject_outliers_grubbs",
    "reject_outliers_robust",
    "robust_threshold",
]

OutlierMethod = Literal["interpolate", "drop"]
#: 1/Φ⁻¹(3/4): the MAD of Gaussian data times this is σ.
MAD_TO_SIGMA = 1.482602218505602
_MIN_SAMPLES = 3
_Center = NDArray[np.float64] | Callable[[], NDArray[np.float64]]


@dataclass(frozen=True, eq=False, init=False)
class OutlierResult:
    """Result of an outlier rejection. Arrays are read-only.

    `center` may be given as a function of no arguments that returns it: it is then computed
    on first access and kept (the robust rule's P1 caller never reads it).

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
        Passes (3σ, robust: 1) or tests (Grubbs) performed per column.
    test : str
        ``"robust"``, ``"3sigma"``, ``"3sigma-robust"``, ``"grubbs"`` or ``"generalized-esd"``.
    method : str
        ``"interpolate"`` or ``"drop"``.
    threshold : float
        The threshold k in units of `scale` (Eq. (2) for the robust rule, n_σ for the 3σ rule);
        NaN for the Grubbs test, whose critical value changes with each test.
    """

    values: NDArray[np.float64]
    outlier_mask: NDArray[np.bool_]
    kept: NDArray[np.bool_]
    n_outliers: NDArray[np.int64]
    scale: NDArray[np.float64]
    n_iterations: NDArray[np.int64]
    test: str
    method: str
    threshold: float
    _center: _Center = field(repr=False)

    def __init__(self, values: NDArray[np.float64], outlier_mask: NDArray[np.bool_],
                 kept: NDArray[np.bool_], n_outliers: NDArray[np.int64], center: _Center,
                 scale: NDArray[np.float64], n_iterations: NDArray[np.int64], test: str,
                 method: str, threshold: float = math.nan) -> None:
        fields = {"values": values, "outlier_mask": outlier_mask, "kept": kept,
                  "n_outliers": n_outliers, "scale": scale, "n_iterations": n_iterations,
                  "test": test, "method": method, "threshold": threshold, "_center": center}
        for name, value in fields.items():
            object.__setattr__(self, name, value)

    @property
    def center(self) -> NDArray[np.float64]:
        """Final location estimate per column (see the class docstring), read-only."""
        found = self._center
        if callable(found):
            found = found()
            found.setflags(write=False)
            object.__setattr__(self, "_center", found)
        return found

    @property
    def outlier_indices(self) -> tuple[NDArray[np.int64], ...]:
        """Rows flagged in each column (one array per column, ascending), to say where."""
        mask = self.outlier_mask[:, None] if self.outlier_mask.ndim == 1 else self.outlier_mask
        return tuple(np.flatnonzero(mask[:, j]).astype(np.int64) for j in range(mask.shape[1]))

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
    return _finish(cols, one_d, mask, center, scale, iters, test, method, t, n_s)


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


def robust_threshold(n_samples: int, alpha: float = 0.01, min_threshold: float = 3.5) -> float:
    """Return k(n) of Eq. (2) (module docstring): the robust rule's threshold in units of s.

    Parameters
    ----------
    n_samples : int
        Samples in the column, n ≥ 1.
    alpha : float
        Probability that a column of n Gaussian samples loses any sample, in (0, 1).
    min_threshold : float
        Floor k_min, > 0.

    Returns
    -------
    float
        k(n) = max(k_min, Φ⁻¹(1 − α_n/2)), α_n = 1 − (1 − α)^{1/n}. [–]

    Examples
    --------
    >>> [round(robust_threshold(n), 2) for n in (10**3, 10**4, 10**5, 10**6)]
    [4.42, 4.89, 5.33, 5.73]
    """
    n = _check_count(n_samples, "n_samples", 1)
    a = check_positive(alpha, "alpha")
    if a >= 1.0:
        raise InvalidInputError(f"`alpha` must be in (0, 1); got {a}")
    k_min = check_positive(min_threshold, "min_threshold")
    alpha_n = -math.expm1(math.log1p(-a) / n)  # Eq. (2): 1 − (1 − α)^{1/n}
    return max(k_min, float(stats.norm.isf(alpha_n / 2.0)))


def reject_outliers_robust(
    values: ArrayLike,
    *,
    alpha: float = 0.01,
    half_width: int = 4,
    min_threshold: float = 3.5,
    method: OutlierMethod = "interpolate",
    time_s: ArrayLike | None = None,
) -> OutlierResult:
    """Flag samples far from a running median, in one pass, at the threshold k(n) of Eq. (2).

    The rule is the module docstring's "Robust rule": deviations from the running median of
    each sample's 2·`half_width` neighbours, scaled by 1.4826·MAD of those deviations, flagged
    beyond k(n) = max(k_min, Φ⁻¹(1 − α_n/2)), α_n = 1 − (1 − α)^{1/n}, so that a column of n
    Gaussian samples loses any sample with probability α.

    Parameters
    ----------
    values : array_like, shape (n,) or (n, k)
        Samples of a window, one column per channel, n ≥ 3; it may vary slowly (over many more
        than 2·`half_width` + 1 samples). [any unit]
    alpha : float
        Probability that a column of n Gaussian samples loses any sample, in (0, 1).
    half_width : int
        h ≥ 1: the running median takes the 2h neighbours of each sample; clusters of up to
        h − 1 adjacent outliers are found without flagging their good neighbours (a cluster of
        h makes half of an adjacent sample's neighbours, and the median breaks down).
    min_threshold : float
        Floor k_min of the threshold, > 0 (short windows).
    method : {"interpolate", "drop"}
        What to do with flagged samples.
    time_s : array_like, shape (n,), optional
        Strictly increasing sample times used for the interpolation. [s]

    Returns
    -------
    OutlierResult
        Cleaned values, mask (and :attr:`OutlierResult.outlier_indices`), counts per column,
        the median of the kept samples as `center` (computed when first read), s as `scale`
        and k(n) as `threshold`.

    Raises
    ------
    InvalidInputError
        If `values` has fewer than 3 rows, is not 1-D/2-D, or holds NaN or infinite values;
        `time_s` does not match or is not strictly increasing; `method` or a number is invalid.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.random.default_rng(1).normal(size=2000)
    >>> x[[100, 101, 1500]] += [12.0, -15.0, 9.0]
    >>> res = reject_outliers_robust(x)
    >>> res.outlier_indices[0].tolist(), round(res.threshold, 2)
    ([100, 101, 1500], 4.56)
    """
    cols, one_d = as_columns(values, "values", min_samples=_MIN_SAMPLES)
    h = _check_count(half_width, "half_width", 1)
    _check_method(method)
    t = None if time_s is None else as_time(time_s, "time_s", cols.shape[0])
    n, k = cols.shape
    k_n = robust_threshold(n, alpha, min_threshold)
    flagged, counts, scale = _robust_flags(cols, h, k_n)
    mask = flagged.T  # (n, k), each column contiguous
    iters = np.ones(k, dtype=np.int64)
    center = _kept_median(cols, mask)
    return _finish(cols, one_d, mask, center, scale, iters, "robust", method, t, k_n, counts)


def _robust_flags(cols: NDArray[np.float64], h: int, k_n: float, backend: str = "auto"
                  ) -> tuple[NDArray[np.bool_], NDArray[np.int64], NDArray[np.float64]]:
    """Return the flags (k, n), their counts per column and the scales s of the robust rule.

    With numba the residuals and the flags are two compiled passes per column
    (:mod:`._flag_kernel`: the margin computed as they go, the MAD selected without the
    deviations' array); with ``backend="numpy"`` or without numba numpy makes each step. The
    same operations in the same order: the same flags and scales bit for bit.
    """
    n, k = cols.shape
    by_column = np.ascontiguousarray(cols.T)  # each column contiguous: every pass below streams
    fused = None if backend == "numpy" else flag_kernels()
    flagged = np.empty((k, n), dtype=bool)
    counts = np.empty(k, dtype=np.int64)
    scale = np.empty(k)
    for j in range(k):
        x = by_column[j]
        if fused is not None and n >= 2 * (2 * h + 1):
            c = neighbour_median(x, h)
            r = residuals(x, c, h)  # the edges of c extrapolated, r = x − c
            med_r = median(r)  # np.median's value bit for bit, by Floyd–Rivest selection
            s = MAD_TO_SIGMA * median_abs_deviation(r, med_r)
            if s <= 0.0:
                s = float(np.std(r, ddof=1))
            counts[j] = flag_far(r, c, h, med_r, k_n * s, flagged[j])  # Eq. (2)
        else:
            c, margin = _running_median(x, h)
            r = x - c
            med_r = median(r, backend=backend)
            dev = np.abs(r - med_r)
            s = MAD_TO_SIGMA * median(dev, backend=backend)
            if s <= 0.0:
                s = float(np.std(r, ddof=1))
            np.greater(dev, k_n * s + margin, out=flagged[j])  # Eq. (2)
            counts[j] = np.count_nonzero(flagged[j])
        scale[j] = s
    return flagged, counts, scale


def _kept_median(cols: NDArray[np.float64], mask: NDArray[np.bool_]
                 ) -> Callable[[], NDArray[np.float64]]:
    """Return a function computing the median of each column's unflagged samples.

    :func:`_finish` overwrites only flagged samples of `cols` (``method="interpolate"``) or
    none (``"drop"``), so the unflagged ones keep their input values.
    """
    def center() -> NDArray[np.float64]:
        return np.array([median(cols[~mask[:, j], j]) for j in range(cols.shape[1])])

    return center


def _running_median(x: NDArray[np.float64], h: int
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Median of the 2h neighbours of each sample (itself left out), and its curvature margin.

    Leaving xᵢ out keeps xᵢ − ĉᵢ Gaussian for Gaussian data (with xᵢ in, ĉᵢ = xᵢ whenever xᵢ
    is the window's median, which piles deviations up at 0 and makes the MAD underestimate
    their tails). The first h samples get the line through ĉ_h and ĉ_{2h}, the last h the same
    at the other end, so that a slope does not bias the edges. The margin bounds what
    curvature does to ĉ, from the second difference Δ²ᵢ = ĉ_{i−h} − 2ĉᵢ + ĉ_{i+h}: |Δ²|/4
    inside (a running median cuts an extremum by ≈ f''·h²/8 = Δ²/8), |Δ²|·(h − i)(2h − i)/(2h²)
    on the extrapolated edges (the quadratic term the line leaves out). A column shorter than
    2(2h + 1) gets its median throughout and no margin.
    """
    n, w = x.size, 2 * h + 1
    if n < 2 * w:
        return np.full(n, median(x)), np.zeros(n)
    c = neighbour_median(x, h)  # a sorted window slid along x: O(n·h), no n × 2h copy
    return c, curvature_margin(c, h)  # the edges extrapolated, the margin (one compiled pass)


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
            center: _Center, scale: NDArray[np.float64], iters: NDArray[np.int64],
            test: str, method: str, t: NDArray[np.float64] | None,
            threshold: float = math.nan,
            counts: NDArray[np.int64] | None = None) -> OutlierResult:
    """Replace or drop the flagged samples; `counts`: the flags per column when known."""
    n = cols.shape[0]
    n_out = mask.sum(axis=0).astype(np.int64) if counts is None else counts
    if method == "drop":
        kept = (np.asarray(~mask.any(axis=1), dtype=bool) if n_out.any()
                else np.ones(n, dtype=bool))
        out = cols[kept].copy()
    else:
        kept = np.ones(n, dtype=bool)
        out = cols  # as_columns' own copy; a flagged sample is filled from kept ones only
        columns = np.flatnonzero(n_out)
        if columns.size:
            axis = np.arange(n, dtype=np.float64) if t is None else t
            for j in columns:
                bad = np.flatnonzero(mask[:, j])
                near = _kept_neighbours(bad, n)
                out[bad, j] = np.interp(axis[bad], axis[near], cols[near, j])
    values = restore_shape(out, one_d)
    mask_out = mask[:, 0].copy() if one_d else mask
    for arr in (values, mask_out, kept, n_out, scale, iters):
        arr.setflags(write=False)
    if not callable(center):
        center.setflags(write=False)
    return OutlierResult(values=values, outlier_mask=mask_out, kept=kept, n_outliers=n_out,
                         center=center, scale=scale, n_iterations=iters, test=test,
                         method=method, threshold=threshold)


def _kept_neighbours(bad: NDArray[np.intp], n: int) -> NDArray[np.intp]:
    """Return the kept rows next to the flagged rows `bad` (sorted) of a column of `n` rows.

    Each run of consecutive flagged rows is bracketed by the kept row just before it and the
    one just after it (where they exist). ``np.interp`` of a flagged row between these rows
    gives what it gives between all kept rows (the same bracketing pair and formula, or the
    first or last kept value beyond them), without copying every kept row of the column.
    """
    starts = np.flatnonzero(np.diff(bad, prepend=-2) != 1)
    ends = np.append(starts[1:], bad.size) - 1
    rows = np.empty(2 * starts.size, dtype=np.intp)
    rows[0::2], rows[1::2] = bad[starts] - 1, bad[ends] + 1  # non-decreasing
    rows = rows[(rows >= 0) & (rows < n)]
    return rows[np.diff(rows, prepend=-1) != 0]  # one kept row between two runs: once


def _check_method(method: str) -> None:
    if method not in ("interpolate", "drop"):
        raise InvalidInputError(f"`method` must be 'interpolate' or 'drop'; got {method!r}")


def _check_count(value: object, name: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise InvalidInputError(f"`{name}` must be an integer ≥ {minimum}; got {value!r}")
    return int(value)
