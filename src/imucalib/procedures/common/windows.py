"""Statistics of a valid window that every procedure needs beyond the window mean.

A static window is averaged over its valid span, a turning one over the longest span of whole
revolutions (:func:`~imucalib.processing.statistics.compute_integer_revolution_window`); the
standard error of a mean, with correlated noise, is
:func:`~imucalib.processing.statistics.compute_window_statistics`'s (docs/processing-estimation.md).
Here:

- :class:`RunningMoments`: the exact mean and scatter of a long window read in blocks (bounded
  memory), each block shifted by the first block's mean to keep the sums well conditioned;
- :func:`table_angle_at`: the table angle at IMU sample times, extrapolated at the window's rate
  just outside the feedback span (so a window of exactly N revolutions keeps N whole ones);
- :func:`harmonic_residual_std`: the scatter of a turning window about what a calibrated model
  predicts there, the mean plus the once-per-revolution harmonic of the table angle
  (g-sensitivity to the gravity turning in the IMU, the horizontal Earth rate; docs/p1.md).

Contents
--------
:class:`RunningMoments`, :func:`harmonic_residual_std`, :func:`table_angle_at`
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["RunningMoments", "harmonic_residual_std", "table_angle_at"]

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
        self._sum += (raw - self._shift).sum(axis=0)
        d = filtered - self._shift
        self._sum_f += d.sum(axis=0)
        self._sum_f2 += (d * d).sum(axis=0)
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
    coef, *_ = np.linalg.lstsq(A, values, rcond=None)
    resid = values - A @ coef
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
