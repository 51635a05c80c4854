"""Statistics of a valid window that every procedure needs beyond the window mean.

A static window is averaged over its valid span, a turning one over the longest span of whole
revolutions (:func:`~imucalib.processing.statistics.compute_integer_revolution_window`); the
standard error of a mean, with correlated noise, is
:func:`~imucalib.processing.statistics.compute_window_statistics`'s (docs/processing-estimation.md).
Here:

- :class:`RunningMoments`: the exact mean and scatter of a long window read in blocks (bounded
  memory), each block shifted by the first block's mean to keep the sums well conditioned;
- :class:`RunningRowMean`: the mean of rows read in blocks, numpy's ``x.mean(axis=0)`` of the
  rows stacked bit for bit (numpy adds the rows of a C-ordered array of two columns or more one
  after the other; :mod:`imucalib.processing.moments`);
- :func:`table_angle_at`: the table angle at IMU sample times, extrapolated at the window's rate
  just outside the feedback span (so a window of exactly N revolutions keeps N whole ones);
- :func:`harmonic_residual_std`: the scatter of a turning window about what a calibrated model
  predicts there, the mean plus the once-per-revolution harmonic of the table angle
  (g-sensitivity to the gravity turning in the IMU, the horizontal Earth rate; docs/p1.md);
- :func:`counter_times`: a window's sample times from its counter, its dropouts checked;
- :func:`whole_revolutions`: a turning window's whole-revolution span, its mean rate and the
  samples' scatter about the once-per-revolution harmonic, the commanded revolutions checked.

Contents
--------
:class:`RunningMoments`, :class:`RunningRowMean`, :func:`harmonic_residual_std`,
:func:`table_angle_at`, :func:`counter_times`, :func:`whole_revolutions`, :class:`TurnSpan`
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import InvalidInputError, MissingSegmentError
from imucalib.processing import compute_integer_revolution_window, reconstruct_time_base
from imucalib.processing.moments import shifted_sums

__all__ = ["RunningMoments", "RunningRowMean", "TurnSpan", "counter_times", "harmonic_residual_std",
           "table_angle_at", "whole_revolutions"]

_F64 = NDArray[np.float64]


class RunningMoments:
    """Exact running mean and scatter of rows (n, k), shifted by the first block's mean.

    :meth:`add` takes each block twice: as read (for the mean) and low-passed (for the
    scatter, which then excludes the noise above the cut-off).
    """

    def __init__(self) -> None:
        self.n = 0
        self._shift: _F64 | None = None
        self._sum: _F64 | None = None
        self._sum_f: _F64 | None = None
        self._sum_f2: _F64 | None = None

    def add(self, raw: _F64, filtered: _F64) -> None:
        """Accumulate one block of rows: `raw` for the mean, `filtered` for the scatter."""
        if self._shift is None:
            self._shift = raw.mean(axis=0)
            k = raw.shape[1]
            self._sum, self._sum_f, self._sum_f2 = np.zeros(k), np.zeros(k), np.zeros(k)
        assert self._sum is not None and self._sum_f is not None and self._sum_f2 is not None
        s_raw, s_f, s_f2 = shifted_sums(raw, filtered, self._shift)  # one pass, numpy's sums
        self._sum += s_raw
        self._sum_f += s_f
        self._sum_f2 += s_f2
        self.n += raw.shape[0]

    @property
    def mean(self) -> _F64:
        """Mean of the raw rows."""
        assert self._shift is not None and self._sum is not None
        return np.asarray(self._shift + self._sum / self.n, dtype=np.float64)

    @property
    def std(self) -> _F64:
        """Standard deviation of the filtered rows about their mean (ddof = 1)."""
        assert self._sum_f is not None and self._sum_f2 is not None
        var = (self._sum_f2 - self._sum_f**2 / self.n) / max(self.n - 1, 1)
        return np.asarray(np.sqrt(np.maximum(var, 0.0)), dtype=np.float64)


class RunningRowMean:
    """Mean of rows (n, k) read in blocks, equal to ``x.mean(axis=0)`` of them stacked.

    numpy reduces axis 0 of a C-ordered array of k ≥ 2 columns row after row,
    ``((x₀ + x₁) + x₂) + …``, and divides by n: adding each block's rows in turn onto the
    running sum (the sum as the block's first row) makes the same additions, so the mean is
    numpy's bit for bit while only one block is held. (A single column, whose contiguous rows
    numpy sums pairwise, differs from it in the last bits.)
    """

    def __init__(self) -> None:
        self.n = 0
        self._sum: _F64 | None = None

    def add(self, rows: _F64) -> None:
        """Accumulate one block of rows (m, k)."""
        if rows.shape[0] == 0:
            return
        block = np.asarray(rows, dtype=np.float64)
        if self._sum is None:
            self._sum = np.add.reduce(block, axis=0)
        else:
            self._sum = np.add.reduce(np.vstack([self._sum[None, :], block]), axis=0)
        self.n += block.shape[0]

    @property
    def mean(self) -> _F64:
        """The mean of the rows added (at least one)."""
        assert self._sum is not None, "no rows added"
        return np.asarray(self._sum / self.n, dtype=np.float64)


def harmonic_residual_std(values: _F64, angle_rad: _F64) -> _F64:
    """Return the standard deviation about the mean and the once-per-revolution harmonic.

    Fits values ≈ c₀ + c₁·sin θ + c₂·cos θ per column by least squares and returns
    √(Σ r²/(n − 3)) of the residuals r (module docstring).

    Parameters
    ----------
    values : ndarray, shape (n, k)
    angle_rad : ndarray, shape (n,)
        The turning axis' angle at each row. [rad]
    """
    A = np.column_stack([np.ones_like(angle_rad), np.sin(angle_rad), np.cos(angle_rad)])
    q, _ = np.linalg.qr(A)  # the projection onto A's columns: lstsq's residual, half the time
    resid = values - q @ (q.T @ values)
    dof = max(values.shape[0] - 3, 1)
    return np.asarray(np.sqrt(np.sum(resid**2, axis=0) / dof), dtype=np.float64)


def table_angle_at(t: _F64, fb_t: _F64, fb_angle: _F64) -> _F64:
    """Return the table angle at times `t`: interpolated in the feedback span, else extrapolated.

    Outside ``[fb_t[0], fb_t[-1]]`` the angle continues at the mean rate of the feedback span
    (the table turns at constant rate through a rate window).
    """
    out = np.interp(t, fb_t, fb_angle)
    span = float(fb_t[-1] - fb_t[0])
    if span > 0:
        rate = float(fb_angle[-1] - fb_angle[0]) / span
        before, after = t < fb_t[0], t > fb_t[-1]
        out[before] = fb_angle[0] + rate * (t[before] - fb_t[0])
        out[after] = fb_angle[-1] + rate * (t[after] - fb_t[-1])
    return out


def counter_times(where: str, counter: NDArray[Any], time_s: _F64, *, max_lost_fraction: float,
                  max_gap_s: float, reconstruct: bool) -> tuple[_F64, float, int]:
    """Return (sample times, sample period, samples lost) of a window, its dropouts checked.

    With `reconstruct`, the times come from the sample counter on the receive times
    (:func:`~imucalib.processing.sync.reconstruct_time_base`: what a turn's angle weighting
    needs); otherwise the receive times serve (a static mean needs no instants). [s], [s]

    Raises
    ------
    InvalidInputError
        A counter that repeats or goes backwards.
    MissingSegmentError
        More than `max_lost_fraction` of the samples lost, or a gap longer than `max_gap_s`.
    """
    c = np.asarray(counter, dtype=np.int64)
    steps = np.diff(c)
    if np.any(steps <= 0):
        raise InvalidInputError(f"{where}: the sample counter repeats or goes backwards")
    if reconstruct:
        base = reconstruct_time_base(c, time_s)
        t, period = np.asarray(base.time_s, dtype=np.float64), float(base.sample_period_s)
    else:
        t = np.asarray(time_s, dtype=np.float64)
        period = float(t[-1] - t[0]) / float(c[-1] - c[0])
    lost = int(np.sum(steps - 1))
    expected = c.size + lost
    longest = float(np.max(steps) - 1) * period
    if lost > max_lost_fraction * expected or longest > max_gap_s:
        raise MissingSegmentError(
            f"{where}: {lost} of {expected} samples lost to dropouts (longest gap "
            f"{longest:.3g} s; at most {max_lost_fraction:.0%} and {max_gap_s:g} s are "
            "accepted)")
    return t, period, lost


@dataclass(frozen=True)
class TurnSpan:
    """The whole-revolution span of a turning window (:func:`whole_revolutions`).

    Attributes
    ----------
    mean : ndarray, shape (k,)
        The angle-weighted mean of each column over the span.
    time_s : ndarray
        The samples' times in the span. [s]
    rate_rps : float
        The mean rate over the span (encoder angle over time). [rad/s]
    n_revolutions : int
    residual : ndarray, shape (m, k)
        The samples about their mean and once-per-revolution harmonic (what the averaging
        cancels): the noise.
    """

    mean: _F64
    time_s: _F64
    rate_rps: float
    n_revolutions: int
    residual: _F64


def whole_revolutions(where: str, t: _F64, values: _F64, fb_time_s: _F64, fb_angle_rad: _F64,
                      commanded_revolutions: object = None) -> TurnSpan:
    """Return the longest whole-revolution span of a turning window (module docstring).

    The feedback angle is interpolated at the samples' times (:func:`table_angle_at`). The
    station ends a turn's window on the N-th revolution's crossing, so a sample at each edge
    may fall outside it: N − 1 whole revolutions make a complete record, fewer one cut short.

    Raises
    ------
    MissingSegmentError
        Fewer than two feedback samples, less than one revolution, or fewer than the commanded
        revolutions − 1.
    """
    if len(fb_time_s) < 2:
        raise MissingSegmentError(f"{where}: fewer than 2 feedback samples in the window")
    cols = values.reshape(values.shape[0], -1)
    angle = table_angle_at(t, np.asarray(fb_time_s, dtype=np.float64),
                           np.unwrap(np.asarray(fb_angle_rad, dtype=np.float64)))
    try:
        win = compute_integer_revolution_window(t, cols, angle_rad=angle)
    except InvalidInputError as exc:
        raise MissingSegmentError(f"{where}: {exc}") from None
    n_rev = int(win.n_revolutions)
    if isinstance(commanded_revolutions, int | float) and n_rev < int(commanded_revolutions) - 1:
        raise MissingSegmentError(
            f"{where}: the turn holds {n_rev} whole revolution(s) of the "
            f"{int(commanded_revolutions)} commanded (cut short: at least commanded − 1 are "
            "expected, a sample at each edge may fall outside the window)")
    sl = slice(win.start_index, win.stop_index)
    ts, a = t[sl], angle[sl]
    design = np.column_stack([np.ones(a.size), np.sin(a), np.cos(a)])
    coef, *_ = np.linalg.lstsq(design, cols[sl], rcond=None)
    return TurnSpan(mean=np.asarray(win.mean, dtype=np.float64).ravel(), time_s=ts,
                    rate_rps=float((a[-1] - a[0]) / (ts[-1] - ts[0])), n_revolutions=n_rev,
                    residual=cols[sl] - design @ coef)
