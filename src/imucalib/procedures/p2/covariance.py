"""The covariance of P2's window means and its propagation, shared by the analysis and the plan.

P2's estimates are linear in the window means y (per channel: gyro x, y, z, accelerometer
x, y, z): the point fits θ_k = Q_k·y_k (:func:`~imucalib.procedures.p2.reduction.least_squares`,
its gain linearised at the solution) and the temperature models β_i = W_i·θ_i. Whatever the
linear map G from the means, the covariance is

    Cov(G·y) = Σ_ch G_ch·C_ch·G_chᵀ                                         (TD.P1)

with C_ch the covariance of one channel's window means: under the unit's coloured noise
(white, flicker, random walk) Eq. (TD.2) of docs/test-design.md between every pair of windows
from their start times and lengths (:func:`~imucalib.estimation.compute_window_mean_covariance`,
docs/equations.md Eq. (11.2); Papoulis and Pillai 2002, §9-4), the random walk taken from the
start of the run; for independent windows diag(σ_j²). The channels' noise is independent
(one noise model per axis), so their contributions add. :func:`~imucalib.procedures.p2.predict.
predict_p2` evaluates it on a plan's nominal windows, :func:`~imucalib.procedures.p2.analysis.
analyze_unit` on the recorded ones (docs/p2.md, "Temperature models").

Contents
--------
:func:`window_covariance`, :func:`independent_covariance`, :func:`propagate`,
:func:`means_operator`, :data:`N_CHANNELS`
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib.errors import InvalidInputError
from imucalib.estimation.noise_covariance import compute_window_mean_covariance
from imucalib.models.noise import NoiseModel
from imucalib.procedures.p2.reduction import ORIENTATIONS

__all__ = ["N_CHANNELS", "independent_covariance", "means_operator", "propagate",
           "window_covariance"]

_F64 = NDArray[np.float64]
#: Channels of a window mean: gyro x, y, z, then accelerometer x, y, z.
N_CHANNELS: Final = 6
_TRIADS: Final = ("gyro", "accel")


def window_covariance(noise: Mapping[str, NoiseModel], start_s: ArrayLike,
                      duration_s: ArrayLike, *, reference_time_s: float = 0.0) -> _F64:
    """Return C_ch of Eq. (TD.2) for every channel, shape (6, n, n). [SI²]

    Parameters
    ----------
    noise : mapping of str to NoiseModel
        ``{"gyro": …, "accel": …}``, the unit's noise.
    start_s, duration_s : array_like, shape (n,)
        Each window's start on the run's clock and its length. [s]
    reference_time_s : float
        Where the random walk starts (the run's start; the twin's truth is the bias there),
        clipped to the first window's start. [s]
    """
    starts = np.asarray(start_s, dtype=np.float64)
    durs = np.maximum(np.asarray(duration_s, dtype=np.float64), 1e-3)
    ref = min(float(reference_time_s), float(starts.min()))
    out = np.zeros((N_CHANNELS, starts.size, starts.size))
    for t, triad in enumerate(_TRIADS):
        out[3 * t:3 * t + 3] = compute_window_mean_covariance(noise[triad], starts, durs,
                                                              reference_time_s=ref)
    return out


def independent_covariance(se: ArrayLike) -> _F64:
    """Return diag(σ_j²) per channel, shape (6, n, n), from standard errors (n, 6). [SI²]"""
    s = np.asarray(se, dtype=np.float64)
    if s.ndim != 2 or s.shape[1] != N_CHANNELS:
        raise InvalidInputError(f"standard errors must have shape (n, 6); got {s.shape}")
    out = np.zeros((N_CHANNELS, s.shape[0], s.shape[0]))
    idx = np.arange(s.shape[0])
    out[:, idx, idx] = (s**2).T
    return out


def propagate(gain: _F64, covariance: _F64) -> _F64:
    """Return Σ_ch G_ch·C_ch·G_chᵀ of Eq. (TD.P1), symmetrised; `gain` (6, m, n), C (6, n, n)."""
    out = np.zeros((gain.shape[1], gain.shape[1]))
    for g, c in zip(gain, covariance, strict=True):
        out += g @ c @ g.T
    return 0.5 * (out + out.T)


def means_operator(orientations: Sequence[str], kinds: Sequence[str],
                   rates_rps: Sequence[float]) -> tuple[_F64, NDArray[np.int_]]:
    """Return the map from a point's window means to its 90 combined means, and their channels.

    The order of :meth:`~imucalib.procedures.p2.reduction.PointWindows.means_vector`: the
    static accelerometer means, the +ω and −ω gyro means, the +ω and −ω accelerometer means,
    each (6 orientations × 3 axes), every one the plain mean of its windows
    (:func:`~imucalib.procedures.p2.analysis.assemble_point`). Row r of the (90, n) matrix
    averages channel ``channel[r]`` of its windows.
    """
    n = len(orientations)
    op = np.zeros((90, n))
    channel = np.zeros(90, dtype=np.int_)
    groups = (("static", 0, 3), ("plus", 1, 0), ("minus", -1, 0), ("plus", 1, 3),
              ("minus", -1, 3))
    for f, (kind, sign, ch0) in enumerate(groups):
        for o_i, o in enumerate(ORIENTATIONS):
            mine = [j for j in range(n) if orientations[j] == o and (
                kinds[j] == "static" if kind == "static"
                else kinds[j] == "rate" and sign * rates_rps[j] > 0)]
            for a in range(3):
                r = 18 * f + 3 * o_i + a
                channel[r] = ch0 + a
                if mine:
                    op[r, mine] = 1.0 / len(mine)
    return op, channel
