"""Time synchronisation: interpolation onto a target time base, and device-clock reconstruction.

Contents
--------
:class:`SyncResult`, :func:`synchronize`
    Linear interpolation of one stream (the IMU) onto the time stamps of another (the table
    feedback), with the achieved alignment error and the ≤ 1 ms check of procedure P1
    (docs/p1.md, rule 3).
:class:`TimeBase`, :func:`reconstruct_time_base`
    Device time on the host clock by linear regression of host receive time on the sample
    counter (docs/drivers.md, "Time synchronisation practice"), with clock-rate error, jitter
    and gaps.

Alignment error
---------------
Interpolated values are attributed to the target times; the *alignment error* is a bound on the
time error of that attribution, as the sum of three parts (all in seconds)::

    e_align = u_offset + e_interp + 3·σ_jitter                                        (1)
    e_interp = π·f_max·h_max²/4                                                       (2)

- u_offset: the uncertainty of the offset between the two clocks after `source_offset_s`
  (latency) has been applied — zero when both streams are stamped by one clock (the Recording
  contract), otherwise from the synchronisation method (hardware pulse, PPS/PTP, or the
  regression of :func:`reconstruct_time_base`). It is supplied by the caller.
- e_interp: linear interpolation over a source interval h has a value error at most
  h²/8·max|x''| [1]_; for a signal band-limited to f_max, Bernstein's inequality
  max|x''| ≤ 2πf_max·max|x'| [2]_ turns it into an equivalent *time* error of at most
  π·f_max·h²/4 (error / largest slope), Eq. (2), with h_max the longest source interval that
  brackets a target. f_max is the bandwidth of the interpolated signal (the cut-off of the
  :func:`~imucalib.processing.filtering.lowpass_zero_phase` filter applied before, or the IMU's
  bandwidth); by default the source Nyquist frequency, which gives the conservative
  e_interp = π·h/8. For 1 kHz IMU data e_interp ≤ 0.39 ms; for 100 Hz data filtered at 10 Hz,
  0.79 ms.
- σ_jitter: the RMS deviation of the source time stamps from a uniform grid (a straight line
  through them against their integer sample index, gaps counted), i.e. the random error of each
  stamp; 3σ covers 99.7 % of samples. Reconstructed device time (:func:`reconstruct_time_base`)
  has σ_jitter ≈ 0; raw host receive stamps carry their transport jitter.

The bound is compared with `max_alignment_error_s` (1 ms, procedure P1's software requirement
and processing rule 3, docs/p1.md) and :class:`~imucalib.errors.LimitExceededError` is raised
when it is exceeded.

Clock reconstruction
--------------------
Host receive times are t_host,i = a + T·c_i + ℓ + εᵢ, with c_i the unwrapped counter, T the true
sample period on the host clock, ℓ ≥ 0 the mean latency and εᵢ the jitter. Least squares on
(c_i, t_host,i), iterated twice with samples beyond 5 robust standard deviations removed (OS
scheduling hiccups), gives T̂ and t̂ᵢ = â + T̂·cᵢ: the latency jitter is removed and the clock-rate
error (1/T̂)/f_nominal − 1 revealed [3]_. The mean latency ℓ stays in â: it cannot be separated
from the offset without an external reference and belongs to u_offset above. Counter gaps (lost
samples) are reported; a counter of b bits wraps at 2^b and is unwrapped when `counter_modulus`
is given.

References
----------
.. [1] G. Dahlquist and Å. Björck, *Numerical Methods in Scientific Computing* I, SIAM, 2008,
   §4.2.2 (error of linear interpolation).
.. [2] S. N. Bernstein, 1912; see A. F. Timan, *Theory of Approximation of Functions of a Real
   Variable*, 1963, §4.8 (Bernstein's inequality for entire functions of exponential type).
.. [3] docs/drivers.md, "Time synchronisation practice" (regression of host time on the sample
   counter); IEEE Std 1554-2005 (inertial sensor test data acquisition).
.. [4] N. R. Draper and H. Smith, *Applied Regression Analysis*, 3rd ed., Wiley, 1998, §1.2
   (the straight line by least squares, in centred form).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array, check_nonnegative, check_positive
from imucalib.errors import InvalidInputError, LimitExceededError
from imucalib.processing._common import as_columns, as_time, restore_shape
from imucalib.processing._select_kernel import median

__all__ = [
    "DEFAULT_MAX_ALIGNMENT_ERROR_S",
    "SyncResult",
    "TimeBase",
    "estimate_timestamp_jitter_s",
    "reconstruct_time_base",
    "synchronize",
]

#: Procedure P1 (docs/p1.md, rule 3): IMU samples and table feedback share a time base with
#: ≤ 1 ms error.
DEFAULT_MAX_ALIGNMENT_ERROR_S = 1e-3
_GAP_FACTOR = 1.5  # an interval longer than 1.5 × the median spacing is a gap
_ROBUST_K = 5.0


@dataclass(frozen=True, eq=False)
class SyncResult:
    """Result of :func:`synchronize`. Arrays are read-only.

    Attributes
    ----------
    time_s : ndarray, shape (m,)
        Target times. [s]
    values : ndarray, shape (m,) or (m, k)
        Source values interpolated at the target times. [units of the source]
    alignment_error_s : float
        Bound (1) of :mod:`~imucalib.processing.sync`. [s]
    interpolation_error_s : float
        e_interp, Eq. (2). [s]
    timestamp_jitter_s : float
        σ_jitter of the source stamps (0 when not estimated). [s]
    offset_uncertainty_s : float
        u_offset as given. [s]
    signal_bandwidth_hz : float
        f_max used in Eq. (2). [Hz]
    max_source_interval_s : float
        h_max, the longest source interval bracketing a target. [s]
    nearest_sample_distance_s : ndarray, shape (m,)
        Distance from each target to its nearest source sample. [s]
    n_targets_in_gaps : int
        Targets inside a source interval longer than 1.5 × the median spacing (lost samples).
    """

    time_s: NDArray[np.float64]
    values: NDArray[np.float64]
    alignment_error_s: float
    interpolation_error_s: float
    timestamp_jitter_s: float
    offset_uncertainty_s: float
    signal_bandwidth_hz: float
    max_source_interval_s: float
    nearest_sample_distance_s: NDArray[np.float64]
    n_targets_in_gaps: int


def estimate_timestamp_jitter_s(time_s: ArrayLike) -> float:
    """Return the RMS deviation of time stamps from a uniform grid (module docstring). [s]

    The stamps are regressed on their integer sample index k, accumulated from the rounded
    number of median intervals in each step, so lost samples do not count as jitter (valid while
    the jitter is well below Δ/2).

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Strictly increasing stamps, n ≥ 3. [s]

    Returns
    -------
    float
        σ_jitter. [s]

    Raises
    ------
    InvalidInputError
        If fewer than 3 stamps, or not strictly increasing.
    """
    t = as_time(time_s, "time_s")
    if t.size < 3:
        raise InvalidInputError(f"`time_s` must have at least 3 stamps; got {t.size}")
    d = np.diff(t)
    return _jitter_of_steps(t, d, median(d))


def _fit_line(x: NDArray[np.float64], y: NDArray[np.float64]) -> tuple[float, float]:
    """Return the least-squares line (slope b̂, intercept â) of y ≈ â + b̂·x in closed form.

    With the means x̄, ȳ (pairwise sums) [4]_::

        b̂ = Σ(xᵢ − x̄)(yᵢ − ȳ) / Σ(xᵢ − x̄)²,    â = ȳ − b̂·x̄                          (3)

    the normal equations of the straight line solved on centred data, which keeps them
    well-conditioned; it equals ``np.polyfit(x, y, 1)`` to rounding without its Vandermonde
    matrix and SVD. `x` must hold at least two distinct values.
    """
    x_bar = float(x.mean())
    y_bar = float(y.mean())
    dx = x - x_bar
    slope = float(dx @ (y - y_bar)) / float(dx @ dx)  # Eq. (3)
    return slope, y_bar - slope * x_bar


def _jitter_of_steps(t: NDArray[np.float64], d: NDArray[np.float64], dt: float) -> float:
    """σ_jitter of validated stamps `t` with steps ``d = diff(t)`` and median step `dt` [s].

    The line of the stamps on their local counts is Eq. (3); the residuals are taken about it
    as ``np.polyval`` forms them, (t − t₀) − (b̂·k + â).
    """
    k = np.empty(t.size)
    k[0] = 0.0
    np.cumsum(np.maximum(np.round(d / dt), 1.0), out=k[1:])  # local counts
    # integer counts stay distinct below 2^53; beyond, repeated values may make the line
    # undefined (np.unique would be a sort of the whole record)
    if k[-1] >= 2.0**53 and 1 + np.count_nonzero(np.diff(k)) < 3:
        return 0.0
    y = t - t[0]
    slope, intercept = _fit_line(k, y)
    resid = y - (slope * k + intercept)
    return float(np.sqrt(np.sum(resid**2) / (t.size - 2)))


def synchronize(
    source_time_s: ArrayLike,
    source_values: ArrayLike,
    target_time_s: ArrayLike,
    *,
    source_offset_s: float = 0.0,
    offset_uncertainty_s: float = 0.0,
    signal_bandwidth_hz: float | None = None,
    max_alignment_error_s: float | None = DEFAULT_MAX_ALIGNMENT_ERROR_S,
    estimate_jitter: bool = True,
) -> SyncResult:
    """Interpolate a source stream linearly onto target times and bound the alignment error.

    Parameters
    ----------
    source_time_s : array_like, shape (n,)
        Strictly increasing stamps of the source (IMU) samples, n ≥ 2. [s]
    source_values : array_like, shape (n,) or (n, k)
        Source samples. [any unit]
    target_time_s : array_like, shape (m,)
        Non-decreasing target (table feedback) times, inside the corrected source span. [s]
    source_offset_s : float
        Added to `source_time_s` to express it on the target clock (e.g. minus a known latency).
        [s]
    offset_uncertainty_s : float
        u_offset, the uncertainty of that offset, ≥ 0. [s]
    signal_bandwidth_hz : float, optional
        f_max of Eq. (2); the source Nyquist frequency 1/(2·median spacing) when omitted. [Hz]
    max_alignment_error_s : float or None
        Limit on the bound (1) (docs/p1.md, rule 3: 1 ms); None disables the check. [s]
    estimate_jitter : bool
        Estimate σ_jitter from the source stamps (:func:`estimate_timestamp_jitter_s`); set False
        for sources sampled non-uniformly on purpose.

    Returns
    -------
    SyncResult
        Interpolated values and the error budget.

    Raises
    ------
    InvalidInputError
        If shapes disagree, values are not finite, `source_time_s` is not strictly increasing,
        `target_time_s` decreases, or a target lies outside the source span (no extrapolation).
    LimitExceededError
        If the alignment error bound exceeds `max_alignment_error_s`.

    Examples
    --------
    >>> import numpy as np
    >>> t_imu = np.arange(0.0, 2.0, 1e-3)
    >>> t_table = np.arange(0.1, 1.9, 0.01)
    >>> res = synchronize(t_imu, np.sin(t_imu), t_table, signal_bandwidth_hz=50.0)
    >>> bool(np.allclose(res.values, np.sin(t_table), atol=1e-6)), res.alignment_error_s < 1e-3
    (True, True)
    """
    t_src = as_time(source_time_s, "source_time_s")
    if t_src.size < 2:
        raise InvalidInputError(f"`source_time_s` must have at least 2 samples; got {t_src.size}")
    cols, one_d = as_columns(source_values, "source_values", copy=False)  # only read
    if cols.shape[0] != t_src.size:
        raise InvalidInputError(
            f"`source_values` must have {t_src.size} rows (one per source time); got "
            f"{cols.shape[0]}"
        )
    t_tgt = as_time(target_time_s, "target_time_s", strict=False)
    if t_tgt.size < 1:
        raise InvalidInputError("`target_time_s` must hold at least one time; got none")
    offset = float(as_array(source_offset_s, "source_offset_s", shape=()))
    u_off = check_nonnegative(offset_uncertainty_s, "offset_uncertainty_s")
    t_src = t_src + offset
    outside = (t_tgt < t_src[0]) | (t_tgt > t_src[-1])
    if outside.any():
        raise InvalidInputError(
            f"`target_time_s` must lie within the source span [{t_src[0]:.9g}, {t_src[-1]:.9g}] s "
            f"(after `source_offset_s`); got {int(outside.sum())} time(s) outside, from "
            f"{t_tgt[0]:.9g} to {t_tgt[-1]:.9g} s"
        )
    spacing = np.diff(t_src)
    dt_med = median(spacing)
    f_max = (0.5 / dt_med if signal_bandwidth_hz is None
             else check_positive(signal_bandwidth_hz, "signal_bandwidth_hz"))

    # bracketing interval j: t_src[j] ≤ t < t_src[j + 1]; a target on a sample has h = 0
    j = np.clip(np.searchsorted(t_src, t_tgt, side="right") - 1, 0, t_src.size - 2)
    on_sample = (t_tgt == t_src[j]) | (t_tgt == t_src[j + 1])
    h = np.where(on_sample, 0.0, spacing[j])
    h_max = float(h.max())
    nearest = np.minimum(np.abs(t_tgt - t_src[j]), np.abs(t_src[j + 1] - t_tgt))
    n_gaps = int(np.count_nonzero(h > _GAP_FACTOR * dt_med))

    lam = (t_tgt - t_src[j]) / spacing[j]
    out = cols[j] * (1.0 - lam)[:, None] + cols[j + 1] * lam[:, None]
    e_interp = math.pi * f_max * h_max**2 / 4.0  # Eq. (2)
    # σ_jitter from the validated stamps, their steps and median step (computed above)
    jitter = (_jitter_of_steps(t_src, spacing, dt_med) if (estimate_jitter and t_src.size >= 3)
              else 0.0)
    e_align = u_off + e_interp + 3.0 * jitter  # Eq. (1)
    if max_alignment_error_s is not None:
        limit = check_positive(max_alignment_error_s, "max_alignment_error_s")
        if e_align > limit:
            raise LimitExceededError(
                f"the alignment error must be ≤ `max_alignment_error_s` = {limit * 1e3:.4g} ms; "
                f"got {e_align * 1e3:.4g} ms = offset uncertainty {u_off * 1e3:.4g} ms + "
                f"interpolation bound {e_interp * 1e3:.4g} ms (f_max {f_max:.4g} Hz, longest "
                f"source interval {h_max * 1e3:.4g} ms) + 3 × jitter {jitter * 1e3:.4g} ms"
            )
    values = restore_shape(out, one_d)
    for arr in (t_tgt, values, nearest):
        arr.setflags(write=False)
    return SyncResult(
        time_s=t_tgt, values=values, alignment_error_s=e_align, interpolation_error_s=e_interp,
        timestamp_jitter_s=jitter, offset_uncertainty_s=u_off, signal_bandwidth_hz=f_max,
        max_source_interval_s=h_max, nearest_sample_distance_s=nearest, n_targets_in_gaps=n_gaps,
    )


@dataclass(frozen=True, eq=False)
class TimeBase:
    """Result of :func:`reconstruct_time_base`. Arrays are read-only.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Reconstructed sample times on the host clock, â + T̂·c. [s]
    counter : ndarray of int64, shape (n,)
        The unwrapped sample counter c.
    sample_period_s : float
        T̂, the device's sample period measured on the host clock. [s]
    sample_rate_hz : float
        1/T̂. [Hz]
    clock_rate_error : float
        (1/T̂)/f_nominal − 1 [–] (positive: the device runs fast against the host); NaN when no
        nominal rate is given.
    offset_s : float
        â, the host time of counter 0 (includes the mean transport latency). [s]
    jitter_s : float
        RMS of the receive-time residuals about the line (kept samples). [s]
    max_abs_residual_s : float
        Largest |residual| over all samples, rejected ones included. [s]
    n_rejected : int
        Samples left out of the fit as outliers (> 5 robust σ).
    gap_indices : ndarray of int64
        Indices i where the counter jumps by more than 1 from sample i − 1.
    n_missing : int
        Samples lost in those gaps.
    """

    time_s: NDArray[np.float64]
    counter: NDArray[np.int64]
    sample_period_s: float
    sample_rate_hz: float
    clock_rate_error: float
    offset_s: float
    jitter_s: float
    max_abs_residual_s: float
    n_rejected: int
    gap_indices: NDArray[np.int64]
    n_missing: int


def reconstruct_time_base(
    counter: ArrayLike,
    host_time_s: ArrayLike,
    *,
    nominal_rate_hz: float | None = None,
    counter_modulus: int | None = None,
) -> TimeBase:
    """Reconstruct device sample times from the counter and host receive times (module docstring).

    Parameters
    ----------
    counter : array_like of int, shape (n,)
        Device sample counter, increasing (modulo `counter_modulus` when given), n ≥ 3.
    host_time_s : array_like, shape (n,)
        Host receive time of each sample (non-decreasing is not required). [s]
    nominal_rate_hz : float, optional
        The device's nominal output data rate, for `clock_rate_error`. [Hz]
    counter_modulus : int, optional
        2^bits for a wrapping counter; the counter is then unwrapped.

    Returns
    -------
    TimeBase
        Reconstructed times, period, clock-rate error, jitter and gaps.

    Raises
    ------
    InvalidInputError
        If shapes disagree, values are not finite or not integral, fewer than 3 samples, or the
        counter repeats or goes backwards (after unwrapping).
    """
    c_int = _as_counter(counter)
    t_host = _as_float_vector(host_time_s, "host_time_s")
    if t_host.shape != c_int.shape:
        raise InvalidInputError(
            f"`host_time_s` must have shape {c_int.shape} (one per counter value); got "
            f"{t_host.shape}"
        )
    step = np.diff(c_int)
    if counter_modulus is not None:
        mod = int(check_positive(counter_modulus, "counter_modulus"))
        step = np.mod(step, mod)
    if np.any(step <= 0):
        i = int(np.argmax(step <= 0)) + 1
        raise InvalidInputError(
            f"`counter` must increase at every sample (modulo `counter_modulus`); got "
            f"counter[{i}] = {int(c_int[i])} after counter[{i - 1}] = {int(c_int[i - 1])}"
        )
    jumps = step > 1
    if counter_modulus is not None or jumps.any():
        c = np.concatenate([[0], np.cumsum(step)]) + c_int[0]
        gaps = np.flatnonzero(jumps) + 1
        n_missing = int(np.sum(step[jumps] - 1))
    else:  # every raw step 1: the counter is its own unwrapped form (copied: flags change)
        c = c_int.copy()
        gaps = np.zeros(0, dtype=np.int64)
        n_missing = 0

    x = (c - c[0]).astype(np.float64)
    y = t_host - t_host[0]
    keep, resid, period, intercept = _trimmed_line(x, y)
    if not period > 0:
        raise InvalidInputError(f"host time must increase with the counter; got a fitted period "
                                f"of {period:.6g} s")
    n_kept = c.size if keep is None else int(np.count_nonzero(keep))
    kept = resid if keep is None else resid[keep]
    jitter = float(np.sqrt(np.sum(kept**2) / max(n_kept - 2, 1)))
    offset = float(t_host[0] + intercept - period * c[0])
    t_rec = offset + period * c.astype(np.float64)
    rate = 1.0 / period
    err = float("nan") if nominal_rate_hz is None else rate / check_positive(
        nominal_rate_hz, "nominal_rate_hz") - 1.0
    c_out = c  # int64 already (cumsum of int64 steps)
    for arr in (t_rec, c_out, gaps):
        arr.setflags(write=False)
    return TimeBase(time_s=t_rec, counter=c_out, sample_period_s=period, sample_rate_hz=rate,
                    clock_rate_error=err, offset_s=offset, jitter_s=jitter,
                    max_abs_residual_s=float(np.abs(resid).max()),
                    n_rejected=int(c.size - n_kept), gap_indices=gaps,
                    n_missing=n_missing)


def _as_counter(counter: ArrayLike) -> NDArray[np.int64]:
    """Return the counter as int64 (n,), n ≥ 3, checking that it is finite and integral.

    An integer array is integral and finite already: it is converted without the float64 copy
    and the rounding test.
    """
    if isinstance(counter, np.ndarray) and (counter.dtype.kind == "i" or (
            counter.dtype.kind == "u" and counter.dtype.itemsize < 8)):
        c_int = counter.astype(np.int64, copy=False)
    else:
        c_raw = as_array(counter, "counter")
        if c_raw.ndim == 1 and c_raw.size >= 3 and np.any(c_raw != np.round(c_raw)):
            raise InvalidInputError("`counter` must hold integers; got non-integral values")
        c_int = c_raw.astype(np.int64)
    if c_int.ndim != 1 or c_int.size < 3:
        raise InvalidInputError(f"`counter` must have shape (n,) with n ≥ 3; got {c_int.shape}")
    return c_int


def _as_float_vector(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """Return `value` as a finite float64 array: a finite float64 array as it is (no copy).

    Anything else goes through :func:`~imucalib._checks.as_array` (conversion, messages).
    The result is only read.
    """
    if isinstance(value, np.ndarray) and value.dtype == np.float64 and bool(
            np.isfinite(value).all()):
        return value
    return as_array(value, name)


def _trimmed_line(x: NDArray[np.float64], y: NDArray[np.float64]
                  ) -> tuple[NDArray[np.bool_] | None, NDArray[np.float64], float, float]:
    """Line of y on x (Eq. (3)), refitted twice without samples beyond 5 robust σ.

    Each pass takes the median r̃ and MAD of the kept residuals, keeps
    |rᵢ − r̃| ≤ 5·1.4826·MAD (all samples count, rejected ones may return) and refits; it stops
    when fewer than 3 samples would remain or the kept set does not change.

    Returns
    -------
    keep : ndarray of bool or None
        The samples of the final fit; None when all are kept.
    resid : ndarray
        y − (b̂·x + â) of every sample about the final line. [units of y]
    slope, intercept : float
        b̂ and â.
    """
    keep: NDArray[np.bool_] | None = None  # None: every sample
    slope, intercept = _fit_line(x, y)
    resid = y - (slope * x + intercept)
    for _ in range(2):  # trimmed refits: Eq. in the module docstring
        kept = resid if keep is None else resid[keep]
        med = median(kept)
        mad = 1.4826 * median(np.abs(kept - med))
        if not mad > 0:
            break  # the kept set cannot change
        new_keep = np.abs(resid - med) <= _ROBUST_K * mad
        n_new = int(np.count_nonzero(new_keep))
        if n_new < 3 or (n_new == x.size if keep is None else np.array_equal(new_keep, keep)):
            break
        keep = None if n_new == x.size else new_keep
        slope, intercept = _fit_line(x[new_keep], y[new_keep])
        resid = y - (slope * x + intercept)
    return keep, resid, slope, intercept
