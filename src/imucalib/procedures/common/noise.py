"""The noise model of window means: fitted once on the longest static record, used for all.

The overlapping Allan variance of the longest static window is fitted with
σ²(τ) ≈ N²/τ + C_B + K²τ/3 (white, flicker and random-walk terms; docs/noise.md §4) and
B = √(C_B/(2 ln 2/π)) (IEEE Std 952-1997 Annex C). The standard error of a window mean of
duration T is then the model's Allan deviation at τ = T (:func:`window_mean_se`), and the
covariance of several windows' means
:func:`~imucalib.estimation.compute_window_mean_covariance` (docs/processing-estimation.md).

Contents
--------
:func:`estimate_noise`, :func:`window_mean_se`, :class:`StaticWindow`
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from imucalib.models.noise import NoiseModel, compute_theoretical_adev

__all__ = ["FLICKER_FACTOR", "StaticWindow", "estimate_noise", "window_mean_se"]

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


def estimate_noise(windows: Sequence[StaticWindow], *, min_duration_s: float = 120.0
                   ) -> dict[str, NoiseModel]:
    """Fit gyro and accelerometer noise models to the longest static record.

    The record's overlapping Allan variance is fitted with σ²(τ) ≈ N²/τ + C_B + K²τ/3 (the
    ``allan_fit`` of :func:`~imucalib.processing.statistics.compute_window_statistics`);
    B = √(C_B/(2 ln 2/π)). Empty when no static window lasts `min_duration_s`. [s]
    """
    static = [w for w in windows if w.kind == "static" and w.allan_fit is not None
              and w.duration_s >= min_duration_s]
    if not static:
        return {}
    best = max(static, key=lambda w: w.duration_s)
    assert best.allan_fit is not None
    fit = np.nan_to_num(best.allan_fit, nan=0.0)
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
