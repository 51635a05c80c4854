"""The station clock on real equipment: monotonic time since the run started, optionally sped up.

Contents
--------
:class:`MonotonicClock`
    A :class:`~imucalib.station.devices.Clock` on ``time.monotonic()``; with ``speed`` > 1 it runs
    faster than the wall (the simulator servers share one such clock as their virtual time base,
    see :class:`~imucalib.drivers.simulators.SimTimeBase`).
"""

from __future__ import annotations

import math
import time

from imucalib.errors import InvalidInputError

__all__ = ["MonotonicClock"]


class MonotonicClock:
    """Seconds since construction on ``time.monotonic()``, multiplied by `speed`, plus `start_s`.

    Parameters
    ----------
    speed : float
        Clock seconds per wall second (1 on real equipment; e.g. 10 to run simulator servers and
        a station under test ten times faster than real time). [–]
    start_s : float
        Clock time at construction (a resumed run continues after its recording's last
        sample). [s]

    Notes
    -----
    :meth:`now_s` is monotonic and thread-safe; :meth:`sleep` lets `duration_s` clock seconds
    pass (``duration_s / speed`` wall seconds).
    """

    def __init__(self, speed: float = 1.0, *, start_s: float = 0.0) -> None:
        value = float(speed)
        if not math.isfinite(value) or value <= 0.0:
            raise InvalidInputError(f"`speed` must be a finite number > 0; got {speed!r}")
        start = float(start_s)
        if not math.isfinite(start):
            raise InvalidInputError(f"`start_s` must be finite; got {start_s!r}")
        self.speed = value
        self.start_s = start
        self.start_monotonic_s = time.monotonic()

    def now_s(self) -> float:
        """Return the clock time: `start_s` plus the scaled time since construction. [s]"""
        return self.start_s + (time.monotonic() - self.start_monotonic_s) * self.speed

    def sleep(self, duration_s: float) -> None:
        """Let `duration_s` clock seconds pass (nothing for a duration ≤ 0). [s]"""
        if duration_s > 0.0:
            time.sleep(duration_s / self.speed)

    def wall_s(self, duration_s: float) -> float:
        """Return the wall-clock seconds that `duration_s` clock seconds take. [s]"""
        return duration_s / self.speed

    def __repr__(self) -> str:
        return f"{type(self).__name__}(speed={self.speed:g}, start_s={self.start_s:g})"
