"""A recorded window's mean and its σ, for the live view, from the blocks the runner read.

The runner reads each IMU once a tick (:mod:`imucalib.web.run_tap`). :class:`BinnedMoments` keeps,
per bin of receive time (:data:`BIN_S` wide), the count, sums and sums of squares of a unit's
six channels (gyro and accelerometer): enough for the mean and the standard deviation over any
span of whole bins, in bounded memory (at most :data:`MAX_BINS` bins; a longer span doubles
the bin width). :func:`find_window` finds a step's valid window from the times of the runner's
ticks (and, for a whole number of revolutions, the angle of the turning axis at each tick);
:func:`window_stats` returns the mean, the standard deviation and the standard error of the
mean over it.

The numbers are the page's: the calibration takes its windows from the Recording
(docs/web.md, "Live view"). The standard error is σ/√n, the white-noise value; coloured noise
makes the true one larger (docs/noise.md).
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections.abc import Sequence
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from imucalib import units

__all__ = ["BIN_S", "MAX_BINS", "BinnedMoments", "find_window", "window_stats"]

#: Width of a bin of receive time (a window's edges are placed to half of it). [s]
BIN_S: Final = 0.05
#: Bins kept per unit; beyond it the bin width doubles.
MAX_BINS: Final = 4096
#: Two station times closer than this are the same tick. [s]
TIME_TOL_S: Final = 1e-6
_CHANNELS: Final = 6


class BinnedMoments:
    """Per-bin count, sums and sums of squares of one unit's gyro and accelerometer samples.

    The sums are of the samples less a reference (the first block's mean), so that the
    variance of a small noise on a large value (gravity) keeps its digits.

    Parameters
    ----------
    bin_s : float
        The initial bin width. [s]
    max_bins : int
        Bins kept at most.
    """

    def __init__(self, bin_s: float = BIN_S, max_bins: int = MAX_BINS) -> None:
        self.base_bin_s = bin_s
        self.bin_s = bin_s
        self.max_bins = max_bins
        self.ref: NDArray[np.float64] | None = None
        self.bins: dict[int, NDArray[np.float64]] = {}

    def add(self, time_s: NDArray[np.float64], gyro_rps: NDArray[np.float64],
            accel_mps2: NDArray[np.float64]) -> None:
        """Add a block of samples (receive time [s], gyro [rad/s], accel [m/s²])."""
        x = np.column_stack([gyro_rps, accel_mps2]).astype(float)
        ok = np.isfinite(time_s) & np.isfinite(x).all(axis=1)
        if not ok.any():
            return
        t, x = np.asarray(time_s, dtype=float)[ok], x[ok]
        if self.ref is None:
            self.ref = x.mean(axis=0)
        d = x - self.ref
        keys = np.floor(t / self.bin_s).astype(np.int64)
        uniq, inverse = np.unique(keys, return_inverse=True)
        n = np.bincount(inverse).astype(float)
        s = np.stack([np.bincount(inverse, weights=d[:, c]) for c in range(_CHANNELS)], axis=1)
        q = np.stack([np.bincount(inverse, weights=d[:, c] ** 2) for c in range(_CHANNELS)],
                     axis=1)
        for j, key in enumerate(uniq.tolist()):
            row = np.concatenate([[n[j]], s[j], q[j]])
            old = self.bins.get(key)
            self.bins[key] = row if old is None else old + row
        while len(self.bins) > self.max_bins:
            self._coarsen()

    def _coarsen(self) -> None:
        merged: dict[int, NDArray[np.float64]] = {}
        for key, row in self.bins.items():
            k = key // 2
            merged[k] = row if k not in merged else merged[k] + row
        self.bins, self.bin_s = merged, self.bin_s * 2.0

    def drop_before(self, time_s: float) -> None:
        """Forget the bins that end before `time_s` (a fresh start once none is left). [s]"""
        self.bins = {k: v for k, v in self.bins.items() if (k + 1) * self.bin_s > time_s}
        if not self.bins:
            self.bin_s, self.ref = self.base_bin_s, None

    def sums(self, start_s: float, end_s: float) -> tuple[NDArray[np.float64], float]:
        """Return the summed bins whose middle is in [`start_s`, `end_s`], and the bin width.

        The row is the count, the six sums and the six sums of squares. [s]
        """
        total = np.zeros(1 + 2 * _CHANNELS)
        for key, row in self.bins.items():
            middle = (key + 0.5) * self.bin_s
            if start_s <= middle <= end_s:
                total += row
        return total, self.bin_s

    def __len__(self) -> int:
        return len(self.bins)


def window_stats(moments: BinnedMoments, start_s: float, end_s: float) -> dict[str, Any] | None:
    """Return a unit's mean, standard deviation and standard error over a window (None: empty).

    Gyro in °/s, specific force in g, per sensor axis; ``n`` the samples, ``bin_s`` the bin
    width the edges were placed to.
    """
    row, bin_s = moments.sums(start_s, end_s)
    n = float(row[0])
    if n < 1 or moments.ref is None:
        return None
    s, q = row[1:1 + _CHANNELS], row[1 + _CHANNELS:]
    mean_d = s / n
    var = np.maximum(q - n * mean_d ** 2, 0.0) / (n - 1) if n > 1 else np.full(_CHANNELS, np.nan)
    sd = np.sqrt(var)
    se = sd / math.sqrt(n)
    mean = moments.ref + mean_d
    gyro, accel = 1.0 / units.DEG, 1.0 / units.G0_MPS2

    def out(values: NDArray[np.float64], scale: float) -> list[float | None]:
        return [float(v) * scale if math.isfinite(float(v)) else None for v in values]

    return {"n": int(n), "bin_s": bin_s,
            "gyro_dps": out(mean[:3], gyro), "gyro_sd_dps": out(sd[:3], gyro),
            "gyro_se_dps": out(se[:3], gyro),
            "accel_g": out(mean[3:], accel), "accel_sd_g": out(sd[3:], accel),
            "accel_se_g": out(se[3:], accel)}


def find_window(ticks: Sequence[float], duration_s: float, *,
                angles_deg: Sequence[float | None] | None = None,
                turn_deg: float | None = None,
                from_first: bool = False) -> tuple[float, float] | None:
    """Return a step's valid window from the station times its ticks ended at (None: none).

    A window of a fixed length (``record_s``, a static step's ``duration_s``) starts at a tick's
    end and ends at a later one, `duration_s` after it: the latest such pair is taken. A window
    of whole revolutions (`turn_deg` of the turning axis, whose angle at each tick's end is in
    `angles_deg`) starts at the latest tick from which the axis has turned `turn_deg` by the
    last tick, and lasts `duration_s` (the turn at the commanded rate).

    Parameters
    ----------
    ticks : sequence of float
        The station times of the step's ticks, rising, the tick before the step first; for a
        turn, the times of the turning axis's last feedback row of each tick. [s]
    duration_s : float
        The window's length (a turn's is found from the angles). [s]
    angles_deg : sequence of float or None, optional
        The turning axis's angle at each tick's end. [°]
    turn_deg : float, optional
        How far the axis turns in the window (revolutions × 360). [°]
    from_first : bool
        For a turn: it starts at the first row, and ends at its first crossing of `turn_deg`.
    """
    if not ticks or not duration_s > 0:
        return None
    if turn_deg is not None and angles_deg is not None:
        return _turn_window(ticks, angles_deg, turn_deg, from_first)
    times = list(ticks)
    tol = TIME_TOL_S * max(1.0, abs(times[-1]))
    for j in range(len(times) - 1, 0, -1):
        want = times[j] - duration_s
        i = bisect.bisect_left(times, want - tol, 0, j)
        if i < j and abs(times[i] - want) <= tol:
            return float(times[i]), float(times[j])
    return None


def _turn_window(times: Sequence[float], angles: Sequence[float | None], turn_deg: float,
                 from_first: bool) -> tuple[float, float] | None:
    rows = [(float(t), float(a)) for t, a in zip(times, angles, strict=True) if a is not None]
    if len(rows) < 2:
        return None
    if from_first:
        t0, a0 = rows[0]
        for (t_prev, a_prev), (t, a) in itertools.pairwise(rows):
            before, after = abs(a_prev - a0), abs(a - a0)
            if after >= turn_deg:
                frac = (turn_deg - before) / (after - before) if after > before else 1.0
                return t0, t_prev + frac * (t - t_prev)
        return None
    (t_prev, a_prev), (t_last, a_last) = rows[-2], rows[-1]
    for t0, a0 in rows[:-1]:      # the earliest start whose turn ends in the last tick
        before, after = abs(a_prev - a0), abs(a_last - a0)
        if before < turn_deg <= after:
            frac = (turn_deg - before) / (after - before)
            return t0, t_prev + frac * (t_last - t_prev)
    return None
