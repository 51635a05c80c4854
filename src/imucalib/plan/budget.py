"""Disk budget: how many bytes the recording of a plan or a scenario will take, before it runs.

Contents
--------
:class:`StationFacts`
    What a station records besides the plan: its IMUs' output rates, the table's axes and
    feedback rate, a centrifuge, a chamber and its rate; :meth:`StationFacts.of_twin` for a
    twin station.
:func:`estimate_recording_bytes`
    A plan and station facts → bytes (an ``int``), for a station run to compare with its free
    disk space (the peak: the file as written, then its compressed copy at close).
:func:`estimate_plan_recording`, :func:`estimate_recording`
    The same, itemised per stream (:class:`RecordingEstimate`, :class:`StreamEstimate`), with
    the size of the closed, compressed file (:attr:`RecordingEstimate.closed_bytes`).
:func:`check_free_space`
    Refuse (:class:`~imucalib.errors.LimitExceededError`) an estimate larger than the free space
    of the filesystem that will hold the file.
:func:`format_bytes`
    ``1408433271`` → ``"1.41 GB"`` (decimal units, as disk sizes are quoted).

Model
-----
Acquisition is continuous: every stream is written from the first step to the last, through
warm-ups, soaks, settles and operator checks, so the size follows the run's duration
(:func:`plan_run_duration_s`), step by step:

- static and warm-up: their duration (a warm-up at least one drift window, ``window_s``: the
  runner compares the means of two windows);
- position, rate, centrifuge: the settle phase, ``settle_s`` counted from the command but at
  least :data:`MIN_SETTLE_PHASE_S` (the move and the settling check), then the record
  (``record_s`` or whole revolutions at the commanded rate), plus :data:`MOVE_ALLOWANCE_S`
  (acquisition ticks, the end of a revolution);
- soak: the chamber's ramp to the new setpoint, then the IMU's first-order approach to it
  until its temperature span over ``stable_for_s`` is within ``imu_band_degc`` — for a step ΔT
  and a thermal time constant τ that is t = τ·ln(ΔT·(1 − e^(−W/τ)) / band) — then
  ``stable_for_s`` W; never beyond ``timeout_s``;
- operator checks: nothing.

A scenario (``imucalib simulate``) is a plan run on the twin station and is estimated as one
(:func:`imucalib.station.simulate.estimate_scenario_recording`). A guard trip's retry of a step
is not foreseen.

Each stream holds ``⌊rate · duration⌋ + 1`` rows of the canonical layout
(:mod:`imucalib.io.streams`: an IMU row is 81 bytes with float64 samples, a two-axis table row 40,
a chamber row 24); every column is stored in chunks of 65 536 rows, allocated whole, so the last
chunk counts in full. The steps table and the event log are chunked tables too (one row per
step, about three events per step), and :data:`METADATA_BYTES` covers the HDF5 metadata, the plan
and the truth.

What it bounds: the room a run needs (:attr:`RecordingEstimate.total_bytes`, the figure the
free-space checks use). A Recording is written uncompressed and compressed when it is closed
(docs/recording-format.md, "Size and compression"), so the disk holds at the most the file as
written plus its compressed copy. An IMU that gives counts is written as int32 counts (61 bytes a
row instead of 81), which the estimate does not assume: against the twin's files the estimate is
1.4–1.7 times the file as written and covers the peak (written file plus compressed copy,
0.7–0.9 of the estimate). With float64 samples (an IMU without counts) the estimate is 1.0–1.2
of the file as written, and the peak can exceed it (1.3 times it for a navigation-grade twin
IMU); a close that then finds too little room for the copy leaves the file uncompressed and
complete.

The closed file (:attr:`RecordingEstimate.closed_bytes`): the stream columns compressed with the
default compression (gzip level 1 after a byte shuffle, :mod:`imucalib.io.compression`) take the
bytes per row measured on the twin's output (:data:`CLOSED_IMU_ROW_BYTES`,
:data:`CLOSED_MOTION_AXIS_BYTES`, :data:`CLOSED_TIME_BYTES`; compressed chunks are stored at
their compressed size, not whole), the steps, log and metadata as above (they are not
compressed), other streams (chamber, the twin's truth) as written. Against the twin's files it
is 1.1–1.2 times the closed file for a tactical IMU (the P1 run of ``make demo``, a 200 s static
scenario at 1 kHz), 1.9 times for a consumer one (whose counts compress better); an IMU without
counts (float64 samples, such as a navigation-grade twin IMU) makes the closed file about 2.5
times this estimate.
"""

from __future__ import annotations

import math
import os
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Final

import numpy as np

from imucalib.errors import ConfigurationError, LimitExceededError
from imucalib.io.compression import DEFAULT_COMPRESSION
from imucalib.io.recording import (
    DEFAULT_CHUNK_ROWS,
    LOG_CHUNK_ROWS,
    LOG_FIELDS,
    STEP_FIELDS,
    STEPS_CHUNK_ROWS,
    FieldSpec,
    StreamSpec,
)
from imucalib.io.streams import (
    DEVICE_CENTRIFUGE,
    DEVICE_TABLE,
    chamber_stream_spec,
    imu_stream_spec,
    imu_truth_stream_spec,
    motion_stream_spec,
)
from imucalib.plan.schema import (
    CentrifugeStep,
    Plan,
    PositionStep,
    RateStep,
    SoakStep,
    WarmUpStep,
    step_min_duration_s,
)

if TYPE_CHECKING:
    from imucalib.plan.equipment import TwinEquipment

__all__ = [
    "CLOSED_IMU_ROW_BYTES",
    "CLOSED_MOTION_AXIS_BYTES",
    "CLOSED_TIME_BYTES",
    "METADATA_BYTES",
    "MIN_SETTLE_PHASE_S",
    "MOVE_ALLOWANCE_S",
    "RecordingEstimate",
    "StationFacts",
    "StreamEstimate",
    "check_free_space",
    "estimate_plan_recording",
    "estimate_recording",
    "estimate_recording_bytes",
    "format_bytes",
    "plan_facts",
    "plan_run_duration_s",
    "plan_step_starts_s",
]

#: Time allowed per position, rate or centrifuge step for ticks and the move's end. [s]
MOVE_ALLOWANCE_S: Final = 1.0
#: Least settle phase of a plan's motion step: a move and the settling check take about this
#: long on the twin's tables however short ``settle_s`` is (8–10 s for 180° at 2 s). [s]
MIN_SETTLE_PHASE_S: Final = 10.0
#: Allowance for the HDF5 object headers, chunk indexes, metadata, plan text and truth. [B]
METADATA_BYTES: Final = 512 * 1024
#: Bytes of one IMU row in a closed file (default compression: gzip level 1 after a byte
#: shuffle): six int32 counts at 1.4–1.8 B each, time stamps, device times and counter 0.05–0.17 B
#: each, temperature and saturation flag a few hundredths. Measured on the twin's tactical IMU
#: at 1 kHz (10.4 B in the P1 run of ``make demo``, ``out/p1-run.h5``, and in a 200 s static
#: scenario; a consumer IMU's counts 4.9 B), with ``bench/bench_recording.py --codecs``'s
#: conversion and ``h5py.Dataset.id.get_storage_size`` per column. [B]
CLOSED_IMU_ROW_BYTES: Final = 11.0
#: Bytes per axis of a table's or centrifuge's row in a closed file: the float64 angle
#: (2.4–3.9 B) and rate (0.1–0.6 B), measured as :data:`CLOSED_IMU_ROW_BYTES`. [B]
CLOSED_MOTION_AXIS_BYTES: Final = 4.0
#: Bytes of a motion stream's ``time_s`` per row in a closed file (0.08–0.31 B measured). [B]
CLOSED_TIME_BYTES: Final = 0.3
#: Event-log rows per step (start, end, a note) plus a few per run.
_EVENTS_PER_STEP: Final = 3
_EVENTS_PER_RUN: Final = 10


@dataclass(frozen=True)
class StationFacts:
    """What a station records, besides what the plan says.

    Attributes
    ----------
    imu_sample_rates_hz : tuple of float
        Output data rate of each IMU recorded. [Hz]
    table_axes : int
        Axes of the rate table (0: none).
    centrifuge : bool
        Whether a centrifuge (one axis) is recorded.
    feedback_rate_hz : float
        Rate of the table's and the centrifuge's feedback rows. [Hz]
    chamber : bool
        Whether a thermal chamber is recorded.
    chamber_rate_hz : float
        Rate of the chamber's rows. [Hz]
    imu_truth : bool
        Whether the twin's per-sample truth streams are written too (scenarios only).
    initial_temperature_degc : float
        Chamber temperature before the first soak. [°C]
    chamber_ramp_degc_per_min : float
        The chamber's fastest setpoint ramp. [°C/min]
    imu_thermal_time_constant_s : float
        Longest thermal time constant of the IMUs (their approach to the chamber air). [s]
    """

    imu_sample_rates_hz: tuple[float, ...]
    table_axes: int = 0
    centrifuge: bool = False
    feedback_rate_hz: float = 100.0
    chamber: bool = False
    chamber_rate_hz: float = 1.0
    imu_truth: bool = False
    initial_temperature_degc: float = 20.0
    chamber_ramp_degc_per_min: float = 5.0
    imu_thermal_time_constant_s: float = 600.0

    def __post_init__(self) -> None:
        rates = (*self.imu_sample_rates_hz, self.feedback_rate_hz, self.chamber_rate_hz,
                 self.chamber_ramp_degc_per_min, self.imu_thermal_time_constant_s)
        if not all(math.isfinite(r) and r > 0 for r in rates):
            raise ConfigurationError(
                f"station rates and time constants must be finite and > 0; got IMUs "
                f"{list(self.imu_sample_rates_hz)} Hz, feedback {self.feedback_rate_hz} Hz, "
                f"chamber {self.chamber_rate_hz} Hz and {self.chamber_ramp_degc_per_min} °C/min, "
                f"IMU thermal time constant {self.imu_thermal_time_constant_s} s")
        if self.table_axes < 0:
            raise ConfigurationError(f"`table_axes` must be ≥ 0; got {self.table_axes}")

    @classmethod
    def of_twin(cls, twin: TwinEquipment) -> StationFacts:
        """Return the facts of a twin station (a plan's ``[twin]`` or a scenario)."""
        from imucalib.models.imu import GRADES

        rates = tuple(imu.sample_rate_hz if imu.sample_rate_hz is not None
                      else GRADES[imu.grade].sample_rate_hz for imu in twin.imus)
        axes = {"none": 0, "single-axis": 1, "dual-axis": 2}[twin.table.kind]
        truth = bool(getattr(twin, "store_truth_streams", False))
        return cls(imu_sample_rates_hz=rates, table_axes=axes,
                   centrifuge=twin.centrifuge.enabled,
                   feedback_rate_hz=twin.table.feedback_rate_hz, chamber=twin.chamber.enabled,
                   imu_truth=truth,
                   initial_temperature_degc=twin.chamber.initial_temperature_degc,
                   chamber_ramp_degc_per_min=twin.chamber.max_ramp_degc_per_min,
                   imu_thermal_time_constant_s=max(i.thermal_time_constant_s
                                                   for i in twin.imus))


@dataclass(frozen=True)
class StreamEstimate:
    """One stream's share of the estimate."""

    name: str
    rate_hz: float
    rows: int
    row_bytes: int
    bytes: int  # as written: whole chunks of uncompressed rows
    closed_bytes: int  # in the closed file, compressed with the default compression


@dataclass(frozen=True)
class RecordingEstimate:
    """The estimated size of a recording, per stream.

    Attributes
    ----------
    duration_s : float
        Recorded span (the least duration of the steps). [s]
    streams : tuple of StreamEstimate
        Each stream's rows and bytes.
    tables_bytes : int
        Steps table, event log and :data:`METADATA_BYTES` (not compressed at close). [B]
    """

    duration_s: float
    streams: tuple[StreamEstimate, ...]
    tables_bytes: int

    @property
    def total_bytes(self) -> int:
        """The disk the run needs, the figure the free-space checks use. [B]

        The file as written, which also covers its compressed copy at close for IMUs that give
        counts (module docstring).
        """
        return self.tables_bytes + sum(s.bytes for s in self.streams)

    @property
    def closed_bytes(self) -> int:
        """The estimated size of the closed file, compressed with the default compression. [B]"""
        return self.tables_bytes + sum(s.closed_bytes for s in self.streams)

    def describe(self) -> str:
        """Return one line: the disk needed, the closed file, the span and the streams."""
        parts = ", ".join(f"{s.name} {s.rows:,} rows × {s.row_bytes} B at {s.rate_hz:g} Hz"
                          for s in self.streams)
        return (f"about {format_bytes(self.total_bytes)} of disk, "
                f"{format_bytes(self.closed_bytes)} once closed ({DEFAULT_COMPRESSION}), over "
                f"{self.duration_s:,.0f} s ({self.duration_s / 3600:.2f} h): {parts}")


def format_bytes(n: float) -> str:
    """Return a byte count in kB, MB, GB or TB (powers of 1000), three significant digits."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if abs(n) >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} B"


def _row_bytes(spec: StreamSpec) -> int:
    return sum(np.dtype(c.dtype).itemsize for c in spec.columns.values())


def _chunked(rows: int, row_bytes: int, chunk_rows: int) -> int:
    return math.ceil(rows / chunk_rows) * chunk_rows * row_bytes


def _stream(spec: StreamSpec, rate_hz: float, duration_s: float,
            closed_row_bytes: float | None = None) -> StreamEstimate:
    """Return one stream's estimate (`closed_row_bytes` None: closed as written)."""
    rows = math.floor(rate_hz * duration_s) + 1
    size = _row_bytes(spec)
    closed = rows * (size if closed_row_bytes is None else closed_row_bytes)
    return StreamEstimate(spec.name, rate_hz, rows, size,
                          _chunked(rows, size, DEFAULT_CHUNK_ROWS), math.ceil(closed))


def _closed_motion_row_bytes(n_axes: int) -> float:
    return CLOSED_TIME_BYTES + n_axes * CLOSED_MOTION_AXIS_BYTES


def _table_bytes(fields: Mapping[str, FieldSpec]) -> int:
    return sum(f.max_bytes if f.kind == "text" else np.dtype(f.kind).itemsize
               for f in fields.values())


def estimate_recording(duration_s: float, n_steps: int, facts: StationFacts
                       ) -> RecordingEstimate:
    """Return the estimated recording of `duration_s` of continuous acquisition.

    Parameters
    ----------
    duration_s : float
        Recorded span. [s]
    n_steps : int
        Rows of the steps table (one per step attempt).
    facts : StationFacts
        What is recorded, at which rates.

    Returns
    -------
    RecordingEstimate

    Raises
    ------
    ConfigurationError
        For a negative or non-finite duration or step count.
    """
    if not (math.isfinite(duration_s) and duration_s >= 0) or n_steps < 0:
        raise ConfigurationError(f"`duration_s` must be finite and ≥ 0 and `n_steps` ≥ 0; got "
                                 f"{duration_s} s and {n_steps}")
    streams = []
    for i, rate in enumerate(facts.imu_sample_rates_hz):
        name = f"IMU-{i + 1:04d}"
        streams.append(_stream(imu_stream_spec(name), rate, duration_s, CLOSED_IMU_ROW_BYTES))
        if facts.imu_truth:
            streams.append(_stream(imu_truth_stream_spec(name), rate, duration_s))
    if facts.table_axes:
        axes = [f"axis{i}" for i in range(facts.table_axes)]
        streams.append(_stream(motion_stream_spec(DEVICE_TABLE, "main", axes),
                               facts.feedback_rate_hz, duration_s,
                               _closed_motion_row_bytes(facts.table_axes)))
    if facts.centrifuge:
        streams.append(_stream(motion_stream_spec(DEVICE_CENTRIFUGE, "main", ["spin"]),
                               facts.feedback_rate_hz, duration_s, _closed_motion_row_bytes(1)))
    if facts.chamber:
        streams.append(_stream(chamber_stream_spec("main"), facts.chamber_rate_hz, duration_s))
    events = _EVENTS_PER_STEP * n_steps + _EVENTS_PER_RUN
    tables = (_chunked(max(n_steps, 1), _table_bytes(STEP_FIELDS), STEPS_CHUNK_ROWS)
              + _chunked(events, _table_bytes(LOG_FIELDS), LOG_CHUNK_ROWS) + METADATA_BYTES)
    return RecordingEstimate(float(duration_s), tuple(streams), tables)


def _facts_from_plan(plan: Plan) -> StationFacts:
    """Facts a plan without ``[twin]`` implies: one IMU at its least acquisition rate."""
    axes = max((len(s.angles_deg) for s in plan.steps if isinstance(s, PositionStep)),
               default=0)
    if axes == 0 and any(isinstance(s, RateStep) for s in plan.steps):
        axes = 1 + max(s.axis for s in plan.steps if isinstance(s, RateStep))
    return StationFacts(
        imu_sample_rates_hz=(plan.equipment.acquisition_rate_min_hz,), table_axes=axes,
        centrifuge=any(isinstance(s, CentrifugeStep) for s in plan.steps),
        chamber=any(isinstance(s, SoakStep) for s in plan.steps))


def _soak_s(step: SoakStep, from_degc: float, facts: StationFacts) -> float:
    """Ramp, IMU approach and stable span of a soak (module docstring), within its time-out."""
    ramp = facts.chamber_ramp_degc_per_min
    if step.ramp_degc_per_min is not None:
        ramp = min(ramp, step.ramp_degc_per_min)
    delta = abs(step.temperature_degc - from_degc)
    tau, span = facts.imu_thermal_time_constant_s, step.stable_for_s
    ratio = delta * -math.expm1(-span / tau) / step.imu_band_degc
    approach = tau * math.log(ratio) if ratio > 1.0 else 0.0
    return min(60.0 * delta / ramp + approach + span, step.timeout_s)


def plan_step_starts_s(plan: Plan, facts: StationFacts) -> tuple[float, ...]:
    """Return the expected station time at which each step of a plan's run starts. [s]

    Element ``i`` is the expected duration of the steps before step ``i`` (module docstring),
    summed in the plan's order, so it equals ``plan_run_duration_s`` of the plan cut before
    step ``i`` on the same `facts`; one element more, the last, is the whole run's duration.
    One pass over the steps, for a caller that needs every step's start (a plan's prediction).
    """
    starts = [0.0]
    total = 0.0
    chamber_degc = facts.initial_temperature_degc
    for step in plan.steps:
        if isinstance(step, SoakStep):
            total += _soak_s(step, chamber_degc, facts)
            chamber_degc = step.temperature_degc
        elif isinstance(step, WarmUpStep):
            total += max(step.duration_s, step.window_s)
        elif isinstance(step, PositionStep | RateStep | CentrifugeStep):
            record = step_min_duration_s(step) - step.settle_s
            total += max(step.settle_s, MIN_SETTLE_PHASE_S) + record + MOVE_ALLOWANCE_S
        else:
            total += step_min_duration_s(step)
        starts.append(total)
    return tuple(starts)


def plan_run_duration_s(plan: Plan, facts: StationFacts) -> float:
    """Return the expected duration of a plan's run on a station (module docstring). [s]"""
    return plan_step_starts_s(plan, facts)[-1]


def plan_facts(plan: Plan) -> StationFacts:
    """Return the station facts a plan's estimates assume: its ``[twin]``'s, else its steps'."""
    return StationFacts.of_twin(plan.twin) if plan.twin is not None else _facts_from_plan(plan)


def estimate_plan_recording(plan: Plan, facts: StationFacts | None = None
                            ) -> RecordingEstimate:
    """Return the estimated recording of a plan's run.

    Parameters
    ----------
    plan : Plan
        The plan.
    facts : StationFacts, optional
        The station's; by default those of the plan's ``[twin]``, or, without one, a single IMU
        at ``equipment.acquisition_rate_min_hz`` with the devices the steps need.
    """
    if facts is None:
        facts = plan_facts(plan)
    return estimate_recording(plan_run_duration_s(plan, facts), len(plan.steps), facts)


def estimate_recording_bytes(plan: Plan, *, imu_sample_rate_hz: float | Sequence[float],
                             n_imus: int = 1, table_axes: int = 0, centrifuge: bool = False,
                             feedback_rate_hz: float = 100.0, chamber: bool = False,
                             chamber_rate_hz: float = 1.0) -> int:
    """Return the bytes a plan's recording on a station will take (module docstring).

    Parameters
    ----------
    plan : Plan
        The plan to run.
    imu_sample_rate_hz : float or sequence of float
        The IMUs' output data rate, one for all `n_imus`, or one per IMU. [Hz]
    n_imus : int
        IMUs recorded (ignored when `imu_sample_rate_hz` is a sequence).
    table_axes : int
        Axes of the rate table (0: none).
    centrifuge : bool
        Whether a centrifuge is recorded.
    feedback_rate_hz : float
        Table and centrifuge feedback rate. [Hz]
    chamber : bool
        Whether a chamber is recorded.
    chamber_rate_hz : float
        Chamber reading rate. [Hz]

    Returns
    -------
    int
        The estimated file size. [B]
    """
    rates = (tuple(float(r) for r in imu_sample_rate_hz)
             if isinstance(imu_sample_rate_hz, Sequence)
             else (float(imu_sample_rate_hz),) * n_imus)
    facts = StationFacts(imu_sample_rates_hz=rates, table_axes=table_axes,
                         centrifuge=centrifuge, feedback_rate_hz=feedback_rate_hz,
                         chamber=chamber, chamber_rate_hz=chamber_rate_hz)
    return estimate_plan_recording(plan, facts).total_bytes


def check_free_space(estimate_bytes: int, path: str | os.PathLike[str], *,
                     replaced_bytes: int = 0, what: str = "the recording") -> int:
    """Refuse a recording larger than the free space where `path` will be written.

    Parameters
    ----------
    estimate_bytes : int
        The estimated size. [B]
    path : str or Path
        The file to write (its nearest existing folder is measured).
    replaced_bytes : int
        Bytes freed before writing (an existing file that is overwritten). [B]
    what : str
        What is written, for the message.

    Returns
    -------
    int
        The free space counted. [B]

    Raises
    ------
    LimitExceededError
        If `estimate_bytes` exceeds the free space; the message names both.
    """
    folder = Path(path).absolute().parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    free = shutil.disk_usage(folder).free + max(replaced_bytes, 0)
    if estimate_bytes > free:
        raise LimitExceededError(
            f"{what} needs about {format_bytes(estimate_bytes)} but {folder} has only "
            f"{format_bytes(free)} free; free some space, write elsewhere (--out) or shorten "
            "the steps")
    return free
