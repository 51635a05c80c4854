"""The checks every window reduction makes, and the pooled white-noise standard error.

A procedure reduces each recorded step's valid window to a mean (docs/procedures.md). Before it
averages, it reads the window's samples once and refuses a window that cannot give an honest
mean: too few samples, a NaN or infinite sample, a sample the IMU flagged saturated (a clipped
mean is biased), or, in :func:`~imucalib.procedures.common.windows.counter_times`, a counter
that repeats or more dropouts than the limits allow. Every window's standard error then comes
from the white-noise density pooled over the unit's windows,

    σ_mean = N / √T,                                                              (W.1)

with N² the pooled block variance s²·τ of :func:`~imucalib.procedures.common.noise.
pooled_white_density` and T the window's span.

Contents
--------
:class:`WindowLimits`, :class:`BlockNoiseLimits`, :data:`MIN_WINDOW_SAMPLES`,
:func:`checked_samples`,
:func:`pooled_white_se`
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import InvalidInputError, MissingSegmentError, SaturationError
from imucalib.io.reader import StreamData
from imucalib.procedures.common.noise import pooled_white_density

__all__ = ["MIN_WINDOW_SAMPLES", "BlockNoiseLimits", "WindowLimits", "checked_samples",
           "pooled_white_se"]

_F64 = NDArray[np.float64]

#: The fewest samples a window may hold.
MIN_WINDOW_SAMPLES = 10


@dataclass(frozen=True)
class WindowLimits:
    """What a window may lose to dropouts: every procedure's processing options extend it.

    Attributes
    ----------
    max_lost_fraction : float
        Samples lost to dropouts a window may miss (fraction of those expected).
    max_gap_s : float
        Longest single dropout in a window. [s]
    """

    max_lost_fraction: float = 0.01
    max_gap_s: float = 0.5

    def __post_init__(self) -> None:
        if not (math.isfinite(self.max_lost_fraction) and 0.0 <= self.max_lost_fraction <= 1.0):
            raise InvalidInputError(f"`max_lost_fraction` must be in [0, 1]; got "
                                    f"{self.max_lost_fraction!r}")
        if not (math.isfinite(self.max_gap_s) and self.max_gap_s >= 0.0):
            raise InvalidInputError(f"`max_gap_s` must be ≥ 0; got {self.max_gap_s!r}")


@dataclass(frozen=True)
class BlockNoiseLimits(WindowLimits):
    """The window limits and the noise blocks of the pooled standard error, Eq. (W.1).

    For the procedures whose standard errors are :func:`pooled_white_se`'s.

    Attributes
    ----------
    noise_block_s : float
        Length of the blocks whose means' scatter gives the white-noise density. [s]
    """

    noise_block_s: float = 1.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (math.isfinite(self.noise_block_s) and self.noise_block_s > 0):
            raise InvalidInputError(f"`noise_block_s` must be positive; got "
                                    f"{self.noise_block_s!r}")


def checked_samples(where: str, data: StreamData, columns: Sequence[str], *,
                    saturation_note: Callable[[_F64], str] | None = None) -> _F64:
    """Return the window's samples of `columns`, shape (n, k), refusing a bad window.

    Parameters
    ----------
    where : str
        The window in messages (``"unit IMU-1, step 4 (+x up)"``).
    data : StreamData
        The window's rows (with the ``saturated`` column).
    columns : sequence of str
        The columns to average.
    saturation_note : callable, optional
        Given the samples, the text that follows "N of M samples flagged saturated" (what
        reached its range, what to do).

    Raises
    ------
    MissingSegmentError
        Fewer than :data:`MIN_WINDOW_SAMPLES` samples.
    InvalidInputError
        A NaN or infinite sample.
    SaturationError
        A sample flagged saturated.
    """
    n = len(data)
    if n < MIN_WINDOW_SAMPLES:
        raise MissingSegmentError(f"{where}: only {n} samples in its valid window")
    values = np.column_stack([np.asarray(data.columns[c], dtype=np.float64) for c in columns])
    if not np.all(np.isfinite(values)):
        raise InvalidInputError(f"{where}: the window holds NaN or infinite samples")
    saturated = int(np.count_nonzero(np.asarray(data.columns["saturated"])))
    if saturated:
        note = saturation_note(values) if saturation_note is not None else ""
        raise SaturationError(f"{where}: {saturated} of {n} samples flagged saturated{note}")
    return values


def pooled_white_se(block_variances: Sequence[tuple[int, _F64]], durations_s: Sequence[float],
                    *, unit: str, what: str = "window") -> list[_F64]:
    """Return each window's white-noise standard error N/√T, Eq. (W.1).

    Parameters
    ----------
    block_variances : sequence of (int, ndarray)
        Each window's degrees of freedom K − 1 and block variance s²·τ per channel.
    durations_s : sequence of float
        Each window's span T. [s]
    unit, what : str
        The unit and what a window is (``"turn"``, ``"record"``) in the message.

    Raises
    ------
    MissingSegmentError
        No window is long enough for three noise blocks.
    """
    white = pooled_white_density(list(block_variances))
    if white is None:
        raise MissingSegmentError(f"unit {unit}: no {what} is long enough for the noise "
                                  "estimate (three blocks of noise_block_s)")
    return [np.asarray(white / math.sqrt(max(d, 1e-3)), dtype=np.float64) for d in durations_s]
