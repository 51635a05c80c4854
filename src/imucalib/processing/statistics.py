"""Per-step statistics: mean, spread, and a standard error that accounts for correlated noise.

Contents
--------
:class:`WindowStatistics`, :func:`compute_window_statistics`
    Mean, standard deviation, sample count and the standard error of the mean of a window of
    samples, per column, with correlated (flicker, random-walk) noise taken into account.
:class:`RevolutionWindow`, :func:`compute_integer_revolution_window`
    The longest span of a rotating step that covers an integer number of table revolutions, and
    the mean over it (docs/equations.md §5; the rotating steps of an array calibration).

Standard error of a window mean
-------------------------------
For white noise the standard error of the mean of n samples is s/√n. Inertial sensors add
flicker (bias instability) and random-walk noise whose correlation times reach the window length
T = n·Δt, and s/√n then understates the scatter of the mean — on a one-hour gyro bias record of a
consumer MEMS part by a factor of about sixty. We define the standard error as the **Allan
deviation at τ = T** [1]_, [3]_::

    SE² = σ²_A(T) = ½·E[(ȳ₂ − ȳ₁)²]                                                  (1)

the expected scatter between the means of two adjacent windows of the same length: exactly the
variance N²/T of the mean for white noise, K²T/3 for a random walk (the variance of the mean of a
walk started at the window's start), and the flicker floor (2 ln 2/π)·B². This is the uncertainty
that matters when means of successive steps are compared or fitted (the positions of a
multi-position test follow each other in time). Two ways to evaluate it (``se_method``):

``"noise-model"`` (used whenever `noise_model` is given; recommended)
    σ²_A(T) of a :class:`~imucalib.models.noise.NoiseModel` (IEEE 952 terms, from the grade's
    specification or from an Allan characterisation of a long static record), by
    :func:`~imucalib.models.noise.compute_theoretical_adev`. No estimation noise.
``"allan-fit"`` (default without a model)
    σ²_A(T) cannot be measured from one window of length T (it needs 2T), so it is
    extrapolated from the window's own overlapping Allan variance at τ = m·Δt, m = 1, 2, 4, …
    ≤ n/2 (and ≥ `min_cluster_samples`), fitted by weighted non-negative least squares with the
    power laws of IEEE 952 [1]_, [2]_::

        σ²_A(τ) ≈ N²/τ + C_B + K²·τ/3                                               (2)

    with weights edf(τ)/(2·σ̂⁴) (white-noise equivalent degrees of freedom of the overlapping
    estimator, NIST SP 1065 §5.2.4 [3]_), re-weighted once with the fitted model; then
    SE² = max(N̂²/T + Ĉ_B + K̂²·T/3, s²/n). One window holds only a few degrees of freedom at
    its own time scale, so this estimate is *uncertain by about a factor of two* and
    heavy-tailed: on 10–60 s windows its median SE² is 0.8–1.5 times the truth but its mean 2.5–4
    times (spurious random-walk terms extrapolated from the last octaves; measurements in
    ``docs/processing-estimation.md``). It is right on average when the correlated noise
    dominates over several octaves below T (long static records: mean 0.85–1.2 at 10–60 min).
    Windows too short for three cluster sizes fall back to ``"white"``. Before using it on
    low-pass filtered data, raise `min_cluster_samples` above the filter's time constant
    (≈ f_s/f_c samples).
``"white"``
    s/√n, for comparison or for data known to be white.

``n_effective = s²/SE²`` is the equivalent number of independent samples.

Integer revolutions
-------------------
Once-per-revolution terms (horizontal Earth rate, gravity through an axis tilt) average to zero
over whole revolutions. Each sample i represents the angle increment Δθᵢ = θᵢ₊₁ − θᵢ (the last
one extrapolated from its predecessor); the window of samples a … b−1 covers θ_b − θ_a. The
longest window covers n = ⌊|θ_end − θ_start|/2π⌋ revolutions; among the windows of n revolutions
the one whose covered angle is closest to 2πn is chosen (the residual is at most half a sample's
angle, "to within one sample"), ties going to the most central window. The mean weights each
sample by Δθᵢ (``weighting="angle"``, exact cancellation of any function of the table angle even
with rate ripple) or equally (``"time"``); both coincide at constant rate. A sinusoid of
amplitude A leaves at most A·sin(πΔ)/(π(n + Δ)) for a coverage error of Δ revolutions
(docs/equations.md §5, Eq. (5.1)).

References
----------
.. [1] IEEE Std 952-1997 (R2008), Annex C (Allan variance of the noise terms);
   docs/equations.md §8.
.. [2] N. El-Sheimy, H. Hou and X. Niu, "Analysis and modeling of inertial sensors using Allan
   variance", IEEE Trans. Instrum. Meas. 57(1):140–149, 2008.
.. [3] W. J. Riley, *Handbook of Frequency Stability Analysis*, NIST SP 1065, 2008, §5.2.4.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import optimize

from imucalib._checks import as_array, check_positive
from imucalib.analysis._allan_engine import (
    PARALLEL_PHASE_MIN,
    PARALLEL_SUM_MIN,
    integrate_phase,
    n_terms,
    sum_overlapping_rows,
)
from imucalib.analysis._allan_engine import _windows as overlap_windows
from imucalib.analysis._allan_kernels import PHASE_BLOCK, get_kernels
from imucalib.analysis.allan import canonical_mean
from imucalib.errors import InvalidInputError
from imucalib.models.noise import NoiseModel, compute_theoretical_adev
from imucalib.processing._common import as_columns, as_time
from imucalib.processing._select_kernel import median

__all__ = [
    "RevolutionWindow",
    "SeMethod",
    "WindowStatistics",
    "compute_integer_revolution_window",
    "compute_window_statistics",
    "unwrap_angle",
    "window_noise_fit",
]

_MIN_TAU_POINTS = 3
_OCTAVES = 2 ** np.arange(0, 40, dtype=np.int64)  # candidate cluster sizes m of "allan-fit"
SeMethod = Literal["noise-model", "allan-fit", "white"]


@dataclass(frozen=True, eq=False)
class WindowStatistics:
    """Statistics of one window, per column. Arrays have shape (k,) (k = 1 for a 1-D input).

    Attributes
    ----------
    mean : ndarray
        Sample mean. [units of the input]
    std : ndarray
        Sample standard deviation (ddof = 1). [units of the input]
    n_samples : int
        Number of samples n.
    duration_s : float
        T = n / f_s. [s]
    standard_error : ndarray
        SE of the mean, Eq. (1) of :mod:`~imucalib.processing.statistics`, evaluated as
        `se_method` says. [units of the input]
    standard_error_white : ndarray
        std/√n, the white-noise formula, for comparison. [units of the input]
    n_effective : ndarray
        std²/SE², the equivalent number of independent samples.
    white_density : ndarray
        N̂ of the fit (2) [units·√s]; NaN unless ``se_method = "allan-fit"``.
    flicker_variance : ndarray
        Ĉ_B of the fit (2) [units²]; NaN unless ``se_method = "allan-fit"``.
    random_walk : ndarray
        K̂ of the fit (2) [units/√s]; NaN unless ``se_method = "allan-fit"``.
    se_method : str
        ``"noise-model"``, ``"allan-fit"`` or ``"white"`` (also the fallback of a too-short
        ``"allan-fit"``).
    """

    mean: NDArray[np.float64]
    std: NDArray[np.float64]
    n_samples: int
    duration_s: float
    standard_error: NDArray[np.float64]
    standard_error_white: NDArray[np.float64]
    n_effective: NDArray[np.float64]
    white_density: NDArray[np.float64]
    flicker_variance: NDArray[np.float64]
    random_walk: NDArray[np.float64]
    se_method: str


def compute_window_statistics(
    values: ArrayLike,
    sample_rate_hz: float,
    *,
    noise_model: NoiseModel | None = None,
    se_method: SeMethod | None = None,
    min_cluster_samples: int = 1,
) -> WindowStatistics:
    """Compute mean, standard deviation and correlated-noise standard error per column.

    Parameters
    ----------
    values : array_like, shape (n,) or (n, k)
        Uniformly sampled window (a static position, a constant-rate step), n ≥ 2; with a
        `noise_model`, k = 3 (the model's axes). [any unit; the model's for "noise-model"]
    sample_rate_hz : float
        f_s. [Hz]
    noise_model : NoiseModel, optional
        The sensor's noise (two-sided IEEE 952 coefficients) for ``"noise-model"``.
    se_method : {"noise-model", "allan-fit", "white"}, optional
        How the standard error is evaluated (module docstring); default ``"noise-model"`` when
        a model is given, else ``"allan-fit"``.
    min_cluster_samples : int
        Smallest cluster size m of the ``"allan-fit"`` (raise it for filtered data), ≥ 1.

    Returns
    -------
    WindowStatistics
        Per-column statistics.

    Raises
    ------
    InvalidInputError
        If fewer than 2 samples, values not finite, a parameter out of range, ``"noise-model"``
        without a model, or a model with k ≠ 3 columns.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.random.default_rng(0).normal(0.0, 1.0, (10_000, 3))
    >>> st = compute_window_statistics(x, 100.0, noise_model=NoiseModel(white_density=0.1))
    >>> np.round(st.standard_error, 6).tolist()            # N/√T = 0.1/√100
    [0.01, 0.01, 0.01]
    """
    cols, _ = as_columns(values, "values", min_samples=2, copy=False)  # only read
    fs = check_positive(sample_rate_hz, "sample_rate_hz")
    ms = _cluster_sizes(cols.shape[0], min_cluster_samples)
    method = se_method or ("noise-model" if noise_model is not None else "allan-fit")
    if method not in ("noise-model", "allan-fit", "white"):
        raise InvalidInputError(f"`se_method` must be 'noise-model', 'allan-fit' or 'white'; got "
                                f"{se_method!r}")
    n, k = cols.shape
    duration = n / fs
    mean = cols.mean(axis=0)
    dev = cols - mean  # also the centred input of the Allan fit
    # ndarray.std(ddof=1)'s own operations on the deviations it would form again
    std = np.sqrt(np.sum(np.multiply(dev, dev), axis=0) / (n - 1))
    se_white = std / np.sqrt(n)
    nan = np.full(k, np.nan)
    wd, fl, rw = nan, nan.copy(), nan.copy()
    if method == "noise-model":
        if noise_model is None:
            raise InvalidInputError("`se_method` 'noise-model' needs a `noise_model`; got None")
        if k != 3:
            raise InvalidInputError(f"`values` must have 3 columns (the axes of `noise_model`); "
                                    f"got {k}")
        se = compute_theoretical_adev(noise_model, [duration])[0]  # Eq. (1)
    elif method == "allan-fit":
        if ms.size < _MIN_TAU_POINTS:
            method, se = "white", se_white.copy()
        else:
            coefs = _fit_allan(dev, 1.0 / fs, ms)
            wd, fl, rw = np.sqrt(coefs[:, 0]), coefs[:, 1], np.sqrt(3.0 * coefs[:, 2])
            se2 = coefs[:, 0] / duration + coefs[:, 1] + coefs[:, 2] * duration  # Eqs. (1)-(2)
            se = np.sqrt(np.maximum(se2, se_white**2))
    else:
        se = se_white.copy()
    with np.errstate(divide="ignore", invalid="ignore"):
        n_eff = np.where(se > 0, std**2 / np.where(se > 0, se, 1.0) ** 2, float(n))
    se = np.asarray(se, dtype=np.float64)
    for arr in (mean, std, se, se_white, n_eff, wd, fl, rw):
        arr.setflags(write=False)
    return WindowStatistics(mean=mean, std=std, n_samples=n, duration_s=duration,
                            standard_error=se, standard_error_white=se_white, n_effective=n_eff,
                            white_density=wd, flicker_variance=fl, random_walk=rw,
                            se_method=method)


def window_noise_fit(values: ArrayLike, sample_rate_hz: float, *,
                     min_cluster_samples: int = 1
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return a window's column means and the noise terms of its Allan fit, Eq. (2).

    What :func:`compute_window_statistics` (``se_method="allan-fit"``) gives as ``mean`` and
    as ``white_density``, ``flicker_variance``, ``random_walk``, bit for bit, without the
    window's other statistics (its spread and standard error), for a caller that pools the
    noise terms of many windows into one model (P2, docs/p2.md).

    Parameters
    ----------
    values : array_like, shape (n,) or (n, k)
        Uniformly sampled window, n ≥ 2. [any unit]
    sample_rate_hz : float
        f_s. [Hz]
    min_cluster_samples : int
        Smallest cluster size m of the fit, ≥ 1.

    Returns
    -------
    mean : ndarray, shape (k,)
        The column means. [units of `values`]
    fit : ndarray, shape (3, k)
        Rows N̂ [units·√s], Ĉ_B [units²] and K̂ [units/√s] of Eq. (2); NaN for a window too
        short for three cluster sizes.

    Raises
    ------
    InvalidInputError
        Fewer than 2 samples, values not finite, or a parameter out of range.
    """
    cols, _ = as_columns(values, "values", min_samples=2, copy=False)  # only read
    fs = check_positive(sample_rate_hz, "sample_rate_hz")
    ms = _cluster_sizes(cols.shape[0], min_cluster_samples)
    mean = cols.mean(axis=0)
    if ms.size < _MIN_TAU_POINTS:
        return mean, np.full((3, cols.shape[1]), np.nan)
    coefs = _fit_allan(cols - mean, 1.0 / fs, ms)
    return mean, np.vstack([np.sqrt(coefs[:, 0]), coefs[:, 1], np.sqrt(3.0 * coefs[:, 2])])


def _cluster_sizes(n: int, min_cluster_samples: int) -> NDArray[np.int64]:
    """Return the cluster sizes m = 1, 2, 4, … of the fit (2): ≥ `min_cluster_samples`, ≤ n/2."""
    if isinstance(min_cluster_samples, bool) or not isinstance(min_cluster_samples,
                                                               int | np.integer) \
            or min_cluster_samples < 1:
        raise InvalidInputError(f"`min_cluster_samples` must be an integer ≥ 1; got "
                                f"{min_cluster_samples!r}")
    return _OCTAVES[(_OCTAVES >= min_cluster_samples) & (_OCTAVES <= n // 2)]


@dataclass(frozen=True, eq=False)
class _AllanPlan:
    """Everything of the window fit (2) but the data, for n samples of k columns (private).

    Cached per (n, k, cluster sizes, Δt) by :func:`_allan_plan`: a station's windows come in a
    few lengths, and forming these arrays again cost more than the window's sums themselves.
    The arrays are read-only.

    Attributes
    ----------
    tau : ndarray, shape (M,)
        τ = m·Δt of each cluster size. [s]
    count : ndarray of int64, shape (M,)
        Terms of the overlapping sum at each τ, n + 1 − 2m.
    scale : ndarray, shape (M,)
        2·count·τ², the divisor of the sums in NIST SP 1065 Eq. (8). [s²]
    basis : ndarray, shape (M, 3)
        The power laws of Eq. (2) at each τ: 1/τ, 1, τ.
    rel_sd : ndarray, shape (M,)
        σ(σ̂²)/σ² = √(2/edf) of each τ (NIST SP 1065 §5.2.4).
    starts, wins, counts : ndarray of int64 or None
        The one kernel call of :func:`~imucalib.analysis._allan_engine.sum_overlapping_rows`
        for k rows of n + 1 phase points (its windows and term counts); None when its terms
        reach the engine's threaded path, which then runs itself.
    """

    tau: NDArray[np.float64]
    count: NDArray[np.int64]
    scale: NDArray[np.float64]
    basis: NDArray[np.float64]
    rel_sd: NDArray[np.float64]
    starts: NDArray[np.int64] | None
    wins: NDArray[np.int64] | None
    counts: NDArray[np.int64] | None


@functools.lru_cache(maxsize=64)
def _allan_plan(n: int, k: int, ms_key: tuple[int, ...], dt: float) -> _AllanPlan:
    """Return the :class:`_AllanPlan` of n samples in k columns at cluster sizes `ms_key`."""
    ms = np.array(ms_key, dtype=np.int64)
    count = n_terms("oadev", ms, n + 1)
    tau = np.asarray(ms * dt, dtype=np.float64)
    starts = wins = counts = None
    if int(count.sum()) * k < PARALLEL_SUM_MIN:
        # sum_overlapping_rows' layout: row j's windows moved on by j·(n + 1); its job groups
        # are one group below PARALLEL_SUM_MIN terms, the one kernel call made here
        offsets, win = overlap_windows(ms, 2)
        rows = np.arange(k, dtype=np.int64)
        starts = (offsets[None, :] + (n + 1) * rows[:, None]).reshape(-1)
        wins = np.ascontiguousarray(
            (win[None, :, :] + offsets.size * rows[:, None, None]).reshape(-1, win.shape[1]))
        counts = np.tile(count.astype(np.int64), k)
    plan = _AllanPlan(tau=tau, count=count, scale=2.0 * count * tau**2,
                      basis=np.column_stack([1.0 / tau, np.ones_like(tau), tau]),
                      rel_sd=np.sqrt(2.0 / _edf_white(n, ms)), starts=starts, wins=wins,
                      counts=counts)
    for arr in (plan.tau, plan.count, plan.scale, plan.basis, plan.rel_sd, starts, wins, counts):
        if arr is not None:
            arr.setflags(write=False)
    return plan


def _overlapping_avar(x: NDArray[np.float64], dt: float, ms: NDArray[np.int64]
                      ) -> NDArray[np.float64]:
    """Overlapping Allan variance of rate samples (n, k) at τ = m·dt; shape (len(ms), k).

    The one Allan path of the project: the phase sum and the blocked sums of squared second
    differences of :mod:`imucalib.analysis` (``compute_oadev``'s kernels, NIST SP 1065 Eq. (8)),
    without its noise identification and confidence intervals, which this fit does not use::

        σ²_A(m·dt) = Σ_{i<n+1−2m} (x_{i+2m} − 2x_{i+m} + xᵢ)² / (2·(n + 1 − 2m)·(m·dt)²)

    The k phase series are integrated into the rows of one array and their sums taken in one
    kernel pass (:func:`~imucalib.analysis._allan_engine.sum_overlapping_rows`), the same
    operations as column by column. A window of one phase block (n ≤ ``PHASE_BLOCK``, every
    window statistic of a calibration) has its phase formed for all columns at once: the
    canonical phase of one block is ``(0 + Σ_{i≤j}(yᵢ − ȳ))·τ0``, a sequential sum, which
    ``np.cumsum`` along each row forms by the same operations (``_allan_kernels``' numpy
    twin does just that), and ȳ the row's ``np.sum`` over n (the canonical mean of fewer than
    2^20 samples).
    """
    n, k = x.shape
    plan = _allan_plan(n, k, tuple(ms.tolist()), dt)
    tau0 = 1.0 / (1.0 / dt)  # phase_from_rate(·, 1/dt)'s step
    phase = np.empty((k, n + 1))
    phase[:, 0] = 0.0
    if n <= PHASE_BLOCK:
        rows = np.ascontiguousarray(x.T)
        mean = (0.0 + np.sum(rows, axis=1)) / n  # canonical_mean of each row
        np.multiply(0.0 + np.cumsum(rows - mean[:, None], axis=1), tau0, out=phase[:, 1:])
    else:
        # below PARALLEL_PHASE_MIN integrate_phase runs this one kernel: call it without its
        # dispatch
        phase_kernel = get_kernels()["phase"] if n < PARALLEL_PHASE_MIN else None
        for j in range(k):
            col = np.ascontiguousarray(x[:, j])
            if phase_kernel is None:
                integrate_phase(col, canonical_mean(col), tau0, phase[j, 1:])
            else:
                phase_kernel(col, canonical_mean(col), tau0, phase[j, 1:], 0.0)
    if plan.counts is None:
        sums = sum_overlapping_rows(phase, ms, plan.count, 2)
    else:
        assert plan.starts is not None and plan.wins is not None
        totals = np.zeros(plan.counts.size)
        get_kernels()["sumsq_overlap"](phase.reshape(-1), plan.starts, plan.wins, plan.counts,
                                       2, totals)
        sums = totals.reshape(k, ms.size)
    out: NDArray[np.float64] = (sums / plan.scale).T
    return out


def _edf_white(n: int, m: NDArray[np.int64]) -> NDArray[np.float64]:
    """Equivalent degrees of freedom of the overlapping ADEV, white FM (NIST SP 1065 §5.2.4)."""
    npts = n + 1  # phase points
    mf = m.astype(np.float64)
    edf = (3.0 * (npts - 1) / (2.0 * mf) - 2.0 * (npts - 2) / npts) * 4.0 * mf**2 / (
        4.0 * mf**2 + 5.0)
    return np.asarray(np.maximum(edf, 1.0), dtype=np.float64)


def _nnls_core() -> Callable[..., tuple[NDArray[np.float64], float, int]] | None:
    """Return scipy's compiled NNLS when :func:`scipy.optimize.nnls` calls exactly it, else None.

    ``nnls(A, b)`` checks its arguments (finite, shapes) and then returns this core's answer
    for ``maxiter = 3·n``; the fit below calls the core on arrays it has checked itself (one
    check for every column), which is most of the cost of a 9 × 3 problem.
    """
    try:
        from scipy.optimize import _nnls as wrapper
        from scipy.optimize._slsqplib import nnls as core
    except ImportError:  # pragma: no cover - another scipy
        return None
    found = getattr(wrapper, "_nnls", None)
    return core if found is core else None


_NNLS = _nnls_core()


def _nnls(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``scipy.optimize.nnls(a, b)[0]`` for finite, C-ordered float64 `a` (m, n) and `b` (m,)."""
    if _NNLS is None:  # pragma: no cover - another scipy
        return np.asarray(optimize.nnls(a, b)[0], dtype=np.float64)
    coef, _, info = _NNLS(a, b, 3 * a.shape[1])
    if info == 3:  # pragma: no cover - nnls' own refusal
        raise RuntimeError("Maximum number of iterations reached.")
    return np.asarray(coef, dtype=np.float64)


def _fit_allan(x: NDArray[np.float64], dt: float, ms: NDArray[np.int64]) -> NDArray[np.float64]:
    """Non-negative weighted fit of Eq. (2) per column; returns (k, 3): N², C_B, K²/3.

    Each column with some positive variance is fitted twice, the weights first from its
    variances, then from the fitted model (where positive); the weighted designs of every
    column are formed at once (the same element-wise operations as one column at a time).
    """
    avar = _overlapping_avar(x, dt, ms)
    k = x.shape[1]
    plan = _allan_plan(x.shape[0], k, tuple(ms.tolist()), dt)
    out = np.zeros((k, 3))
    rows = np.ascontiguousarray(avar.T)  # (k, M): each column's variances
    live = np.flatnonzero(np.any(rows > 0, axis=1)).tolist()
    if not live:
        return out
    model = np.maximum(rows, 1e-300)
    for _ in range(2):  # weights from the data, then from the fitted model
        sd = model * plan.rel_sd
        design = plan.basis[None, :, :] / sd[:, :, None]
        rhs = rows / sd
        checked = bool(np.isfinite(design).all() and np.isfinite(rhs).all())
        for j in live:
            coef = _nnls(design[j], rhs[j]) if checked else optimize.nnls(design[j], rhs[j])[0]
            fitted = plan.basis @ coef
            np.copyto(model[j], fitted, where=fitted > 0)  # the fitted model where positive
            out[j] = coef
    return out


@dataclass(frozen=True, eq=False)
class RevolutionWindow:
    """Result of :func:`compute_integer_revolution_window`.

    Attributes
    ----------
    start_index, stop_index : int
        The window is samples ``start_index … stop_index − 1``.
    n_revolutions : int
        Whole revolutions covered, ≥ 1.
    covered_angle_rad : float
        |θ_stop − θ_start| covered by the window. [rad]
    angle_error_rad : float
        covered − 2π·n (at most half a sample's angle increment in magnitude). [rad]
    start_time_s, end_time_s : float
        Times of the first sample and of the boundary after the last one. [s]
    mean : ndarray, shape (k,) or scalar-shaped (1,)
        Revolution mean of each column of `values`. [units of `values`]
    weighting : str
        ``"angle"`` or ``"time"``.
    """

    start_index: int
    stop_index: int
    n_revolutions: int
    covered_angle_rad: float
    angle_error_rad: float
    start_time_s: float
    end_time_s: float
    mean: NDArray[np.float64]
    weighting: str

    @property
    def n_samples(self) -> int:
        """Samples in the window."""
        return self.stop_index - self.start_index


def compute_integer_revolution_window(
    time_s: ArrayLike,
    values: ArrayLike,
    *,
    angle_rad: ArrayLike | None = None,
    rate_rps: ArrayLike | None = None,
    weighting: Literal["angle", "time"] = "angle",
) -> RevolutionWindow:
    """Select the longest integer-revolution span of a rotating step and its mean.

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Strictly increasing sample times. [s]
    values : array_like, shape (n,) or (n, k)
        Samples to average (IMU outputs). [any unit]
    angle_rad : array_like, shape (n,), optional
        Table angle at each sample (wrapped or not; it is unwrapped). [rad]
    rate_rps : array_like, shape (n,), optional
        Table rate, integrated (trapezoid) when no angle is given. [rad/s]
    weighting : {"angle", "time"}
        Weights of the mean (module docstring).

    Returns
    -------
    RevolutionWindow
        The window and the revolution mean.

    Raises
    ------
    InvalidInputError
        If neither or both of `angle_rad` / `rate_rps` are given, shapes disagree, the angle is
        not strictly monotonic (the table must turn one way), or it covers less than one
        revolution.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(0.0, 10.0, 0.01)                # 10 s at 100 Hz, 100 °/s: 2.78 rev
    >>> theta = np.deg2rad(100.0) * t
    >>> y = 1.0 + np.cos(theta)                       # once-per-revolution term
    >>> w = compute_integer_revolution_window(t, y, angle_rad=theta)
    >>> w.n_revolutions, round(float(w.mean[0]), 9)
    (2, 1.0)
    """
    t = as_time(time_s, "time_s")
    cols, _ = as_columns(values, "values", min_samples=2, copy=False)  # only read
    if cols.shape[0] != t.size:
        raise InvalidInputError(f"`values` must have {t.size} rows (one per time); got "
                                f"{cols.shape[0]}")
    if (angle_rad is None) == (rate_rps is None):
        raise InvalidInputError("give exactly one of `angle_rad` and `rate_rps`; got "
                                f"{'both' if angle_rad is not None else 'neither'}")
    if weighting not in ("angle", "time"):
        raise InvalidInputError(f"`weighting` must be 'angle' or 'time'; got {weighting!r}")
    if angle_rad is not None:
        theta = unwrap_angle(_as_vector(angle_rad, "angle_rad", t.size))
    elif rate_rps is not None:
        w = _as_vector(rate_rps, "rate_rps", t.size)
        theta = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
    step = np.diff(theta)
    sign = 1.0 if step.sum() >= 0 else -1.0
    forward = sign * step
    if np.any(forward <= 0):
        raise InvalidInputError(
            "the table angle must change monotonically through the step (one direction of "
            f"rotation); got {int(np.sum(forward <= 0))} sample step(s) against it"
        )
    th = sign * theta
    n = t.size
    # boundary angle after each sample: θ_{i+1}, the last one extrapolated
    bound = np.empty(n + 1)
    bound[:n] = th
    bound[n] = th[-1] + (th[-1] - th[-2])
    # a span short of N revolutions by less than half a sample step counts as N (the servo's
    # rate noise moves the last boundary by a fraction of a step); the window's angle_error_rad
    # says by how much
    median_step = median(forward)
    half_step = 0.5 * median_step
    n_rev = int(np.floor((bound[-1] - bound[0] + half_step) / (2.0 * np.pi) + 1e-12))
    if n_rev < 1:
        raise InvalidInputError(
            "the step must cover at least one revolution; got "
            f"{np.degrees(bound[-1] - bound[0]):.6g}°"
        )
    a, b = _closest_span(bound, bound[:-1] + 2.0 * np.pi * n_rev, max(median_step, 1e-300))
    dtheta = np.diff(bound[a: b + 1])
    weights = dtheta if weighting == "angle" else np.ones(b - a)
    mean = (weights @ cols[a:b]) / weights.sum()
    covered = float(bound[b] - bound[a])
    end_time = float(t[b]) if b < n else float(t[-1] + (t[-1] - t[-2]))
    mean.setflags(write=False)
    return RevolutionWindow(start_index=a, stop_index=b, n_revolutions=n_rev,
                            covered_angle_rad=covered,
                            angle_error_rad=covered - 2.0 * np.pi * n_rev,
                            start_time_s=float(t[a]), end_time_s=end_time,
                            mean=mean,
                            weighting=weighting)


def _closest_span(bound: NDArray[np.float64], target: NDArray[np.float64], scale: float
                  ) -> tuple[int, int]:
    """Return the window (a, b), samples a … b − 1, whose covered angle is closest to 2π·n.

    `bound` (n + 1,) holds the increasing boundary angles, ``target[a] = bound[a] + 2π·n`` (n
    whole revolutions) and `scale` the median step. For each start a the stop b is the
    boundary next below or above the target (below when the two are equally close), b > a;
    among the starts, the smallest error in units of `scale` rounded to 1e-9 wins, then the
    most central window, then the earliest: a lexicographic sort's first entry (module
    docstring, "Integer revolutions"), found by two minima.
    """
    n = target.size
    starts = np.arange(n)
    above = np.searchsorted(bound, target)     # first boundary ≥ the target
    below = above - 1                          # the last below it
    inf = np.inf
    err_below = np.where(below > starts, np.abs(bound[below] - target), inf)
    inside = (above > starts) & (above < bound.size)
    err_above = np.where(inside, np.abs(bound[np.minimum(above, n)] - target), inf)
    take_above = err_above < err_below
    best_err = np.where(take_above, err_above, err_below)
    best_stop = np.where(take_above, above, below)
    live = np.flatnonzero(np.isfinite(best_err))
    if not live.size:  # pragma: no cover - the first start always has a stop
        raise InvalidInputError("no window of whole revolutions in the step")
    score = np.round(best_err[live] / scale, 9)
    live = live[score == score.min()]
    center_off = np.abs((live + best_stop[live]) / 2.0 - n / 2.0)
    a = int(live[np.argmin(center_off)])
    return a, int(best_stop[a])


def unwrap_angle(angle_rad: NDArray[np.float64]) -> NDArray[np.float64]:
    """``np.unwrap(angle_rad)`` (period 2π), bit for bit, without its work on a continuous angle.

    np.unwrap adds to sample i the running sum of the corrections of the steps before it,
    each zero where |Δθ| < π: on an angle with no such jump (a table's feedback unwrapped
    already, 100 Hz samples of a turn) the sum is 0 and the result ``θ[0], θ[1:] + 0.0``,
    formed here from one test of the steps. Anything else is np.unwrap's. [rad]
    """
    p = np.asarray(angle_rad)
    if p.ndim != 1 or p.dtype != np.float64 or p.size < 2 \
            or not bool(np.all(np.abs(np.diff(p)) < np.pi)):
        unwrapped: NDArray[np.float64] = np.unwrap(p)
        return unwrapped
    out = p + 0.0
    out[0] = p[0]
    return out


def _as_vector(value: ArrayLike, name: str, n: int) -> NDArray[np.float64]:
    out = as_array(value, name)
    if out.shape != (n,):
        raise InvalidInputError(f"`{name}` must have shape ({n},) (one per time); got {out.shape}")
    return out
