"""The noise model of window means: fitted once on the long static records, used for all.

The overlapping Allan variance of each long static window is fitted with
σ²(τ) ≈ N²/τ + C_B + K²τ/3 (white, flicker and random-walk terms; docs/noise.md §4) and
B = √(C_B/(2 ln 2/π)) (IEEE Std 952-1997 Annex C). When a run holds several records about as
long as the longest (a P1 plan's repetitions), their fitted N², C_B and K² are averaged,
weighted by duration (:func:`estimate_noise`). The standard error of a window mean of
duration T is then the model's Allan deviation at τ = T (:func:`window_mean_se`), and the
covariance of several windows' means
:func:`~imucalib.estimation.compute_window_mean_covariance` (docs/processing-estimation.md).

The procedures of long records (P3, the classical tests) use instead the white-noise density
from the scatter of block means, pooled over a unit's records (:func:`block_variance`,
:func:`pooled_white_density`): N² = Σ (K_i − 1)·s_i²·τ / Σ (K_i − 1), s_i² the variance of
record i's K_i block means of length τ (1 s). Blocks much longer than the output filter's memory
keep N free of its bias, and the Allan fit's flicker and random-walk terms of one-minute records
(poorly determined, clipped at zero, so biased upwards) stay out; noise correlated over longer
times shows in the fits' χ² instead (docs/p3.md, "On the twin").

Contents
--------
:func:`estimate_noise`, :func:`window_mean_se`, :class:`StaticWindow`, :func:`block_variance`,
:func:`pooled_white_density`
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from imucalib.models.noise import NoiseModel, compute_theoretical_adev
from imucalib.processing.moments import block_means

__all__ = ["FLICKER_FACTOR", "StaticWindow", "block_variance", "estimate_noise",
           "pooled_white_density", "window_mean_se"]

_F64 = NDArray[np.float64]

#: Allan plateau² of flicker noise per B² (IEEE 952): 2 ln 2/π.
FLICKER_FACTOR = 2.0 * math.log(2.0) / math.pi


class StaticWindow(Protocol):
    """What :func:`estimate_noise` reads of a window."""

    @property
    def kind(self) -> str:
        """``"static"`` for a window the fit may use."""
        ...

    @property
    def duration_s(self) -> float:
        """Length of the averaged span. [s]"""
        ...

    @property
    def allan_fit(self) -> _F64 | None:
        """Per channel (gyro x, y, z, accel x, y, z) the fitted N̂, Ĉ_B, K̂, shape (3, 6)."""
        ...


#: The shortest static record :func:`estimate_noise` fits a noise model to. [s]
NOISE_RECORD_MIN_S = 120.0


def estimate_noise(windows: Sequence[StaticWindow], *,
                   min_duration_s: float = NOISE_RECORD_MIN_S) -> dict[str, NoiseModel]:
    """Fit gyro and accelerometer noise models to the long static records.

    Each record's overlapping Allan variance is fitted with σ²(τ) ≈ N²/τ + C_B + K²τ/3 (the
    ``allan_fit`` of :func:`~imucalib.processing.statistics.compute_window_statistics`);
    B = √(C_B/(2 ln 2/π)). The records at least half as long as the longest are pooled: their
    N², C_B and K² averaged with weights proportional to duration (each term is linear in
    the Allan variance it describes). One record's flicker and random-walk terms are uncertain
    by a factor of about two (a 600 s record at 1 kHz: B differed by 2× between four
    repetitions of the same twin run); taking just "the longest" of several equally long
    records let the last bits of their durations choose among those estimates. Empty when no
    static window lasts `min_duration_s`. [s]
    """
    static = [w for w in windows if w.kind == "static" and w.allan_fit is not None
              and w.duration_s >= min_duration_s]
    if not static:
        return {}
    longest = max(w.duration_s for w in static)
    pooled = [w for w in static if w.duration_s >= 0.5 * longest]
    weights = np.array([w.duration_s for w in pooled]) / sum(w.duration_s for w in pooled)
    squares = np.array([1.0, 0.0, 1.0])[:, None]  # N and K are densities, C_B a variance
    fit = np.zeros((3, 6))
    for wt, w in zip(weights, pooled, strict=True):
        assert w.allan_fit is not None
        f = np.nan_to_num(w.allan_fit, nan=0.0)
        fit += wt * np.where(squares > 0, f * f, f)
    fit = np.where(squares > 0, np.sqrt(fit), fit)
    out = {}
    for triad, cols in (("gyro", slice(0, 3)), ("accel", slice(3, 6))):
        n, c_b, k = fit[0, cols], fit[1, cols], fit[2, cols]
        out[triad] = NoiseModel(white_density=np.maximum(n, 0.0),
                                bias_instability=np.sqrt(np.maximum(c_b, 0.0) / FLICKER_FACTOR),
                                random_walk=np.maximum(k, 0.0))
    return out


def window_mean_se(noise: Mapping[str, NoiseModel], duration_s: float) -> tuple[_F64, _F64]:
    """Return the (gyro, accel) standard errors of a window mean of `duration_s` [s].

    The noise model's Allan deviation at τ = duration (at least 1 ms), floored at 1e-300 so a
    weight never divides by zero. [rad/s], [m/s²]
    """
    tau = np.array([max(duration_s, 1e-3)])
    gyro = compute_theoretical_adev(noise["gyro"], tau)[0]
    accel = compute_theoretical_adev(noise["accel"], tau)[0]
    return np.maximum(gyro, 1e-300), np.maximum(accel, 1e-300)


def block_variance(values: NDArray[np.float64], period_s: float, block_s: float
                   ) -> tuple[int, _F64]:
    """Return (K − 1, s²·τ) of the K block means of length τ of each column (module docstring).

    τ is `block_s` rounded to whole sample periods `period_s`; fewer than three blocks give
    (0, NaN). s²·τ estimates N², the white-noise density squared, per column.
    """
    per_block = max(round(block_s / period_s), 1)
    cols = values.reshape(values.shape[0], -1)
    k = cols.shape[0] // per_block
    if k < 3:
        return 0, np.full(cols.shape[1], math.nan)
    means = block_means(cols, per_block)  # the reshaped mean(axis=1), bit for bit
    return k - 1, np.asarray(np.var(means, axis=0, ddof=1) * per_block * period_s,
                             dtype=np.float64)


def pooled_white_density(blocks: Sequence[tuple[int, _F64]]) -> _F64 | None:
    """Return N per column pooled over records' :func:`block_variance`, or None if none counts.

    N² = Σ (K_i − 1)·s_i²·τ / Σ (K_i − 1) over the records with blocks (module docstring).
    """
    dof = np.array([b[0] for b in blocks], dtype=float)
    ok = dof > 0
    if not ok.any():
        return None
    var = np.array([np.nan_to_num(np.asarray(b[1], dtype=float)) for b in blocks])
    return np.asarray(np.sqrt(np.maximum(dof[ok] @ var[ok] / dof[ok].sum(), 1e-300)),
                      dtype=np.float64)
