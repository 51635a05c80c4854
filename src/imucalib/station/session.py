"""One session of a run: acquisition, guards, settling, recording and the step loop.

:class:`RunSession` is what :func:`~imucalib.station.runner.run_plan` and
:func:`~imucalib.station.runner.resume_run` drive: every tick it polls the station's devices,
writes their rows to the Recording and checks the guards. :meth:`RunSession.execute` runs one
plan step through the executor of its kind (:mod:`imucalib.station.executors`, one module per
kind), which builds on the session's ``settle``, ``record_for`` and ``record_revolutions``;
:meth:`RunSession.run_steps` retries a step after a trip (see :mod:`imucalib.station.runner` for
the rules). :class:`RunOptions` and :class:`RunStatus` are the options of a run and the status a
live view shows; :class:`StepTrip` and :class:`StepStop` (:mod:`imucalib.station.signals`) the
signals a step raises.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from imucalib import units
from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS
from imucalib.errors import DeviceError, RecordingError, RecordingWriteError, StorageFullError
from imucalib.io.compression import DEFAULT_COMPRESSION
from imucalib.io.events import EventKind
from imucalib.io.recording import RecordingWriter
from imucalib.io.storage import format_bytes
from imucalib.io.streams import (
    DEVICE_CENTRIFUGE,
    DEVICE_CHAMBER,
    DEVICE_IMU,
    DEVICE_TABLE,
    axis_columns,
)
from imucalib.plan.schema import Plan
from imucalib.station.devices import ImuIdentity, Station
from imucalib.station.executors import EXECUTORS
from imucalib.station.guards import (
    RollingWindow,
    accel_fluctuation_g,
    check_chamber_band,
    check_counter,
    check_jumps,
    check_overspeed,
    check_saturation,
)
from imucalib.station.operator import AutoOperator, Operator
from imucalib.station.signals import StepStop, StepTrip

__all__ = ["RunOptions", "RunSession", "RunStatus", "StepStop", "StepTrip"]

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
    min_free_bytes : int
        Room (free disk space, or what the file-size limit leaves) below which the run stops
        safely and closes its Recording, checked every tick; also added to the estimated file
        size in the check before a run starts. [bytes]
    idle_tick_s : float, optional
        Longer ticks while no decision waits on the data: the dwell (``settle_s``) before the
        settling criteria are checked, and a record of a fixed length (whose rows the guards
        still check, every one); by default `tick_s`. The simulated station generates its
        streams per tick, so fewer, longer ticks make it faster. [s]
    on_log : callable, optional
        Called with ``(time_s, level, source, message)`` of every line the run writes to the
        Recording's event log, once written (:mod:`imucalib.station.log_tee`; the web page's
        live log).
    compression : str or None
        Compression of a new run's Recording once closed
        (:data:`~imucalib.io.compression.COMPRESSIONS`; default
        :data:`~imucalib.io.compression.DEFAULT_COMPRESSION`, gzip, which every HDF5 tool
        reads). A resumed run closes its file with the compression it had.
    """

    tick_s: float = 0.5
    operator: Operator = field(default_factory=AutoOperator)
    on_status: Callable[[RunStatus], None] | None = None
    flush_interval_s: float = 1.0
    truth: dict[str, Any] | None = None
    station_toml: str = ""
    min_free_bytes: int = 128 << 20
    idle_tick_s: float | None = None
    compression: str | None = DEFAULT_COMPRESSION
    on_log: Callable[[float, str, str, str], None] | None = None


class RunSession:
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
        self.tick_from_s = station.clock.now_s()  # station time the last tick started at

    # --- acquisition ------------------------------------------------------------------------
    def now(self) -> float:
        """Return the station time. [s]"""
        return self.station.clock.now_s()

    def tick(self, until_s: float | None = None, span_s: float | None = None) -> None:
        """Let time pass (one tick, or `span_s`, not beyond `until_s`), acquire, check guards."""
        step = self.opt.tick_s if span_s is None else span_s
        dt = step if until_s is None else min(step, until_s - self.now())
        self.tick_from_s = self.now()
        if dt > 0:
            self.station.clock.sleep(dt)
        self.acquire()
        self.guard_storage()

    def guard_storage(self) -> None:
        """Stop the run while the Recording can still close cleanly when room runs short.

        Raises
        ------
        StorageFullError
            When less than ``min_free_bytes`` is left for the Recording.
        """
        room = self.writer.room_bytes
        if room < self.opt.min_free_bytes:
            raise StorageFullError(
                f"disk nearly full: {format_bytes(room)} left for {self.writer.path} (the run "
                f"stops below {format_bytes(self.opt.min_free_bytes)}); the equipment was "
                "stopped safely and the file closed; free some space, then continue with "
                f"`imucalib run --resume {self.writer.path}`")

    def acquire(self) -> None:
        """Poll every device, write its rows, and trip on device faults and alarms."""
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
                    if dev is st.centrifuge:
                        over = check_overspeed(
                            fb.rate_rps, self.plan.limits.max_centrifuge_rate_dps * units.DEG,
                            dev.name)
                        if over is not None:
                            raise StepTrip(over)
                status = dev.status()
                if status.fault is not None:
                    raise StepTrip(f"{kind} {dev.name} fault: {status.fault}")
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
                    raise StepTrip(f"chamber {st.chamber.name} alarm: {alarm}")
            for src in st.imus:
                self._acquire_imu(src)
        except DeviceError as exc:
            raise StepTrip(f"device error: {exc}") from exc

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
            # copies: a one-row view would keep the tick's whole block alive for the window's
            # hour (about 50 MiB an hour at 1 kHz)
            t_last = block.time_s[-1:].copy()
            self.temps[name].push(t_last, block.temperature_degc[-1:, None].copy())
            self.gyro_means[name].push(t_last,
                                       np.r_[block.gyro_rps.mean(axis=0),
                                             block.accel_mps2.mean(axis=0)][None, :])
            self.last_sample_s[name] = float(block.time_s[-1])
            self.status.imu_temperature_degc[name] = float(block.temperature_degc[-1])
            self.status.imu_rate_hz[name] = len(block) / max(now - self.tick_from_s, 1e-9)
        elif now - self.last_sample_s[name] > self.g.device_timeout_s:
            raise StepTrip(f"IMU {name}: no data for {now - self.last_sample_s[name]:.3g} s "
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
                raise StepTrip(reason)
        elif self.recording and (crc or missing):
            reason = check_counter(name, missing, crc, self.g.max_counter_gap_samples,
                                   self.g.max_crc_errors)
            if reason:
                raise StepTrip(reason)
        self.health0[name] = health

    # --- criteria ---------------------------------------------------------------------------
    def motion_rows(self, fuge: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return recent (time, angles, rates) of the table (or centrifuge) feedback."""
        t, v = (self.fuge_fb if fuge else self.fb).rows()
        k = v.shape[1] // 2 if v.size else 0
        return t, v[:, :k], v[:, k:]

    def accel_settled(self) -> str | None:
        """Return why the accelerometer output is not settled yet, or None."""
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
        """Trip when, after a soak, the chamber air leaves its band while recording."""
        if self.recording and self.chamber_setpoint is not None:
            _, rows = self.chamber_rows.rows(self._last_tick_start())
            if rows.size:
                reason = check_chamber_band(rows[:, 0], self.chamber_setpoint,
                                            self.g.chamber_band_degc)
                if reason:
                    raise StepTrip(reason)

    def await_samples(self, until_s: float) -> None:
        """Acquire until every IMU has delivered its samples up to `until_s`.

        IMU samples reach the station after the instant they describe (transport latency, the
        device's own buffering), so when a valid window ends some of its samples are still in
        transit. A step is marked ``done`` only once they are in the Recording; the data-quality
        guards apply to them as to the rest of the window.

        Raises
        ------
        StepTrip
            When an IMU's samples up to `until_s` have not arrived within the device time-out.
        """
        deadline = self.now() + self.g.device_timeout_s
        self.recording = True
        try:
            while True:
                late = [name for name, ident in self.ids.items()
                        if self.last_sample_s[name] < until_s - _period_s(ident)]
                if not late:
                    return
                if self.now() >= deadline:
                    name = late[0]
                    raise StepTrip(
                        f"IMU {name}: samples up to the end of the valid window ({until_s:.3f} s) "
                        f"did not arrive within {self.g.device_timeout_s:g} s; the last one is "
                        f"from {self.last_sample_s[name]:.3f} s")
                self.tick()
        finally:
            self.recording = False

    # --- what the step executors build on ---------------------------------------------------
    def settle(self, t_cmd: float, settle_s: float, criterion: Callable[[], str | None],
               correct: Callable[[str], bool] | None = None) -> None:
        """Tick until `settle_s` has passed and `criterion` holds; trip after the time-out.

        `correct` (the "automatic correction" of docs/p1.md, calibration steps 1 and 3) is offered
        each failing reason once per `settle_check_s` after the dwell; it re-commands the
        equipment when the reason is one it can correct, and says whether it did.
        """
        deadline = t_cmd + self.g.settle_timeout_s + settle_s
        last_fix = -math.inf
        idle = self.opt.idle_tick_s
        while True:
            if idle is not None and self.now() - t_cmd < settle_s - idle:
                self.tick(span_s=idle)  # the dwell: nothing is decided yet
            else:
                self.tick()
            if self.now() - t_cmd >= settle_s:
                reason = criterion()
                if reason is None:
                    return
                if self.now() >= deadline:
                    raise StepTrip(
                        f"never settled within {self.g.settle_timeout_s:g} s: {reason}")
                if correct is not None and self.now() - last_fix >= 2 * self.g.settle_check_s \
                        and correct(reason):
                    last_fix = self.now()
                    self.writer.log_event(self.now(), "info", "runner",
                                          f"automatic correction: {reason}; re-commanded")

    def record_for(self, duration_s: float, guard: Callable[[], None]) -> tuple[float, float]:
        """Record a valid window of `duration_s` with `guard` checked every tick.

        With ``idle_tick_s`` longer than ``tick_s`` the ticks are longer and the motion
        feedback kept is widened meanwhile, so that the guard still sees every row.
        """
        start = self.now()
        longer = self.opt.idle_tick_s
        widened = [(w, w.span_s) for w in (self.fb, self.fuge_fb)
                   if longer is not None and longer > self.opt.tick_s]
        for w, span in widened:
            w.span_s = span + (longer or 0.0)
        self.recording = True
        try:
            while self.now() < start + duration_s - 1e-9:
                self.tick(start + duration_s, longer)
                guard()
                self.guard_chamber()
        finally:
            self.recording = False
            for w, span in widened:
                w.span_s = span
        return start, start + duration_s

    def record_revolutions(self, fuge: bool, axis: int, revolutions: int,
                           guard: Callable[[], None]) -> tuple[float, float]:
        """Record whole revolutions of a spinning axis; return the valid window."""
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

    def latest_motion(self, fuge: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Return the measured angles and rates of the table (or centrifuge) in the last tick."""
        t, angle, rate = self.motion_rows(fuge)
        recent = t > self._last_tick_start() - 1e-9
        return angle[recent], rate[recent]

    def _last_tick_start(self) -> float:
        """Station time from which rows belong to the last tick (at least `tick_s` back)."""
        return min(self.tick_from_s, self.now() - self.opt.tick_s)

    def log_station_event(self, kind: EventKind | str, detail: str) -> None:
        """Log a station event (a remount, a unit swap, a load) and show it as the last event.

        Written by :meth:`~imucalib.io.recording.RecordingWriter.log_station_event` (source
        ``"event:<kind>"``, :mod:`imucalib.io.events`; ``docs/recording-format.md``, "Station
        events").

        Parameters
        ----------
        kind : EventKind or str
            ``"remount"``, ``"swap"`` or ``"load"``.
        detail : str
            What was done, for people (``"+x up, yaw 90°"``).
        """
        self.status.last_event = self.writer.log_station_event(self.now(), kind, detail)

    # --- the step loop ----------------------------------------------------------------------
    def execute(self, index: int, attempt: int) -> str:
        """Run plan step `index` once; return "done" (raises StepTrip, StepStop)."""
        step = self.plan.steps[index]
        label = self.plan.step_label(index)
        commanded = {**step.model_dump(mode="json"), "plan_step": index, "attempt": attempt}
        row = self.writer.begin_step(step.kind, label, self.now(), commanded=commanded,
                                     role=step.role, tags=step.tags, units=tuple(self.ids))
        self.status.step_index, self.status.step_label, self.status.attempt = index, label, attempt
        self.writer.log_event(self.now(), "info", "runner",
                              f"step {index} ({label}) started, attempt {attempt + 1}")
        try:
            outcome = EXECUTORS[step.kind](self, step, attempt, row)
            window, note = outcome.window, outcome.note
            if window is not None:
                self.await_samples(window[1])
            fields: dict[str, Any] = {"t_end_s": self.now(), "status": "done"}
            if window is not None:
                fields.update(valid_start_s=window[0], valid_end_s=window[1])
            if note:
                fields["note"] = note
            self.writer.update_step(row, **fields)
            # durable now: the flush commits the samples before the step's row (RecordingWriter)
            self.writer.flush()
            self.status.steps_done += 1
            return "done"
        except StepTrip as trip:
            self.recording = False
            self.writer.update_step(row, t_end_s=self.now(), status="invalid", note=str(trip))
            raise
        except BaseException as exc:
            self.recording = False
            if not isinstance(exc, StepStop) and not self.writer.closed:
                try:
                    self.writer.update_step(
                        row, t_end_s=self.now(), status="aborted",
                        note=f"interrupted: {type(exc).__name__}: {exc}"[:2000])
                except RecordingError as rec_exc:  # the file itself failed: keep the cause
                    quiet = isinstance(rec_exc, StorageFullError | RecordingWriteError)
                    (_log.debug if quiet else _log.error)("cannot mark step %d aborted: %s",
                                                          index, rec_exc)
            raise

    def safe_state(self, *, chamber_too: bool = False) -> None:
        """Stop the motion (and the chamber when asked); never raises."""
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
        """Reconnect the motion devices (resetting their interlocks)."""
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
            except (StepTrip, DeviceError) as exc:
                if self.now() >= deadline:
                    raise StepStop(f"step {index}: cannot resume after the trip: still "
                                     f"failing after {self.g.recover_timeout_s:g} s: {exc}"
                                     ) from exc
                self.safe_state()
                self.station.clock.sleep(self.opt.tick_s)

    def run_steps(self, first: int) -> None:
        """Execute the plan from step `first`, with retries after trips."""
        n = len(self.plan.steps)
        for index in range(first, n):
            self.status.remaining_min_s = _remaining_s(self.plan, index)
            attempt = 0
            while True:
                try:
                    self.execute(index, attempt)
                    break
                except StepTrip as trip:
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
                        raise StepStop(f"step {index} tripped: {reason}") from trip
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


def _period_s(ident: ImuIdentity) -> float:
    """One nominal sample period of an IMU (a 10 ms default when its rate is unknown). [s]"""
    rate = ident.sample_rate_hz
    return 1.0 / rate if math.isfinite(rate) and rate > 0 else 0.01


def _remaining_s(plan: Plan, first: int) -> float:
    from imucalib.plan.schema import step_min_duration_s

    return float(sum(step_min_duration_s(s) for s in plan.steps[first:]))

