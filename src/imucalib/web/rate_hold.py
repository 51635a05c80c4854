"""Since when a motion axis holds its commanded rate: what the live view needs to place a turn.

The runner starts a window of whole revolutions once the step's ``settle_s`` has passed and
every feedback row it keeps (the last ``max(settle_check_s, 2 tick) + tick`` seconds) is within
the guard's ``rate_tolerance_dps`` of the commanded rate (``check_rate_hold``,
docs/station.md). :class:`RateHold` follows one device's feedback on its way to the runner
(:mod:`imucalib.web.run_tap`) and its ``set_rate`` commands, and keeps per axis the time of
the last row off the commanded rate: the window can start at a tick whose rows since that time
reach back over the runner's span. It keeps the feedback of the last :data:`KEEP_S` only (a new
command is checked against it) and at most :data:`MAX_ROWS` rows.
"""

from __future__ import annotations

import math
from collections import deque
from typing import Final

import numpy as np
from numpy.typing import NDArray

__all__ = ["KEEP_S", "MAX_ROWS", "RateHold"]

#: Feedback kept to check a new command against. [s]
KEEP_S: Final = 60.0
#: Feedback rows kept at most (a 1 kHz device: the last minute).
MAX_ROWS: Final = 60_000


class RateHold:
    """The time of the last feedback row off the commanded rate, per axis (module docstring).

    Parameters
    ----------
    tolerance_rps : float
        How far a row may be off the commanded rate (``inf``: never). [rad/s]
    """

    def __init__(self, tolerance_rps: float = math.inf) -> None:
        self.tolerance_rps = tolerance_rps
        self.commanded: dict[int, float] = {}
        self.off_since: dict[int, float] = {}
        self._blocks: deque[tuple[NDArray[np.float64], NDArray[np.float64]]] = deque()
        self._rows = 0

    def command(self, axis: int, rate_rps: float) -> None:
        """Note a new commanded rate of `axis`; rows kept that are off it count as off. [rad/s]"""
        self.commanded[axis] = float(rate_rps)
        self.off_since.pop(axis, None)
        for t, rate in self._blocks:
            self._check(axis, t, rate)

    def feedback(self, time_s: NDArray[np.float64], rate_rps: NDArray[np.float64]) -> None:
        """Follow a block of feedback (time [s], rates per axis [rad/s])."""
        t = np.asarray(time_s, dtype=float)
        rate = np.asarray(rate_rps, dtype=float).reshape(t.size, -1)
        if t.size == 0:
            return
        for axis in self.commanded:
            self._check(axis, t, rate)
        self._blocks.append((t, rate))
        self._rows += t.size
        while self._blocks and (self._rows > MAX_ROWS
                                or self._blocks[0][0][-1] < t[-1] - KEEP_S):
            self._rows -= self._blocks.popleft()[0].size

    def _check(self, axis: int, t: NDArray[np.float64], rate: NDArray[np.float64]) -> None:
        if axis >= rate.shape[1] or not math.isfinite(self.tolerance_rps):
            return
        off = ~(np.abs(rate[:, axis] - self.commanded[axis]) <= self.tolerance_rps)
        if off.any():
            last = float(t[off][-1])
            self.off_since[axis] = max(last, self.off_since.get(axis, -math.inf))

    def last_off_s(self, axis: int) -> float | None:
        """Return the time of the last row of `axis` off its commanded rate (None: none). [s]"""
        return self.off_since.get(axis)
