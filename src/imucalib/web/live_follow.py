"""What the live view adds to a run's state in the worker: windows, the soak, a temperature trace.

:class:`LiveFollower` is fed by :class:`~imucalib.web.run_reporter.RunReporter` after every tick
of the runner. It keeps, in bounded memory,

- the station times of the current step's ticks (and the turning axes' angles), to find the
  step's valid window when it ends (:func:`~imucalib.web.window_stats.find_window`) and give
  each unit's mean and σ over it (:meth:`LiveFollower.window_event`);
- during a soak step, the criterion of the plan (band, stable-for time) and how far the run is
  towards it: since when the chamber air is within the band, how much each unit's temperature
  varied over the last ``stable_for_s`` (:meth:`LiveFollower.soak`), as the runner's soak
  executor checks it (docs/station.md);
- a temperature trace decimated to one point per :data:`TRACE_EVERY_S` of station time and at
  most :data:`TRACE_HZ` a wall second (:meth:`LiveFollower.trace_point`), for the soak chart
  of a page opened late.

Watching changes nothing of the run (docs/web.md, "Live view").
"""

from __future__ import annotations

import itertools
import math
import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Final

from imucalib import units
from imucalib.plan.schema import (
    CentrifugeStep,
    Plan,
    PositionStep,
    RateStep,
    SoakStep,
    StaticStep,
)
from imucalib.web.run_tap import SignalTap
from imucalib.web.window_stats import find_window, window_stats

__all__ = ["MAX_TICKS", "TRACE_EVERY_S", "TRACE_HZ", "WINDOW_KINDS", "LiveFollower"]

#: Tick times kept for one step (a longer step keeps its latest ones).
MAX_TICKS: Final = 20_000
#: Station time between two points of the temperature trace. [s]
TRACE_EVERY_S: Final = 5.0
#: Points of the temperature trace a wall second, at most (a twin faster than real time).
TRACE_HZ: Final = 2.0
#: The step kinds whose valid window is averaged (the analyses' static and rate windows).
WINDOW_KINDS: Final = frozenset({"static", "position", "rate", "centrifuge"})


def _value(values: Any, axis: int) -> float | None:
    if isinstance(values, list) and len(values) > axis and values[axis] is not None:
        return float(values[axis])
    return None


@dataclass(frozen=True)
class _Axis:
    """A turning axis's last feedback row of a tick, and its last row off the command.

    ``time_s`` [s] and ``angle_deg`` [°] of the row; ``off_s`` the time of the last row off the
    commanded rate (None: none) [s].
    """

    time_s: float
    angle_deg: float
    off_s: float | None

    @classmethod
    def of(cls, tap: SignalTap, role: str, axis: int) -> _Axis | None:
        feedback = tap.table if role == "table" else tap.centrifuge
        t, angle = feedback.get("time_s"), _value(feedback.get("angle_deg"), axis)
        if t is None or angle is None:
            return None
        hold = tap.rate_holds.get(role)
        return cls(float(t), angle, hold.last_off_s(axis) if hold is not None else None)


@dataclass(frozen=True)
class _Tick:
    """One tick of the runner: when it ended [s], and the turning axes' last rows."""

    time_s: float
    table: _Axis | None
    centrifuge: _Axis | None


class LiveFollower:
    """The live view's state of one run in the worker (module docstring).

    Parameters
    ----------
    plan : Plan
    tap : SignalTap
        The station's latest values and its binned IMU samples.
    """

    def __init__(self, plan: Plan, tap: SignalTap) -> None:
        self.plan, self.tap = plan, tap
        tap.set_rate_tolerance(plan.guards.rate_tolerance_dps * units.DEG)
        self.ticks: deque[_Tick] = deque(maxlen=MAX_TICKS)
        self.soak_index = -1
        self.soak_rows: deque[tuple[float, dict[str, float]]] = deque(maxlen=MAX_TICKS)
        self.in_band_since: float | None = None
        self._trace_station = -math.inf
        self._trace_wall = -math.inf

    # --- ticks and steps --------------------------------------------------------------------
    def tick(self, time_s: float, step_index: int) -> None:
        """Note a tick of the runner that ended at station time `time_s`. [s]"""
        if self.ticks and abs(self.ticks[-1].time_s - time_s) < 1e-9:
            return                     # the runner's report after a step: no new tick
        step = self.plan.steps[step_index] if 0 <= step_index < len(self.plan.steps) else None
        axis = step.axis if isinstance(step, RateStep) else 0
        self.ticks.append(_Tick(time_s, _Axis.of(self.tap, "table", axis),
                                _Axis.of(self.tap, "centrifuge", 0)))
        if isinstance(step, SoakStep):
            self._soak_tick(step_index, step, time_s)

    def step_started(self, index: int) -> None:
        """Note that step `index` began: keep the tick before it (a window may start there)."""
        while len(self.ticks) > 2:
            self.ticks.popleft()
        if len(self.ticks) == 2:
            self.tap.forget_before(self.ticks[0].time_s)
        if index != self.soak_index:
            self.soak_rows.clear()
            self.in_band_since = None
            self.soak_index = -1

    def window_event(self, index: int) -> dict[str, Any] | None:
        """Return step `index`'s window, with each unit's mean and σ, when it has one.

        Called when the step is done; the data before the window's end is dropped after.
        """
        step = self.plan.steps[index] if 0 <= index < len(self.plan.steps) else None
        if step is None or step.kind not in WINDOW_KINDS or not self.ticks:
            return None
        times = [tick.time_s for tick in self.ticks]
        commanded: dict[str, Any] = {}
        window: tuple[float, float] | None
        if isinstance(step, StaticStep):
            window = find_window(times, step.duration_s)
        elif isinstance(step, PositionStep):
            window = find_window(times, step.record_s)
            commanded["angles_deg"] = list(step.angles_deg)
        elif isinstance(step, RateStep | CentrifugeStep):
            commanded["rate_dps"] = step.rate_dps
            if isinstance(step, RateStep):
                commanded["axis"] = step.axis
            if step.revolutions is not None and step.rate_dps != 0:
                window = self._turn_window(step)
            else:
                window = find_window(times, step.record_s or 0.0)
        else:
            window = None
        if window is None:
            return None
        stats = {name: s for name, m in self.tap.moments.items()
                 if (s := window_stats(m, *window)) is not None}
        self.tap.forget_before(window[1])
        if not stats:
            return None
        return {"step_index": index, "kind": step.kind, "label": self.plan.step_label(index),
                "t_start_s": window[0], "t_end_s": window[1],
                "duration_s": window[1] - window[0], "commanded": commanded, "units": stats}

    def _turn_window(self, step: RateStep | CentrifugeStep) -> tuple[float, float] | None:
        """Return the window of whole revolutions of a rate or centrifuge step.

        It starts where the runner starts it: at the first tick ``settle_s`` after the step
        began whose feedback over the runner's span (``max(settle_check_s, 2 tick) + tick``)
        holds the commanded rate (:mod:`imucalib.web.rate_hold`), at that tick's last row; it
        ends where the axis crossed the turn, between the rows around it. Without that (no
        rate known) the window is found from the angles alone (:func:`find_window`).
        """
        assert step.revolutions is not None
        fuge = isinstance(step, CentrifugeStep)
        ticks = list(self.ticks)
        turn = step.revolutions * 360.0
        tick_s = max((b.time_s - a.time_s for a, b in itertools.pairwise(ticks)),
                     default=0.0)
        span = max(self.plan.guards.settle_check_s, 2 * tick_s) + tick_s
        t_cmd = ticks[0].time_s
        rows = [r for tick in ticks if (r := tick.centrifuge if fuge else tick.table)]
        for k, tick in enumerate(ticks[1:], start=1):
            row = tick.centrifuge if fuge else tick.table
            if row is None or tick.time_s - t_cmd < step.settle_s - 1e-9 or (
                    row.off_s is not None and row.off_s >= row.time_s - span):
                continue
            later = [r for t in ticks[k:] if (r := t.centrifuge if fuge else t.table)]
            window = find_window([r.time_s for r in later], turn / abs(step.rate_dps),
                                 angles_deg=[r.angle_deg for r in later], turn_deg=turn,
                                 from_first=True)
            if window is not None:
                return window
            break
        return find_window([r.time_s for r in rows], turn / abs(step.rate_dps),
                           angles_deg=[r.angle_deg for r in rows], turn_deg=turn)

    # --- the soak ---------------------------------------------------------------------------
    def _soak_tick(self, index: int, step: SoakStep, time_s: float) -> None:
        if index != self.soak_index:
            self.soak_index = index
            self.soak_rows.clear()
            self.in_band_since = None
        air = self.tap.chamber.get("air_degc")
        inside = air is not None and abs(float(air) - step.temperature_degc) <= step.band_degc
        if not inside:
            self.in_band_since = None
        elif self.in_band_since is None:
            self.in_band_since = time_s
        temps = {k: float(v["temperature_degc"]) for k, v in self.tap.imus.items()
                 if v.get("temperature_degc") is not None}
        self.soak_rows.append((time_s, temps))
        while self.soak_rows and self.soak_rows[0][0] < time_s - step.stable_for_s:
            self.soak_rows.popleft()

    def soak(self, step_index: int, time_s: float) -> dict[str, Any] | None:
        """Return the soak criterion of the running soak step and where the run stands."""
        step = self.plan.steps[step_index] if 0 <= step_index < len(self.plan.steps) else None
        if not isinstance(step, SoakStep):
            return None
        low: dict[str, float] = {}
        high: dict[str, float] = {}
        for _t, temps in self.soak_rows:
            for name, value in temps.items():
                low[name] = min(low.get(name, value), value)
                high[name] = max(high.get(name, value), value)
        return {"step_index": step_index, "setpoint_degc": step.temperature_degc,
                "band_degc": step.band_degc, "imu_band_degc": step.imu_band_degc,
                "stable_for_s": step.stable_for_s, "timeout_s": step.timeout_s,
                "in_band_s": (time_s - self.in_band_since
                              if self.in_band_since is not None else 0.0),
                "unit_span_degc": {n: high[n] - low[n] for n in sorted(low)}}

    # --- the temperature trace --------------------------------------------------------------
    def trace_point(self, time_s: float, step_index: int) -> dict[str, Any] | None:
        """Return a point of the temperature trace when one is due (module docstring)."""
        now = time.monotonic()
        if time_s - self._trace_station < TRACE_EVERY_S or now - self._trace_wall < 1 / TRACE_HZ:
            return None
        chamber = self.tap.chamber
        units = {k: v.get("temperature_degc") for k, v in self.tap.imus.items()}
        if chamber.get("air_degc") is None and not any(v is not None for v in units.values()):
            return None
        self._trace_station, self._trace_wall = time_s, now
        return {"time_s": time_s, "step_index": step_index,
                "air_degc": chamber.get("air_degc"),
                "setpoint_degc": chamber.get("setpoint_degc"), "unit_degc": units}
