"""The executor of the soak step: set the chamber, wait until it and every IMU are stable.

Stable means: over the last ``stable_for_s`` the chamber air stayed within ``band_degc`` of the
set point and each IMU's temperature varied by at most ``imu_band_degc``. The step's valid
window is that stable span; from then on the chamber band is guarded while recording.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from imucalib.plan.schema import SoakStep
from imucalib.station.executors.base import StepOutcome
from imucalib.station.guards import check_chamber_band
from imucalib.station.signals import StepTrip

if TYPE_CHECKING:
    from imucalib.station.session import RunSession

__all__ = ["run_soak"]


def run_soak(session: RunSession, step: SoakStep, attempt: int = 0, row: int = -1
             ) -> StepOutcome:
    """Execute a soak: set the chamber, wait for stability; return the stable span."""
    s = session
    chamber = s.station.chamber
    assert chamber is not None
    ramp = None if step.ramp_degc_per_min is None else step.ramp_degc_per_min / 60.0
    chamber.set_temperature(step.temperature_degc, ramp_degc_ps=ramp)
    s.chamber_setpoint = None  # no band guard while the temperature changes
    t_cmd = s.now()
    for win in s.temps.values():
        win.clear()

    def stable() -> str | None:
        t0 = s.now() - step.stable_for_s
        _, air = s.chamber_rows.rows(t0)
        if air.size == 0 or not s.chamber_rows.covers(t0):
            return "chamber: not enough history"
        reason = check_chamber_band(air[:, 0], step.temperature_degc, step.band_degc)
        if reason:
            return reason
        for name, win in s.temps.items():
            if not win.covers(t0):
                return f"IMU {name}: not enough history"
            _, temp = win.rows(t0)
            span = float(temp.max() - temp.min())
            if span > step.imu_band_degc:
                return (f"IMU {name} temperature varied {span:.3g} °C over "
                        f"{step.stable_for_s:g} s (limit {step.imu_band_degc:g} °C)")
        return None

    deadline = t_cmd + step.timeout_s
    while True:
        s.tick()
        if s.now() - t_cmd >= step.stable_for_s and stable() is None:
            s.chamber_setpoint = step.temperature_degc
            return StepOutcome(window=(s.now() - step.stable_for_s, s.now()))
        if s.now() >= deadline:
            raise StepTrip(f"soak at {step.temperature_degc:g} °C not stable within "
                           f"{step.timeout_s:g} s: {stable()}")
