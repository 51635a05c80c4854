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
after its last sample. Completed steps keep their data; nothing is repeated or lost. A station
with a ``remount`` method (the twin) is put back in the pose of the last completed remount
operator check (:attr:`ResumePoint.remount`), since a rebuilt twin starts in the ``+z`` pose;
likewise a station with ``swap_units`` / ``set_centrifuge_load`` gets the completed unit swaps
again, in order (:attr:`ResumePoint.swaps`), and the last completed centrifuge load
(:attr:`ResumePoint.centrifuge_load_kg`).
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Protocol

from imucalib import units
from imucalib.errors import (
    InvalidInputError,
    RecordingError,
    RecordingWriteError,
    StorageFullError,
)
from imucalib.io import StreamSpec
from imucalib.io._layout import column_compression
from imucalib.io.compression import (
    COMPRESSION_NAMES,
    COMPRESSIONS,
    DEFAULT_COMPRESSION,
    compression_from_name,
)
from imucalib.io.context import RecordingContext
from imucalib.io.coverage import uncovered_done_steps
from imucalib.io.events import EventKind
from imucalib.io.opening import open_recording
from imucalib.io.recording import KEEP, RecordingWriter, _Keep
from imucalib.io.recover import compact_recording, recover_recording, stale_partial
from imucalib.io.storage import DEFAULT_RESERVE_BYTES, format_bytes, room_bytes
from imucalib.io.streams import (
    DEVICE_CENTRIFUGE,
    DEVICE_IMU,
    DEVICE_TABLE,
    chamber_stream_spec,
    imu_stream_spec,
    motion_stream_spec,
)
from imucalib.plan.io import parse_plan, plan_hash, plan_to_toml
from imucalib.plan.schema import (
    CentrifugeStep,
    Plan,
    PositionStep,
    RateStep,
    SoakStep,
    operator_check_problems,
)
from imucalib.station.devices import ImuIdentity, Station
from imucalib.station.log_tee import tee_log
from imucalib.station.session import RunOptions, RunSession, RunStatus, StepStop

__all__ = [
    "ResumePoint",
    "RunOptions",
    "RunStatus",
    "RunSummary",
    "TruthSource",
    "check_plan_against_station",
    "check_room_for_run",
    "find_resume_point",
    "resume_run",
    "run_plan",
]

_log = logging.getLogger(__name__)
_DRAIN_S = 1.0  # station time acquired after the last step [s]
#: Root attribute of a run's Recording: the compression its close was asked for (a name of
#: :data:`~imucalib.io.compression.COMPRESSION_NAMES`), which a resume finishes or keeps.
RUN_COMPRESSION_KEY = "run_compression"


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
    storage_note: str = ""  # why the closed file was left uncompressed ("": it was compressed)


def _with_storage_note(summary: RunSummary, writer: RecordingWriter) -> RunSummary:
    """Return the summary with the note of a close that left the file uncompressed."""
    note = writer.compression_skipped
    return dataclasses.replace(summary, storage_note=note) if note else summary


def _stream_specs(station: Station, identities: list[ImuIdentity]) -> list[StreamSpec]:
    specs = [imu_stream_spec(i.name, gyro_lsb_rps=i.gyro_lsb_rps, accel_lsb_mps2=i.accel_lsb_mps2,
                             temperature_lsb_degc=i.temperature_lsb_degc) for i in identities]
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
        A step needing a device the station lacks, table angles for a different axis count,
        or an operator check swapping units the station lacks
        (:func:`~imucalib.plan.schema.operator_check_problems`).
    """
    from imucalib.errors import ConfigurationError

    problems = operator_check_problems(plan.steps, [src.name for src in station.imus],
                                       station.centrifuge is not None)
    if problems:
        raise ConfigurationError(problems[0])

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


def _identities(station: Station) -> list[ImuIdentity]:
    out = []
    for src in station.imus:
        ident = src.identify()
        if ident.name != src.name:
            raise InvalidInputError(f"IMU source {src.name!r} identifies as {ident.name!r}")
        out.append(ident)
    return out


def check_room_for_run(plan: Plan, station: Station, identities: list[ImuIdentity],
                       path: str | Path, min_free_bytes: int) -> None:
    """Refuse, before anything moves, a run whose Recording would not fit where it is written.

    The plan's estimated file size (:func:`imucalib.plan.budget.estimate_plan_recording`, with
    the station's IMUs and devices) plus `min_free_bytes` must fit in the room left
    (:func:`imucalib.io.storage.room_bytes`: free space and the file-size limit).

    Raises
    ------
    StorageFullError
        Naming the estimate, the reserve and the room.
    """
    from imucalib.plan.budget import StationFacts, estimate_plan_recording

    rates = tuple(i.sample_rate_hz if math.isfinite(i.sample_rate_hz) and i.sample_rate_hz > 0
                  else 1000.0 for i in identities)
    facts = StationFacts(imu_sample_rates_hz=rates or (1000.0,),
                         table_axes=len(station.table.axis_names) if station.table else 0,
                         centrifuge=station.centrifuge is not None,
                         chamber=station.chamber is not None)
    need = estimate_plan_recording(plan, facts).total_bytes
    room = room_bytes(path)
    if need + min_free_bytes > room:
        raise StorageFullError(
            f"not enough room for the run: its recording needs about {format_bytes(need)} and "
            f"{format_bytes(min_free_bytes)} must stay free, but {Path(path).parent} has "
            f"{format_bytes(room)} (free space, or what the file-size limit leaves); free some "
            "space or write elsewhere (--out)")


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


class TruthSource(Protocol):
    """What a simulated station offers besides its streams: the truth behind them."""

    def truth_stream_specs(self) -> list[StreamSpec]:
        """Return the layouts of the truth streams."""
        ...

    def drain_truth(self) -> dict[str, dict[str, Any]]:
        """Return, per IMU, the truth columns generated since the previous call."""
        ...


def _write_truth(run: RunSession, truth: TruthSource | None) -> None:
    if truth is not None:
        for name, cols in truth.drain_truth().items():
            run.writer.append_truth(DEVICE_IMU, name, cols)


def _drive(run: RunSession, first: int, truth: TruthSource | None = None) -> RunSummary:
    """Run the steps from `first`, with the safety net; return the outcome."""
    start = run.now()
    status, reason = "done", ""
    tick = run.tick

    def tick_and_notify(until_s: float | None = None, span_s: float | None = None) -> None:
        tick(until_s, span_s)
        _write_truth(run, truth)
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
    except StepStop as stop:
        status, reason = "aborted", str(stop)
        run.safe_state()
        run.writer.log_event(run.now(), "error", "runner", f"run stopped: {reason}")
    except BaseException as exc:
        run.safe_state(chamber_too=True)
        try:
            if not run.writer.closed:  # a writer that gave its file up after a failed write
                run.writer.log_event(run.now(), "error", "runner",
                                     f"run interrupted: {type(exc).__name__}: {exc}"[:4000])
            run.writer.close()
        except RecordingError as rec_exc:  # the file failed too: the original cause goes up
            # (a full disk or a failed write says so itself; the resume mends either)
            quiet = isinstance(rec_exc, StorageFullError | RecordingWriteError)
            log = _log.debug if quiet else _log.warning
            log("closing %s after %s: %s", run.writer.path, type(exc).__name__, rec_exc)
        raise
    return RunSummary(path=run.writer.path, plan=run.plan.name, status=status,
                      steps_done=run.status.steps_done, steps_invalid=run.status.steps_invalid,
                      trips=tuple(run.trips), start_s=start, end_s=run.now(), reason=reason)


def run_plan(plan: Plan, station: Station, path: str | Path, *,
             options: RunOptions | None = None, overwrite: bool = False,
             truth_source: TruthSource | None = None,
             extra_metadata: Mapping[str, str | int | float | bool] | None = None
             ) -> RunSummary:
    """Execute `plan` on `station`, writing a new Recording at `path`.

    `truth_source` (a simulated station) adds its truth streams under ``/truth``, written as
    the streams are acquired; ``options.truth`` is the truth metadata. `extra_metadata` is
    stored with the run's own (a scenario's description, for one).

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
    if opt.idle_tick_s is not None and not opt.idle_tick_s > 0:
        raise InvalidInputError(f"`idle_tick_s` must be > 0; got {opt.idle_tick_s!r}")
    if opt.compression not in COMPRESSIONS:
        raise InvalidInputError(f"`compression` must be one of {COMPRESSIONS}; "
                                f"got {opt.compression!r}")
    check_plan_against_station(plan, station)
    if Path(path).exists() and not overwrite:
        raise RecordingError(f"{path} exists; pass overwrite=True to replace it")
    identities = _connect(station, plan)
    try:
        check_room_for_run(plan, station, identities, path, opt.min_free_bytes)
    except StorageFullError:
        _disconnect(station)
        raise
    # the plan's facts as keys of their own (read by io/context.py; plan_toml is provenance)
    context = RecordingContext.of_plan(plan.model_dump(mode="json"), plan_hash(plan))
    meta: dict[str, str | int | float | bool] = {
        **context.metadata(),
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
        RUN_COMPRESSION_KEY: opt.compression or "none",
        **(extra_metadata or {}),
    }
    try:
        writer = RecordingWriter(path, streams=_stream_specs(station, identities),
                                 metadata=meta, truth=opt.truth, overwrite=overwrite,
                                 truth_streams=(truth_source.truth_stream_specs()
                                                if truth_source is not None else ()),
                                 flush_interval_s=opt.flush_interval_s,
                                 compression=opt.compression)
    except BaseException:
        _disconnect(station)  # nothing has moved
        raise
    with writer:
        tee_log(writer, opt.on_log)
        writer.log_event(station.clock.now_s(), "info", "runner",
                         f"plan {plan.name!r} started on {station.describe().get('kind', '?')}")
        run = RunSession(plan, station, writer, opt, identities)
        summary = _drive(run, 0, truth_source)
        _close_or_stop(run)
    _disconnect(station)
    return _with_storage_note(summary, writer)


def _close_or_stop(run: RunSession) -> None:
    """Close the run's Recording; if that fails, stop the equipment safely before raising.

    The close writes the last rows, closes the file and compresses it: a write that fails there
    (:class:`~imucalib.errors.RecordingWriteError`, or a :class:`StorageFullError`) ends the run
    as a full disk does, with the equipment stopped and disconnected.
    """
    try:
        run.writer.close()
    except BaseException:
        run.safe_state(chamber_too=True)
        _disconnect(run.station)
        raise


def _disconnect(station: Station) -> None:
    for dev in (station.table, station.centrifuge, station.chamber, *station.imus):
        if dev is not None:
            try:
                dev.disconnect()
            except Exception as exc:
                _log.warning("disconnecting %s failed: %s", getattr(dev, "name", dev), exc)


@dataclass(frozen=True)
class ResumePoint:
    """Where an interrupted run continues.

    Attributes
    ----------
    plan : Plan
        The run's plan (from the Recording).
    first_step : int
        The first plan step not done; ``len(plan.steps)`` when every step is done.
    last_time_s : float
        The latest time in the file. [s]
    interrupted : tuple of int
        Step rows left ``running`` or ``pending`` by the interruption.
    uncovered : mapping of int to str
        Step rows marked ``done`` whose committed samples do not cover their valid window
        (a writer killed before its samples reached the file), with the reason; they are run
        again.
    remount : tuple of (str, float, int), optional
        The pose of the last completed remount operator check, as (axis up, yaw [°], plan
        step), in the order the steps ran; None when no remount step was completed. A resumed
        twin is put back in this pose.
    swaps : tuple of (str, str)
        The unit pairs of every completed swap operator check (``swap_units``), in the order
        the steps ran; a resumed twin swaps them again, in that order.
    centrifuge_load_kg : float, optional
        The load of the last completed operator check with ``centrifuge_load_kg``; None when
        there was none. A resumed twin's centrifuge is given it. [kg]
    """

    plan: Plan
    first_step: int
    last_time_s: float
    interrupted: tuple[int, ...]
    uncovered: Mapping[int, str] = field(default_factory=dict)
    remount: tuple[str, float, int] | None = None
    swaps: tuple[tuple[str, str], ...] = ()
    centrifuge_load_kg: float | None = None


def find_resume_point(path: str | Path) -> ResumePoint:
    """Read a Recording and say where its run continues.

    A plan step counts as done when one of its rows is ``done`` and that row's committed
    samples cover its valid window (:func:`imucalib.io.coverage.uncovered_done_steps`).

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
        uncovered = uncovered_done_steps(rec)
        done: set[int] = set()
        interrupted = []
        remount: tuple[str, float, int] | None = None
        swaps: list[tuple[str, str]] = []
        load_kg: float | None = None
        for s in rec.steps:
            idx = s.commanded.get("plan_step") if isinstance(s.commanded, dict) else None
            if s.status == "done" and idx is not None and s.index not in uncovered:
                done.add(int(idx))
                if s.kind != "operator-check":
                    continue
                up = s.commanded.get("remount")
                if isinstance(up, str):
                    remount = (up, float(s.commanded.get("remount_yaw_deg") or 0.0), int(idx))
                pair = s.commanded.get("swap_units")
                if isinstance(pair, list | tuple) and len(pair) == 2:
                    swaps.append((str(pair[0]), str(pair[1])))
                load = s.commanded.get("centrifuge_load_kg")
                if load is not None:
                    load_kg = float(load)
            if s.status in ("running", "pending"):
                interrupted.append(s.index)
        first = 0
        while first in done:
            first += 1
        last = max((info.t_last_s for info in rec.streams if info.n_samples), default=0.0)
        last = max([last, *(s.t_end_s for s in rec.steps if math.isfinite(s.t_end_s)),
                    *(e.time_s for e in rec.log)])
    return ResumePoint(plan, first, float(last), tuple(interrupted), uncovered, remount,
                       tuple(swaps), load_kg)


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
        # uncompressed: the writer appends to it uncompressed, and compresses it at its close
        report = recover_recording(p, p.with_name(f".{p.stem}.recovering.h5"), overwrite=True,
                                   compression=None)
        p.replace(crashed)
        report.output.replace(p)
    point = find_resume_point(p)
    compression = _run_compression(p)
    if was_open and isinstance(compression, _Keep):  # a file from before RUN_COMPRESSION_KEY
        compression = DEFAULT_COMPRESSION
    if point.first_step >= len(point.plan.steps):
        if not was_open:
            if _finish_compression(p, compression):
                return _finished_summary(p, point, "every step was already done; the "
                                                   "interrupted compression was finished")
            raise RecordingError(f"{p}: every step of plan {point.plan.name!r} is already done "
                                 "and the file is closed; there is nothing to resume")
        # the runner died while closing (after its last step): recovery finished the close
        with RecordingWriter.reopen(p, flush_interval_s=opt.flush_interval_s,
                                    compression=compression) as writer:
            tee_log(writer, opt.on_log)
            writer.log_event(point.last_time_s, "warning", "runner",
                             "the run had done every step but its file was not closed; closed "
                             f"by resume (the file as found is kept as {p.stem}.crashed.h5)")
        return _finished_summary(p, point)
    station = make_station(point.plan, point.last_time_s + 1.0)
    check_plan_against_station(point.plan, station)
    identities = _connect(station, point.plan)
    rest = point.plan.model_copy(update={"steps": point.plan.steps[point.first_step:]})
    try:
        check_room_for_run(rest, station, identities, p, opt.min_free_bytes)
    except StorageFullError:
        _disconnect(station)
        raise
    with RecordingWriter.reopen(p, flush_interval_s=opt.flush_interval_s,
                                compression=compression) as writer:
        tee_log(writer, opt.on_log)
        for index in point.interrupted:
            writer.update_step(index, status="aborted",
                               note="interrupted (runner stopped); the run was resumed")
        for index, reason in point.uncovered.items():
            writer.update_step(index, status="invalid",
                               note=f"samples lost when the runner stopped: {reason}"[:2000])
            writer.log_event(station.clock.now_s(), "warning", "runner",
                             f"step row {index} was marked done but {reason}; it is run again")
        writer.log_event(station.clock.now_s(), "warning", "runner",
                         f"run resumed at step {point.first_step} "
                         f"({point.plan.step_label(point.first_step)})"
                         + (" after a crash; the crashed file is kept as "
                            f"{p.stem}.crashed.h5" if was_open else ""))
        restore = getattr(station, "remount", None)
        if point.remount is not None and callable(restore):
            up, yaw, k = point.remount
            restore(up, yaw)  # the rebuilt twin starts in the +z pose; the fixture was not moved
            writer.log_station_event(station.clock.now_s(), EventKind.REMOUNT,
                                     f"{up} up, yaw {yaw:g}° (the pose of completed step {k}, "
                                     "restored on resume)")
        _restore_swaps_and_load(station, writer, point)
        run = RunSession(point.plan, station, writer, opt, identities)
        summary = _drive(run, point.first_step)
        _close_or_stop(run)
    _disconnect(station)
    return _with_storage_note(summary, writer)


def _restore_swaps_and_load(station: Station, writer: RecordingWriter,
                            point: ResumePoint) -> None:
    """Re-apply a resumed run's completed unit swaps and its last centrifuge load on a twin.

    The rebuilt twin starts with every unit in its first place and the configured load; a
    station without ``swap_units`` / ``set_centrifuge_load`` (a real one) kept them as they
    were.
    """
    swap = getattr(station, "swap_units", None)
    if point.swaps and callable(swap):
        for first, second in point.swaps:
            swap(first, second)
        writer.log_station_event(station.clock.now_s(), EventKind.SWAP,
                                 ", ".join(f"{a} ↔ {b}" for a, b in point.swaps)
                                 + " (the completed swaps, restored on resume)")
    load = getattr(station, "set_centrifuge_load", None)
    if point.centrifuge_load_kg is not None and callable(load):
        load(point.centrifuge_load_kg)
        writer.log_station_event(station.clock.now_s(), EventKind.LOAD,
                                 f"{point.centrifuge_load_kg:g} kg (the last completed load, "
                                 "restored on resume)")


def _run_compression(path: Path) -> str | _Keep | None:
    """Return the compression the run asked for its closed Recording (:data:`KEEP`: unknown).

    Read from the root attribute :data:`RUN_COMPRESSION_KEY` (``"none"``: None), which files
    written before it lack.
    """
    with open_recording(path) as rec:
        name = rec.metadata.get(RUN_COMPRESSION_KEY)
    if not isinstance(name, str) or name not in COMPRESSION_NAMES:
        return KEEP
    return compression_from_name(name)


def _finish_compression(path: Path, compression: str | _Keep | None) -> bool:
    """Compress a complete, closed Recording whose compression was interrupted.

    A runner killed (or failing to write) while it compressed the file at its close leaves the
    file complete, closed and uncompressed, and perhaps the partial copy
    (:func:`~imucalib.io.recover.stale_partial`). Returns whether there was such a compression
    to finish; the partial copy is removed in any case.

    Raises
    ------
    StorageFullError
        If the copy would not leave the writer's reserve free.
    RecordingWriteError
        If HDF5 fails to write the copy (the file is left as it was).
    """
    partial = stale_partial(path)
    stale = partial.exists()
    if isinstance(compression, _Keep):  # a file from before RUN_COMPRESSION_KEY
        compression = DEFAULT_COMPRESSION if stale else None
    with open_recording(path, strict=True) as rec:
        had = column_compression(rec._file)[1]
    if compression is None or had == compression:
        partial.unlink(missing_ok=True)
        return False
    size = path.stat().st_size
    room = room_bytes(path)
    if room - size < DEFAULT_RESERVE_BYTES:
        raise StorageFullError(
            f"{path} is complete but uncompressed, and compressing it needs up to "
            f"{format_bytes(size)} with {format_bytes(DEFAULT_RESERVE_BYTES)} left free: "
            f"{format_bytes(room)} is left; free some space, then run `imucalib run --resume "
            f"{path}` again (or leave it uncompressed)")
    compact_recording(path, compression)  # writes, then replaces, the partial copy's name
    partial.unlink(missing_ok=True)
    return True


def _finished_summary(path: Path, point: ResumePoint,
                      reason: str = "every step was already done; the interrupted close was "
                                    "finished") -> RunSummary:
    """Return the summary of a run that a resume found complete (every step done)."""
    with open_recording(path) as rec:
        steps = rec.steps
    done = sum(1 for s in steps if s.status == "done")
    invalid = sum(1 for s in steps if s.status == "invalid")
    return RunSummary(path=path, plan=point.plan.name, status="done", steps_done=done,
                      steps_invalid=invalid, trips=(), start_s=point.last_time_s,
                      end_s=point.last_time_s, reason=reason)
