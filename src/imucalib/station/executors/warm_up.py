"""The executor of the warm-up step: at least its duration, then until the output stops drifting.

Drifting means: for some IMU, the mean of its gyro or accelerometer output over the last
``window_s`` differs from the mean over the window before by more than ``max_gyro_drift_dps``
or ``max_accel_drift_g``. A warm-up records no valid window.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from imucalib import units
from imucalib.plan.schema import WarmUpStep
from imucalib.station.executors.base import StepOutcome
from imucalib.station.signals import StepTrip

if TYPE_CHECKING:
    from imucalib.station.session import RunSession

__all__ = ["run_warm_up"]


def run_warm_up(session: RunSession, step: WarmUpStep, attempt: int = 0, row: int = -1
                ) -> StepOutcome:
    """Execute a warm-up: at least its duration, then until the output stops drifting."""
    s = session
    t_cmd = s.now()
    limits = np.r_[np.full(3, step.max_gyro_drift_dps * units.DEG),
                   np.full(3, step.max_accel_drift_g * units.G0_MPS2)]

    def drift() -> str | None:
        now = s.now()
        for name, win in s.gyro_means.items():
            t, means = win.rows(now - 2 * step.window_s)
            last, prev = means[t >= now - step.window_s], means[t < now - step.window_s]
            if last.size == 0 or prev.size == 0:
                return f"IMU {name}: not enough history"
            change = np.abs(last.mean(axis=0) - prev.mean(axis=0))
            if np.any(change > limits):
                return f"IMU {name}: output still drifting (change {change.max():.3g} SI)"
        return None

    while True:
        s.tick()
        if s.now() - t_cmd >= step.duration_s and drift() is None:
            return StepOutcome()
        if s.now() - t_cmd >= step.timeout_s:
            raise StepTrip(f"warm-up: output still drifting after {step.timeout_s:g} s: "
                           f"{drift()}")
