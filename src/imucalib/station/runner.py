"""Execute a plan on a station and write its Recording, with guards, retries and resume.

Contents
--------
:func:`run_plan`
    Run a plan on a station into a new Recording.
:func:`resume_run`
    Continue an interrupted run from its first incomplete step, appending to its Recording.
:class:`RunOptions`, :class:`RunSummary`, :class:`RunStatus`
    Options, outcome, and the live status passed to ``on_status`` after every tick.

How a step runs
---------------
Every stream is acquired continuously: each tick (``tick_s`` of station time) polls the table,
centrifuge and chamber, reads every IMU, writes it all, and checks the guards. A step

1. commands its devices (``move_to``, ``set_rate``, ``set_temperature`` …);
2. *settles*: waits at least ``settle_s`` and until, over the last ``settle_check_s``, the table
   feedback is within the position (5″) or rate (0.5 °/s) tolerance and the accelerometer's
   fluctuation (:func:`~imucalib.station.guards.accel_fluctuation_g`) is within 0.001 g; gives up
   after ``settle_timeout_s``;
3. *records*: the valid window starts there and lasts ``record_s``, or, for ``revolutions``,
   ends at the first feedback sample where the measured angle has turned that many whole turns
   (so the window spans them to within one sample);
4. is marked done with its valid window.

Guards during the valid window: table position or rate deviation, IMU saturation, output jumps,
lost samples and CRC failures, chamber out of its band after a soak; at any time: device errors
and time-outs, latched table faults, chamber alarms, an IMU that stops delivering. A trip brings
the motion to a safe state (rate to zero, mode off; the chamber to standby on a chamber alarm),
marks the step ``invalid`` with the reason, logs it, then retries the step (reconnecting the
devices) or stops the run, as ``guards.on_trip`` and ``guards.max_retries`` say. Only ``done``
steps carry data an analysis uses. Ctrl-C or any exception also stops the equipment safely,
marks the running step ``aborted`` and closes the file.

Resume
------
The Recording is the checkpoint: each step row's ``commanded`` JSON holds its plan index
(``plan_step``) and attempt. :func:`resume_run` recovers a file a killed runner left open (the
original is kept as ``<stem>.crashed.h5``), marks the interrupted step ``aborted``, and continues
with the first plan step not done, appending to the same file on a time base that continues
after its last sample. Completed steps keep their data; nothing is repeated or lost.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from imucalib import units
from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS
from imucalib.errors import DeviceError, InvalidInputError, RecordingError
from imucalib.io._schema import StreamSpec
from imucalib.io.reader import open_recording
from imucalib.io.recording import RecordingWriter
from imucalib.io.recover import recover_recording
from imucalib.io.streams import (
    DEVICE_CENTRIFUGE,
    DEVICE_CHAMBER,
    DEVICE_IMU,
    DEVICE_TABLE,
    axis_columns,
    chamber_stream_spec,
    imu_stream_spec,
    motion_stream_spec,
)
from imucalib.plan.io import parse_plan, plan_hash, plan_to_toml
from imucalib.plan.schema import (
    CentrifugeStep,
    OperatorCheckStep,
    Plan,
    PositionStep,
    RateStep,
    SoakStep,
    StaticStep,
    WarmUpStep,
)
from imucalib.station.devices import ImuIdentity, MotionDevice, Station
from imucalib.station.guards import (
    RollingWindow,
    accel_fluctuation_g,
    check_chamber_band,
    check_counter,
    check_jumps,
    check_position_hold,
    check_rate_hold,
    check_saturation,
)
from imucalib.station.operator import AutoOperator, Operator

__all__ = ["RunOptions", "RunStatus", "RunSummary", "resume_run", "run_plan"]

_log = logging.getLogger(__name__)
_DRAIN_S = 1.0  # station time acquired after the last step [s]


@dataclass
class RunStatus:
    """What a live view shows; updated in place after every tick."""

    plan: str = ""
    n_steps: int = 0
    step_index: int = -1
    step_label: str = ""
    phase: str = ""
    attempt: int = 0
    time_s: float = 0.0
    steps_done: int = 0
    steps_invalid: int = 0
    remaining_min_s: float = 0.0
    table_angle_deg: tuple[float, ...] = ()
    table_rate_dps: tuple[float, ...] = ()
    chamber_degc: float | None = None
    imu_temperature_degc: dict[str, float] = field(default_factory=dict)
    imu_rate_hz: dict[str, float] = field(default_factory=dict)
    imu_errors: dict[str, str] = field(default_factory=dict)
    last_event: str = ""


@dataclass
class RunOptions:
    """How to run.

    Attributes
    ----------
    tick_s : float
        Station time between acquisitions and guard checks. [s]
    operator : Operator
        Who confirms operator checks (default: confirms automatically as "auto").
    on_status : callable, optional
        Called with the :class:`RunStatus` after every tick (the CLI's live view).
    flush_interval_s : float
        Wall-clock interval between flushes of the Recording. [s]
    truth : mapping, optional
        Twin truth to store under ``/truth`` (never read by analysis).
    station_toml : str
        The station file's text, stored so that a resume can rebuild the same station.
    """

    tick_s: float = 0.5
    operator: Operator = field(default_factory=AutoOperator)
    on_status: Callable[[RunStatus], None] | None = None
    flush_interval_s: float = 1.0
    truth: dict[str, Any] | None = None
    station_toml: str = ""


@dataclass(frozen=True)
class RunSummary:
    """The outcome of a run.

    ``status`` is ``"done"`` or ``"aborted"`` (a trip that stopped it, an operator who declined);
    an exception propagates after the equipment was stopped safely.
    """

    path: Path
    plan: str
    status: str
    steps_done: int
    steps_invalid: int
    trips: tuple[str, ...]
    start_s: float
    end_s: float
    reason: str = ""


class _TripError(Exception):
    """A guard tripped inside a step (internal; surfaces as GuardTripError when it stops a run)."""


class _StopError(Exception):
    """The run stops without a retry (operator declined, retries exhausted)."""


def _stream_specs(station: Station, identities: list[ImuIdentity]) -> list[StreamSpec]:
    specs = [imu_stream_spec(i.name) for i in identities]
    if station.table is not None:
        specs.append(motion_stream_spec(DEVICE_TABLE, station.table.name,
                                        station.table.axis_names))
    if station.centrifuge is not None:
        specs.append(motion_stream_spec(DEVICE_CENTRIFUGE, station.centrifuge.name,
                                        station.centrifuge.axis_names))
    if station.chamber is not None:
        specs.append(chamber_stream_spec(station.chamber.name))
    return specs


def check_plan_against_station(plan: Plan, station: Station) -> None:
    """Refuse, before anything moves, a plan the station cannot execute.

    Raises
    ------
    ConfigurationError
        A step needing a device the station lacks, or table angles for a different axis count.
    """
    from imucalib.errors import ConfigurationError

    for i, step in enumerate(plan.steps):
        where = f"steps.{i} ({step.kind} {plan.step_label(i)!r})"
        if isinstance(step, PositionStep | RateStep):
            if station.table is None:
                raise ConfigurationError(f"{where}: needs a rate table; the station has none")
            n = len(station.table.axis_names)
            if isinstance(step, PositionStep) and len(step.angles_deg) != n:
                raise ConfigurationError(
                    f"{where}: angles_deg has {len(step.angles_deg)} value(s); the table has {n} "
                    f"axis/axes {station.table.axis_names}")
            if isinstance(step, RateStep) and step.axis >= n:
                raise ConfigurationError(f"{where}: axis {step.axis} does not exist on the table "
                                         f"(axes {station.table.axis_names})")
        if isinstance(step, CentrifugeStep) and station.centrifuge is None:
            raise ConfigurationError(f"{where}: needs a centrifuge; the station has none")
        if isinstance(step, SoakStep) and station.chamber is None:
            raise ConfigurationError(f"{where}: needs a thermal chamber; the station has none")


class _Run:
    """One session of a run: acquisition, guards and step execution on an open writer."""

    def __init__(self, plan: Plan, station: Station, writer: RecordingWriter,
                 options: RunOptions, identities: list[ImuIdentity]) -> None:
        self.plan, self.station, self.writer, self.opt = plan, station, writer, options
        self.g = plan.guards
        self.ids = {i.name: i for i in identities}
        span = max(self.g.settle_check_s, 2.0 * options.tick_s) + options.tick_s
        self.fb = RollingWindow(span)
        self.fuge_fb = RollingWindow(span)
        self.accel = {name: RollingWindow(span) for name in self.ids}
        self.temps = {name: RollingWindow(3600.0) for name in self.ids}
        self.gyro_means = {name: RollingWindow(3600.0) for name in self.ids}
        self.chamber_rows = RollingWindow(3600.0)
        self.chamber_setpoint: float | None = None
        self.last_sample_s = dict.fromkeys(self.ids, station.clock.now_s())
        self.health0 = {src.name: src.health() for src in station.imus}
        self.status = RunStatus(plan=plan.name, n_steps=len(plan.steps))
        self.trips: list[str] = []
        self.recording = False  # inside a valid window: data-quality guards apply
        self.held_targets: list[float] | None = None  # the table's last position targets
        self.block_reason: str | None = None

    # --- acquisition ------------------------------------------------------------------------
    def now(self) -> float:
        return self.station.clock.now_s()

    def tick(self, until_s: float | None = None) -> None:
        """Let time pass (at most one tick, not beyond `until_s`), acquire, check device guards."""
        dt = self.opt.tick_s if until_s is None else min(self.opt.tick_s, until_s - self.now())
        if dt > 0:
            self.station.clock.sleep(dt)
        self.acquire()

    def acquire(self) -> None:
        st, w = self.station, self.writer
        self.block_reason = None
        try:
            for dev, kind, window in ((st.table, DEVICE_TABLE, self.fb),
                                      (st.centrifuge, DEVICE_CENTRIFUGE, self.fuge_fb)):
                if dev is None:
                    continue
                fb = dev.poll()
                if len(fb):
                    cols: dict[str, Any] = {"time_s": fb.time_s}
                    for i, axis in enumerate(dev.axis_names):
                        a, r = axis_columns(axis)
                        cols[a], cols[r] = fb.angle_rad[:, i], fb.rate_rps[:, i]
                    w.append(kind, dev.name, cols)
                    window.push(fb.time_s, np.column_stack([fb.angle_rad, fb.rate_rps]))
                    self.status.table_angle_deg = tuple(np.degrees(fb.angle_rad[-1]))
                    self.status.table_rate_dps = tuple(np.degrees(fb.rate_rps[-1]))
                status = dev.status()
                if status.fault is not None:
                    raise _TripError(f"{kind} {dev.name} fault: {status.fault}")
            if st.chamber is not None:
                rows = st.chamber.poll()
                if len(rows):
                    w.append(DEVICE_CHAMBER, st.chamber.name, {
                        "time_s": rows.time_s, "temperature_degc": rows.temperature_degc,
                        "setpoint_degc": rows.setpoint_degc})
                    self.chamber_rows.push(rows.time_s, rows.temperature_degc[:, None])
                    self.status.chamber_degc = float(rows.temperature_degc[-1])
                alarm = st.chamber.status().alarm
                if alarm is not None:
                    raise _TripError(f"chamber {st.chamber.name} alarm: {alarm}")
            for src in st.imus:
                self._acquire_imu(src)
        except DeviceError as exc:
            raise _TripError(f"device error: {exc}") from exc

    def _acquire_imu(self, src: Any) -> None:
        block = src.read()
        name = src.name
        now = self.now()
        if len(block):
            cols: dict[str, Any] = {"time_s": block.time_s, "device_time_s": block.device_time_s,
                                    "counter": block.counter,
                                    "temperature_degc": block.temperature_degc,
                                    "saturated": block.saturated}
            for j, c in enumerate(GYRO_COLUMNS):
                cols[c] = block.gyro_rps[:, j]
            for j, c in enumerate(ACCEL_COLUMNS):
                cols[c] = block.accel_mps2[:, j]
            self.writer.append(DEVICE_IMU, name, cols)
            self.accel[name].push(block.time_s, block.accel_mps2)
            self.temps[name].push(block.time_s[-1:], block.temperature_degc[-1:, None])
            self.gyro_means[name].push(block.time_s[-1:],
                                       np.r_[block.gyro_rps.mean(axis=0),
                                             block.accel_mps2.mean(axis=0)][None, :])
            self.last_sample_s[name] = float(block.time_s[-1])
            self.status.imu_temperature_degc[name] = float(block.temperature_degc[-1])
            self.status.imu_rate_hz[name] = len(block) / max(self.opt.tick_s, 1e-9)
        elif now - self.last_sample_s[name] > self.g.device_timeout_s:
            raise _TripError(f"IMU {name}: no data for {now - self.last_sample_s[name]:.3g} s "
                        f"(time-out {self.g.device_timeout_s:g} s)")
        health = src.health()
        h0 = self.health0[name]
        crc = health.crc_errors - h0.crc_errors
        missing = health.missing_samples - h0.missing_samples
        self.status.imu_errors[name] = f"crc {health.crc_errors}, lost {health.missing_samples}"
        if self.recording and len(block):
            ident = self.ids[name]
            reason = (check_counter(name, missing, crc, self.g.max_counter_gap_samples,
                                    self.g.max_crc_errors)
                      or (check_saturation(name, block.gyro_rps, block.accel_mps2,
                                           block.saturated, ident.gyro_range_rps,
                                           ident.accel_range_mps2)
                          if self.g.trip_on_saturation else None)
                      or check_jumps(name, block.gyro_rps, block.accel_mps2,
                                     self.g.gyro_jump_dps * units.DEG,
                                     self.g.accel_jump_g * units.G0_MPS2))
            if reason:
                raise _TripError(reason)
        elif self.recording and (crc or missing):
            reason = check_counter(name, missing, crc, self.g.max_counter_gap_samples,
                                   self.g.max_crc_errors)
            if reason:
                raise _TripError(reason)
        self.health0[name] = health

    # --- criteria ---------------------------------------------------------------------------
    def motion_rows(self, fuge: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t, v = (self.fuge_fb if fuge else self.fb).rows()
        k = v.shape[1] // 2 if v.size else 0
        return t, v[:, :k], v[:, k:]

    def accel_settled(self) -> str | None:
        worst = 0.0
        for name, win in self.accel.items():
            t, a = win.rows(self.now() - self.g.settle_check_s)
            if t.size == 0 or t[-1] - t[0] < 0.5 * self.g.settle_check_s:
                return f"IMU {name}: not enough data yet"
            worst = max(worst, accel_fluctuation_g(t, a, self.g.settle_average_s))
        if worst > self.g.settle_fluctuation_g:
            return (f"accelerometer fluctuation {worst:.3g} g (limit "
                    f"{self.g.settle_fluctuation_g:g} g)")
        return None

    def guard_chamber(self) -> None:
        if self.recording and self.chamber_setpoint is not None:
            _, rows = self.chamber_rows.rows(self.now() - self.opt.tick_s)
            if rows.size:
                reason = check_chamber_band(rows[:, 0], self.chamber_setpoint,
                                            self.g.chamber_band_degc)
                if reason:
                    raise _TripError(reason)

    # --- step kinds -------------------------------------------------------------------------
    def settle(self, t_cmd: float, settle_s: float, criterion: Callable[[], str | None],
               correct: Callable[[str], bool] | None = None) -> None:
        """Tick until `settle_s` has passed and `criterion` holds; trip after the time-out.

        `correct` (SPEC.md P1's "automatic correction") is offered each failing reason once
        per `settle_check_s` after the dwell; it re-commands the equipment when the reason is
        one it can correct, and says whether it did.
        """
        deadline = t_cmd + self.g.settle_timeout_s + settle_s
        last_fix = -math.inf
        while True:
            self.tick()
            if self.now() - t_cmd >= settle_s:
                reason = criterion()
                if reason is None:
                    return
                if self.now() >= deadline:
                    raise _TripError(
                        f"never settled within {self.g.settle_timeout_s:g} s: {reason}")
                if correct is not None and self.now() - last_fix >= 2 * self.g.settle_check_s \
                        and correct(reason):
                    last_fix = self.now()
                    self.writer.log_event(self.now(), "info", "runner",
                                          f"automatic correction: {reason}; re-commanded")

    def record_for(self, duration_s: float, guard: Callable[[], None]) -> tuple[float, float]:
        start = self.now()
        self.recording = True
        try:
            while self.now() < start + duration_s - 1e-9:
                self.tick(start + duration_s)
                guard()
                self.guard_chamber()
        finally:
            self.recording = False
        return start, start + duration_s

    def record_revolutions(self, fuge: bool, axis: int, revolutions: int,
                           guard: Callable[[], None]) -> tuple[float, float]:
        t, angle, _ = self.motion_rows(fuge)
        start, theta0 = float(t[-1]), float(angle[-1, axis])
        target = revolutions * 2.0 * math.pi
        self.recording = True
        try:
            while True:
                self.tick()
                guard()
                self.guard_chamber()
                t, angle, _ = self.motion_rows(fuge)
                turned = np.abs(angle[:, axis] - theta0)
                hit = np.flatnonzero((t > start) & (turned >= target))
                if hit.size:
                    # the crossing, interpolated between the feedback rows around it (the
                    # angle is linear at constant rate): exact whatever the feedback rate
                    h = int(hit[0])
                    if h == 0 or t[h - 1] < start or turned[h] == turned[h - 1]:
                        return start, float(t[h])
                    frac = (target - turned[h - 1]) / (turned[h] - turned[h - 1])
                    return start, float(t[h - 1] + frac * (t[h] - t[h - 1]))
        finally:
            self.recording = False

    def run_motion(self, step: PositionStep | RateStep | CentrifugeStep
                   ) -> tuple[float, float]:
        fuge = isinstance(step, CentrifugeStep)
        dev: MotionDevice | None = self.station.centrifuge if fuge else self.station.table
        assert dev is not None  # checked against the station before the run
        names = dev.axis_names
        pos_tol = self.g.position_tolerance_arcsec * units.ARCSEC
        hold_tol = self.g.hold_rate_tolerance_dps * units.DEG
        rate_tol = self.g.rate_tolerance_dps * units.DEG
        t_cmd = self.now()
        if isinstance(step, PositionStep) or (isinstance(step, CentrifugeStep)
                                              and step.arm_position_deg is not None):
            angles = (list(step.angles_deg) if isinstance(step, PositionStep)
                      else [step.arm_position_deg or 0.0])
            targets = [a * units.DEG for a in angles]
            if fuge:
                dev.set_rate(0, 0.0)
                self.settle(t_cmd, 0.0, lambda: check_rate_hold(
                    self.motion_rows(True)[2], 0.0, 0, names[0], hold_tol))
            for i, target in enumerate(targets):
                dev.move_to(i, target)
            if not fuge:
                self.held_targets = targets

            def hold() -> str | None:
                _, angle, rate = self.motion_rows(fuge)
                return (check_position_hold(angle, targets, names, pos_tol)
                        or next((r for i in range(len(targets))
                                 if (r := check_rate_hold(rate, 0.0, i, names[i], hold_tol))),
                                None))

            def correct(reason: str) -> bool:
                """Re-command the axes when, at rest over the last tick, one is off target."""
                angle, rate = self._latest(fuge)
                if rate.size == 0 or np.abs(rate).max() > hold_tol:
                    return False  # still moving: the move is not over yet
                if check_position_hold(angle, targets, names, pos_tol) is None:
                    return False  # arrived; the settling span has yet to pass
                for i, target in enumerate(targets):
                    dev.move_to(i, target)
                return True

            self.settle(t_cmd, step.settle_s, lambda: hold() or self.accel_settled(), correct)

            def guard() -> None:
                angle, _ = self._latest(fuge)
                reason = check_position_hold(angle, targets, names, pos_tol)
                if reason:
                    raise _TripError(reason)

            assert step.record_s is not None  # an arm position records for a duration
            return self.record_for(step.record_s, guard)
        axis = 0 if fuge else step.axis  # type: ignore[union-attr]
        rate = step.rate_dps * units.DEG
        dev.set_rate(axis, rate)
        self.settle(t_cmd, step.settle_s, lambda: check_rate_hold(
            self.motion_rows(fuge)[2], rate, axis, names[axis], rate_tol))

        def rate_guard() -> None:
            reason = check_rate_hold(self._latest(fuge)[1], rate, axis, names[axis], rate_tol)
            if reason:
                raise _TripError(reason)

        if step.revolutions is not None:
            return self.record_revolutions(fuge, axis, step.revolutions, rate_guard)
        assert step.record_s is not None
        return self.record_for(step.record_s, rate_guard)

    def _latest(self, fuge: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Measured angles and rates of the last tick."""
        t, angle, rate = self.motion_rows(fuge)
        recent = t > self.now() - self.opt.tick_s - 1e-9
        return angle[recent], rate[recent]

    def run_static(self, step: StaticStep, attempt: int) -> tuple[float, float]:
        table = self.station.table
        names = table.axis_names if table is not None else ()
        tol = self.g.position_tolerance_arcsec * units.ARCSEC
        if table is not None and attempt > 0 and self.held_targets is not None:
            # a retry after a safe stop: back to the position the record was made at
            targets = self.held_targets
            t_cmd = self.now()
            for i, target in enumerate(targets):
                table.move_to(i, target)
            self.settle(t_cmd, 0.0, lambda: check_position_hold(
                self.motion_rows()[1], targets, names, tol) or self.accel_settled())
        held: list[float] | None = None
        if table is not None:
            _, angle, _ = self.motion_rows()
            held = list(angle[-1]) if angle.size else None

        def guard() -> None:
            if held is not None:
                angle, _ = self._latest()
                reason = check_position_hold(angle, held, names, tol)
                if reason:
                    raise _TripError(reason)

        return self.record_for(step.duration_s, guard)

    def run_soak(self, step: SoakStep) -> tuple[float, float]:
        chamber = self.station.chamber
        assert chamber is not None
        ramp = None if step.ramp_degc_per_min is None else step.ramp_degc_per_min / 60.0
        chamber.set_temperature(step.temperature_degc, ramp_degc_ps=ramp)
        self.chamber_setpoint = None  # no band guard while the temperature changes
        t_cmd = self.now()
        for win in self.temps.values():
            win.clear()

        def stable() -> str | None:
            t0 = self.now() - step.stable_for_s
            _, air = self.chamber_rows.rows(t0)
            if air.size == 0 or not self.chamber_rows.covers(t0):
                return "chamber: not enough history"
            reason = check_chamber_band(air[:, 0], step.temperature_degc, step.band_degc)
            if reason:
                return reason
            for name, win in self.temps.items():
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
            self.tick()
            if self.now() - t_cmd >= step.stable_for_s and stable() is None:
                self.chamber_setpoint = step.temperature_degc
                return self.now() - step.stable_for_s, self.now()
            if self.now() >= deadline:
                raise _TripError(f"soak at {step.temperature_degc:g} °C not stable within "
                            f"{step.timeout_s:g} s: {stable()}")

    def run_warm_up(self, step: WarmUpStep) -> None:
        t_cmd = self.now()
        limits = np.r_[np.full(3, step.max_gyro_drift_dps * units.DEG),
                       np.full(3, step.max_accel_drift_g * units.G0_MPS2)]

        def drift() -> str | None:
            now = self.now()
            for name, win in self.gyro_means.items():
                t, means = win.rows(now - 2 * step.window_s)
                last, prev = means[t >= now - step.window_s], means[t < now - step.window_s]
                if last.size == 0 or prev.size == 0:
                    return f"IMU {name}: not enough history"
                change = np.abs(last.mean(axis=0) - prev.mean(axis=0))
                if np.any(change > limits):
                    return f"IMU {name}: output still drifting (change {change.max():.3g} SI)"
            return None

        while True:
            self.tick()
            if self.now() - t_cmd >= step.duration_s and drift() is None:
                return
            if self.now() - t_cmd >= step.timeout_s:
                raise _TripError(f"warm-up: output still drifting after {step.timeout_s:g} s: "
                            f"{drift()}")

    # --- the step loop ----------------------------------------------------------------------
    def execute(self, index: int, attempt: int) -> str:
        """Run plan step `index` once; return "done" (raises _TripError, _StopError)."""
        step = self.plan.steps[index]
        label = self.plan.step_label(index)
        commanded = {**step.model_dump(mode="json"), "plan_step": index, "attempt": attempt}
        row = self.writer.begin_step(step.kind, label, self.now(), commanded=commanded)
        self.status.step_index, self.status.step_label, self.status.attempt = index, label, attempt
        self.writer.log_event(self.now(), "info", "runner",
                              f"step {index} ({label}) started, attempt {attempt + 1}")
        try:
            window: tuple[float, float] | None = None
            note = ""
            if isinstance(step, OperatorCheckStep):
                answer = self.opt.operator.confirm(step.item)
                note = (f"{'confirmed' if answer.confirmed else 'declined'} by {answer.who} at "
                        f"{answer.when_utc}" + (f": {answer.note}" if answer.note else ""))
                self.writer.log_event(self.now(), "info" if answer.confirmed else "warning",
                                      f"operator:{answer.who}", f"{step.item} — {note}")
                if not answer.confirmed:
                    self.writer.update_step(row, t_end_s=self.now(), status="aborted", note=note)
                    raise _StopError(f"operator {answer.who} did not confirm: {step.item}")
            elif isinstance(step, PositionStep | RateStep | CentrifugeStep):
                window = self.run_motion(step)
            elif isinstance(step, StaticStep):
                window = self.run_static(step, attempt)
            elif isinstance(step, SoakStep):
                window = self.run_soak(step)
            elif isinstance(step, WarmUpStep):
                self.run_warm_up(step)
            fields: dict[str, Any] = {"t_end_s": self.now(), "status": "done"}
            if window is not None:
                fields.update(valid_start_s=window[0], valid_end_s=window[1])
            if note:
                fields["note"] = note
            self.writer.update_step(row, **fields)
            self.status.steps_done += 1
            return "done"
        except _TripError as trip:
            self.recording = False
            self.writer.update_step(row, t_end_s=self.now(), status="invalid", note=str(trip))
            raise
        except BaseException as exc:
            self.recording = False
            if not isinstance(exc, _StopError):
                self.writer.update_step(row, t_end_s=self.now(), status="aborted",
                                        note=f"interrupted: {type(exc).__name__}: {exc}"[:2000])
            raise

    def safe_state(self, *, chamber_too: bool = False) -> None:
        for dev in (self.station.table, self.station.centrifuge):
            if dev is not None:
                try:
                    dev.safe_stop()
                except Exception as exc:  # a safe stop must not hide the original problem
                    _log.error("safe stop of %s failed: %s", dev.name, exc)
        if chamber_too and self.station.chamber is not None:
            try:
                self.station.chamber.standby()
            except Exception as exc:
                _log.error("chamber standby failed: %s", exc)

    def reconnect(self) -> None:
        for dev in (self.station.table, self.station.centrifuge):
            if dev is not None:
                dev.connect()

    def recover(self, index: int) -> None:
        """Reconnect and wait until every device is healthy, or stop after the time-out."""
        deadline = self.now() + self.g.recover_timeout_s
        while True:
            try:
                self.reconnect()
                self.tick()
                return
            except (_TripError, DeviceError) as exc:
                if self.now() >= deadline:
                    raise _StopError(f"step {index}: cannot resume after the trip: still "
                                     f"failing after {self.g.recover_timeout_s:g} s: {exc}"
                                     ) from exc
                self.safe_state()
                self.station.clock.sleep(self.opt.tick_s)

    def run_steps(self, first: int) -> None:
        n = len(self.plan.steps)
        for index in range(first, n):
            self.status.remaining_min_s = _remaining_s(self.plan, index)
            attempt = 0
            while True:
                try:
                    self.execute(index, attempt)
                    break
                except _TripError as trip:
                    reason = str(trip)
                    self.trips.append(reason)
                    self.status.steps_invalid += 1
                    self.status.last_event = f"trip: {reason}"
                    chamber_fault = reason.startswith("chamber")
                    self.safe_state(chamber_too=chamber_fault)
                    retry = self.g.on_trip == "retry" and attempt < self.g.max_retries
                    self.writer.log_event(self.now(), "warning", "guard",
                                          f"step {index} ({self.plan.step_label(index)}): "
                                          f"{reason}; equipment stopped safely; "
                                          + ("retrying" if retry else "stopping the run"))
                    if not retry:
                        raise _StopError(f"step {index} tripped: {reason}") from trip
                    attempt += 1
                    if chamber_fault:
                        self.chamber_setpoint = None
                    self.recover(index)
            self.status.step_index = index
            if self.opt.on_status is not None:
                self.opt.on_status(self.status)

    def _notify(self) -> None:
        if self.opt.on_status is not None:
            self.status.time_s = self.now()
            self.opt.on_status(self.status)


def _remaining_s(plan: Plan, first: int) -> float:
    from imucalib.plan.schema import step_min_duration_s

    return float(sum(step_min_duration_s(s) for s in plan.steps[first:]))


def _identities(station: Station) -> list[ImuIdentity]:
    out = []
    for src in station.imus:
        ident = src.identify()
        if ident.name != src.name:
            raise InvalidInputError(f"IMU source {src.name!r} identifies as {ident.name!r}")
        out.append(ident)
    return out


def _connect(station: Station, plan: Plan) -> list[ImuIdentity]:
    for dev in (station.table, station.centrifuge):
        if dev is not None:
            dev.connect()
            for i, _ in enumerate(dev.axis_names):
                limit = (plan.limits.max_centrifuge_rate_dps if dev is station.centrifuge
                         else plan.limits.max_rate_dps)
                dev.set_limits(i, rate_rps=limit * units.DEG,
                               accel_rps2=plan.limits.max_accel_dps2 * units.DEG)
    if station.chamber is not None:
        station.chamber.connect()
    for src in station.imus:
        src.connect()
    return _identities(station)


def _drive(run: _Run, first: int) -> RunSummary:
    """Run the steps from `first`, with the safety net; return the outcome."""
    start = run.now()
    status, reason = "done", ""
    tick = run.tick

    def tick_and_notify(until_s: float | None = None) -> None:
        tick(until_s)
        run._notify()

    run.tick = tick_and_notify  # type: ignore[method-assign]
    try:
        run.acquire()
        run.run_steps(first)
        # samples still in transit (IMU packets arrive after the moment they describe) belong
        # to the last window: keep acquiring a moment before closing
        drain_until = run.now() + max(run.opt.tick_s, _DRAIN_S)
        while run.now() < drain_until - 1e-9:
            run.tick(drain_until)
        run.writer.log_event(run.now(), "info", "runner", f"plan {run.plan.name!r} completed")
    except _StopError as stop:
        status, reason = "aborted", str(stop)
        run.safe_state()
        run.writer.log_event(run.now(), "error", "runner", f"run stopped: {reason}")
    except BaseException as exc:
        run.safe_state(chamber_too=True)
        try:
            run.writer.log_event(run.now(), "error", "runner",
                                 f"run interrupted: {type(exc).__name__}: {exc}"[:4000])
        finally:
            run.writer.close()
        raise
    return RunSummary(path=run.writer.path, plan=run.plan.name, status=status,
                      steps_done=run.status.steps_done, steps_invalid=run.status.steps_invalid,
                      trips=tuple(run.trips), start_s=start, end_s=run.now(), reason=reason)


def run_plan(plan: Plan, station: Station, path: str | Path, *,
             options: RunOptions | None = None, overwrite: bool = False) -> RunSummary:
    """Execute `plan` on `station`, writing a new Recording at `path`.

    Raises
    ------
    ConfigurationError
        If the plan needs a device the station lacks (nothing has moved).
    RecordingError
        If `path` exists and `overwrite` is false.
    DeviceError
        If a device cannot be connected (nothing has moved).
    """
    opt = options or RunOptions()
    if not opt.tick_s > 0:
        raise InvalidInputError(f"`tick_s` must be > 0; got {opt.tick_s!r}")
    check_plan_against_station(plan, station)
    if Path(path).exists() and not overwrite:
        raise RecordingError(f"{path} exists; pass overwrite=True to replace it")
    identities = _connect(station, plan)
    meta: dict[str, str | int | float | bool] = {
        "plan_toml": plan_to_toml(plan), "plan_hash": plan_hash(plan),
        "station_json": json.dumps(station.describe()),
        "station_toml": opt.station_toml,
        "imu_identity_json": json.dumps({i.name: {
            "serial": i.name, "model": i.model, "maker": i.maker,
            "sample_rate_hz": i.sample_rate_hz, "gyro_range_rps": i.gyro_range_rps,
            "accel_range_mps2": i.accel_range_mps2, **dict(i.extra)} for i in identities}),
        "environment_json": json.dumps({}),
        "latitude_deg": station.latitude_deg, "heading_deg": station.heading_deg,
        "run_started_utc": datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "source": "station-run",
    }
    writer = RecordingWriter(path, streams=_stream_specs(station, identities), metadata=meta,
                             truth=opt.truth, overwrite=overwrite,
                             flush_interval_s=opt.flush_interval_s)
    with writer:
        writer.log_event(station.clock.now_s(), "info", "runner",
                         f"plan {plan.name!r} started on {station.describe().get('kind', '?')}")
        run = _Run(plan, station, writer, opt, identities)
        summary = _drive(run, 0)
    _disconnect(station)
    return summary


def _disconnect(station: Station) -> None:
    for dev in (station.table, station.centrifuge, station.chamber, *station.imus):
        if dev is not None:
            try:
                dev.disconnect()
            except Exception as exc:
                _log.warning("disconnecting %s failed: %s", getattr(dev, "name", dev), exc)


@dataclass(frozen=True)
class ResumePoint:
    """Where an interrupted run continues: the plan, its first step not done, the last time."""

    plan: Plan
    first_step: int
    last_time_s: float
    interrupted: tuple[int, ...]


def find_resume_point(path: str | Path) -> ResumePoint:
    """Read a Recording and say where its run continues.

    Raises
    ------
    RecordingError
        If the file has no plan (not a station run).
    """
    with open_recording(path) as rec:
        meta = rec.metadata
        if "plan_toml" not in meta:
            raise RecordingError(f"{path} holds no plan (plan_toml); it is not a station run "
                                 "that can be resumed")
        plan = parse_plan(str(meta["plan_toml"]), f"{path} (plan_toml)")
        done: set[int] = set()
        interrupted = []
        for s in rec.steps:
            idx = s.commanded.get("plan_step") if isinstance(s.commanded, dict) else None
            if s.status == "done" and idx is not None:
                done.add(int(idx))
            if s.status in ("running", "pending"):
                interrupted.append(s.index)
        first = 0
        while first in done:
            first += 1
        last = max((info.t_last_s for info in rec.streams if info.n_samples), default=0.0)
        last = max([last, *(s.t_end_s for s in rec.steps if math.isfinite(s.t_end_s)),
                    *(e.time_s for e in rec.log)])
    return ResumePoint(plan, first, float(last), tuple(interrupted))


def resume_run(path: str | Path, make_station: Callable[[Plan, float], Station], *,
               options: RunOptions | None = None) -> RunSummary:
    """Continue an interrupted run in its own Recording.

    Parameters
    ----------
    path : str or Path
        The Recording of the interrupted run (left open by a killed runner, or closed after a
        stop).
    make_station : callable
        ``make_station(plan, start_time_s)`` returns the station to continue on, its clock
        starting at `start_time_s` (after the last sample in the file).
    options : RunOptions, optional

    Raises
    ------
    RecordingError
        If the file holds no plan, or everything in it is already done.
    """
    opt = options or RunOptions()
    p = Path(path)
    with open_recording(p) as rec:
        was_open = rec.was_open_for_write
    if was_open:
        crashed = p.with_name(f"{p.stem}.crashed.h5")
        report = recover_recording(p, p.with_name(f".{p.stem}.recovering.h5"), overwrite=True)
        p.replace(crashed)
        report.output.replace(p)
    point = find_resume_point(p)
    if point.first_step >= len(point.plan.steps):
        raise RecordingError(f"{p}: every step of plan {point.plan.name!r} is already done")
    station = make_station(point.plan, point.last_time_s + 1.0)
    check_plan_against_station(point.plan, station)
    identities = _connect(station, point.plan)
    with RecordingWriter.reopen(p, flush_interval_s=opt.flush_interval_s) as writer:
        for index in point.interrupted:
            writer.update_step(index, status="aborted",
                               note="interrupted (runner stopped); the run was resumed")
        writer.log_event(station.clock.now_s(), "warning", "runner",
                         f"run resumed at step {point.first_step} "
                         f"({point.plan.step_label(point.first_step)})"
                         + (" after a crash; the crashed file is kept as "
                            f"{p.stem}.crashed.h5" if was_open else ""))
        run = _Run(point.plan, station, writer, opt, identities)
        summary = _drive(run, point.first_step)
    _disconnect(station)
    return summary
