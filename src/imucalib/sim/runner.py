"""Run a twin scenario into a Recording.

The scenario's steps are scheduled on the rig first (every command issued at its virtual time,
every valid window computed from the twin's settling), then the streams are generated chunk by
chunk and written as the virtual clock passes each step's start and end, so the file grows as a
station's recording would and a killed run keeps what was flushed.

Contents
--------
:func:`simulate_scenario`
    Scenario → Recording file; returns a :class:`SimulationSummary`.
:func:`schedule_steps`
    Issue a scenario's commands on a rig and return the :class:`ScheduledStep` list (pure
    bookkeeping on the rig's twins; nothing is generated).
:func:`write_chunk`
    Append one :class:`~imucalib.sim.rig.RigChunk` to a Recording with the canonical layouts.
:func:`rig_stream_specs`
    The canonical stream layouts of a rig's devices.

Valid windows
-------------
- *position*: the move's reference profile ends at t_m; recording starts at
  max(t_m + ``settle_s``, the time from which every axis stays within 5″ and 5″/s of its target,
  bounded by the servo's exponential envelope) and lasts ``record_s`` (SPEC.md P1: settle ≥30 s,
  table within 5″).
- *rate*: from max(ramp end + ``settle_s``, the time the rate stays within 0.5 °/s), over
  ``revolutions`` whole turns at the commanded rate (analysis refines the window on the measured
  angle) or ``record_s``.
- *static*: the whole step; *soak*: no valid window (not a measurement).
- *centrifuge*: as *rate*, or, at rest with an arm position, as *position*.

Position targets are taken modulo a turn: an unlimited axis goes to the equivalent angle nearest
to where it is (after spinning it does not unwind the turns).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from imucalib import units
from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS
from imucalib.errors import InvalidInputError
from imucalib.io._schema import StreamSpec
from imucalib.io.recording import RecordingWriter
from imucalib.io.streams import (
    DEVICE_CENTRIFUGE,
    DEVICE_CHAMBER,
    DEVICE_IMU,
    DEVICE_TABLE,
    axis_columns,
    chamber_stream_spec,
    imu_stream_spec,
    imu_truth_stream_spec,
    motion_stream_spec,
)
from imucalib.sim.build import build_rig
from imucalib.sim.rig import RigChunk, TwinRig
from imucalib.sim.scenario import (
    CentrifugeStep,
    PositionStep,
    RateStep,
    Scenario,
    SoakStep,
    StaticStep,
)
from imucalib.sim.table import SimRateTable, TableFeedback

__all__ = [
    "POSITION_TOLERANCE_RAD",
    "RATE_TOLERANCE_RPS",
    "ScheduledStep",
    "SimulationSummary",
    "rig_stream_specs",
    "schedule_steps",
    "simulate_scenario",
    "write_chunk",
]

#: Table deviation allowed in a valid position window (SPEC.md P1: 5″).
POSITION_TOLERANCE_RAD = 5.0 * units.ARCSEC
#: Rate deviation allowed in a valid rate window (SPEC.md P1: 0.5 °/s).
RATE_TOLERANCE_RPS = 0.5 * units.DEG
_HOLD_RATE_TOLERANCE_RPS = 5.0 * units.ARCSEC  # a held position must also be at rest
MAIN_UNIT = "main"

ProgressCallback = Callable[[float, float], None]


@dataclass(frozen=True)
class ScheduledStep:
    """One scenario step placed on the virtual time line.

    ``valid_start_s``/``valid_end_s`` are None for a step without a measurement window.
    """

    index: int
    kind: str
    label: str
    commanded: dict[str, Any]
    t_start_s: float
    t_end_s: float
    valid_start_s: float | None
    valid_end_s: float | None
    note: str = ""


@dataclass(frozen=True)
class SimulationSummary:
    """What :func:`simulate_scenario` wrote."""

    path: Path
    scenario: str
    steps: tuple[ScheduledStep, ...]
    virtual_duration_s: float
    wall_time_s: float
    samples: dict[str, int] = field(default_factory=dict)

    def describe(self) -> str:
        """Return a short human-readable account (for the CLI)."""
        rate = self.virtual_duration_s / self.wall_time_s if self.wall_time_s > 0 else math.inf
        lines = [f"wrote {self.path}: scenario {self.scenario!r}, {len(self.steps)} steps, "
                 f"{self.virtual_duration_s:,.1f} s of virtual time in {self.wall_time_s:.1f} s "
                 f"({rate:,.0f}× real time)"]
        lines += [f"  {name}: {n:,} samples" for name, n in self.samples.items()]
        return "\n".join(lines)


def _nearest_equivalent(target_rad: float, current_rad: float) -> float:
    """Return target + 2πk closest to `current_rad`."""
    return target_rad + 2.0 * math.pi * round((current_rad - target_rad) / (2.0 * math.pi))


def _hold_settled(table: SimRateTable, axes: Sequence[int]) -> float:
    return max(table.settled_after_s(i, POSITION_TOLERANCE_RAD, _HOLD_RATE_TOLERANCE_RPS)
               for i in axes)


def _rate_settled(table: SimRateTable, axis: int) -> float:
    return table.settled_after_s(axis, POSITION_TOLERANCE_RAD, RATE_TOLERANCE_RPS)


def _position(table: SimRateTable, angles_deg: Sequence[float], t0: float
              ) -> tuple[float, float]:
    """Command every axis to its angle; return (reference end, settled-from time)."""
    ends = []
    for i, angle_deg in enumerate(angles_deg):
        target = angle_deg * units.DEG
        if table.spec.axes[i].angle_limits_rad is None:
            current = float(table.axis_motion(i, np.array([t0]))[0][0])
            target = _nearest_equivalent(target, current)
        ends.append(table.command_position(i, target, t0))
    return max(ends), _hold_settled(table, range(len(angles_deg)))


def _spin(table: SimRateTable, axis: int, rate_dps: float, t0: float) -> tuple[float, float]:
    """Command a rate; return (ramp end, settled-from time)."""
    t_ramp = table.command_rate(axis, rate_dps * units.DEG, t0)
    if rate_dps == 0.0:
        return t_ramp, _hold_settled(table, [axis])
    return t_ramp, _rate_settled(table, axis)


def _window(t_ready: float, settled: float, settle_s: float, length_s: float
            ) -> tuple[float, float, str]:
    note = ""
    start = t_ready + settle_s
    if math.isfinite(settled) and settled > start:
        note = f"settling extended the dwell by {settled - start:.3f} s"
        start = settled
    elif not math.isfinite(settled):
        note = "settling tolerance not reached (rate ripple); window after the dwell"
    return start, start + length_s, note


def _record_length_s(revolutions: int | None, record_s: float | None, rate_dps: float) -> float:
    if revolutions is not None:
        return revolutions * 360.0 / abs(rate_dps)
    assert record_s is not None  # validated by the scenario schema
    return record_s


def schedule_steps(sc: Scenario, rig: TwinRig) -> list[ScheduledStep]:
    """Issue every command of `sc` on `rig`'s twins and return the steps on the time line.

    Raises
    ------
    LimitExceededError
        If a commanded angle, rate, acceleration or temperature exceeds a device limit.
    """
    out: list[ScheduledStep] = []
    t = 0.0
    for i, step in enumerate(sc.steps):
        commanded: dict[str, Any] = step.model_dump(exclude={"label"})
        valid: tuple[float, float] | None
        note = ""
        if isinstance(step, StaticStep):
            valid = (t, t + step.duration_s)
            t_end = t + step.duration_s
        elif isinstance(step, SoakStep):
            assert rig.chamber is not None  # validated by the scenario schema
            ramp = None if step.ramp_degc_per_min is None else step.ramp_degc_per_min / 60.0
            rig.chamber.command_setpoint(step.temperature_degc, t, ramp)
            valid, t_end = None, t + step.duration_s
        elif isinstance(step, PositionStep):
            assert rig.table is not None
            t_ready, settled = _position(rig.table, step.angles_deg, t)
            v0, v1, note = _window(t_ready, settled, step.settle_s, step.record_s)
            valid, t_end = (v0, v1), v1
        elif isinstance(step, RateStep):
            assert rig.table is not None
            t_ready, settled = _spin(rig.table, step.axis, step.rate_dps, t)
            length = _record_length_s(step.revolutions, step.record_s, step.rate_dps)
            v0, v1, note = _window(t_ready, settled, step.settle_s, length)
            valid, t_end = (v0, v1), v1
        elif isinstance(step, CentrifugeStep):
            assert rig.centrifuge is not None
            fuge = rig.centrifuge
            if step.rate_dps == 0.0 and step.arm_position_deg is not None:
                t_stop = fuge.command_stop(t) if fuge.table.mode(0, t) == "rate" else t
                t_ready, settled = _position(fuge.table, [step.arm_position_deg], t_stop)
            else:
                t_ready, settled = _spin(fuge.table, 0, step.rate_dps, t)
            length = _record_length_s(step.revolutions, step.record_s, step.rate_dps)
            v0, v1, note = _window(t_ready, settled, step.settle_s, length)
            valid, t_end = (v0, v1), v1
        else:  # pragma: no cover - the schema admits no other kind
            raise InvalidInputError(f"unknown step kind {step.kind!r}")
        out.append(ScheduledStep(i, step.kind, step.label or f"{step.kind} {i}", commanded, t,
                                 t_end, None if valid is None else valid[0],
                                 None if valid is None else valid[1], note))
        t = t_end
    return out


def rig_stream_specs(rig: TwinRig) -> list[StreamSpec]:
    """Return the canonical layouts of every stream `rig` produces."""
    specs = [imu_stream_spec(name) for name in rig.imu_names]
    if rig.table is not None:
        specs.append(motion_stream_spec(DEVICE_TABLE, MAIN_UNIT, rig.table.spec.names))
    if rig.centrifuge is not None:
        specs.append(motion_stream_spec(DEVICE_CENTRIFUGE, MAIN_UNIT,
                                        rig.centrifuge.table.spec.names))
    if rig.chamber is not None:
        specs.append(chamber_stream_spec(MAIN_UNIT))
    return specs


def _motion_columns(fb: TableFeedback, names: Sequence[str]) -> dict[str, Any]:
    cols: dict[str, Any] = {"time_s": fb.time_s}
    for i, axis in enumerate(names):
        angle, rate = axis_columns(axis)
        cols[angle] = fb.angle_rad[:, i]
        cols[rate] = fb.rate_rps[:, i]
    return cols


def write_chunk(writer: RecordingWriter, rig: TwinRig, chunk: RigChunk, *,
                truth_streams: bool = False) -> dict[str, int]:
    """Append every stream of `chunk` to `writer`; return the rows written per stream."""
    rows: dict[str, int] = {}
    for name, s in chunk.imu.items():
        cols: dict[str, Any] = {"time_s": s.time_s, "device_time_s": s.device_time_s,
                                "counter": s.counter, "temperature_degc": s.temperature_degc,
                                "saturated": s.saturated}
        for j, col in enumerate(GYRO_COLUMNS):
            cols[col] = s.gyro_rps[:, j]
        for j, col in enumerate(ACCEL_COLUMNS):
            cols[col] = s.accel_mps2[:, j]
        writer.append(DEVICE_IMU, name, cols)
        rows[f"{DEVICE_IMU}/{name}"] = len(s)
        if truth_streams:
            truth: dict[str, Any] = {"time_s": s.time_s, "true_time_s": s.true_time_s,
                                     "true_temperature_degc": s.true_temperature_degc}
            for j, axis in enumerate("xyz"):
                truth[f"true_rate_{axis}_rps"] = s.true_rate_b_rps[:, j]
                truth[f"true_force_{axis}_mps2"] = s.true_specific_force_b_mps2[:, j]
            writer.append_truth(DEVICE_IMU, name, truth)
    if chunk.table is not None and rig.table is not None:
        writer.append(DEVICE_TABLE, MAIN_UNIT, _motion_columns(chunk.table, rig.table.spec.names))
        rows[f"{DEVICE_TABLE}/{MAIN_UNIT}"] = len(chunk.table.time_s)
    if chunk.centrifuge is not None and rig.centrifuge is not None:
        writer.append(DEVICE_CENTRIFUGE, MAIN_UNIT,
                      _motion_columns(chunk.centrifuge, rig.centrifuge.table.spec.names))
        rows[f"{DEVICE_CENTRIFUGE}/{MAIN_UNIT}"] = len(chunk.centrifuge.time_s)
    if chunk.chamber is not None:
        writer.append(DEVICE_CHAMBER, MAIN_UNIT, {
            "time_s": chunk.chamber.time_s, "temperature_degc": chunk.chamber.temperature_degc,
            "setpoint_degc": chunk.chamber.setpoint_degc})
        rows[f"{DEVICE_CHAMBER}/{MAIN_UNIT}"] = len(chunk.chamber.time_s)
    return rows


def _metadata(sc: Scenario, rig: TwinRig) -> dict[str, str | int | float | bool]:
    station = {
        "kind": "digital-twin",
        "table": None if rig.table is None else {"axes": list(rig.table.spec.names)},
        "centrifuge": None if rig.centrifuge is None else {"axes": ["spin"]},
        "chamber": rig.chamber is not None,
        "feedback_rate_hz": rig.feedback_rate_hz,
        "site": sc.site.model_dump(),
    }
    identity = {imu.name: {"serial": imu.name, "model": f"twin-{imu.grade}",
                           "maker": "imucalib digital twin", "grade": imu.grade,
                           "sample_rate_hz": rig.imus[imu.name].model.sample_rate_hz}
                for imu in sc.imus}
    return {"scenario_json": sc.model_dump_json(), "station_json": json.dumps(station),
            "imu_identity_json": json.dumps(identity),
            "environment_json": json.dumps(
                {"ambient_temperature_degc": sc.site.ambient_temperature_degc}),
            "latitude_deg": sc.site.latitude_deg, "heading_deg": sc.site.heading_deg,
            "source": "twin"}


def simulate_scenario(sc: Scenario, path: str | Path, *,
                      progress: ProgressCallback | None = None, overwrite: bool = False,
                      flush_interval_s: float = 1.0) -> SimulationSummary:
    """Run scenario `sc` on the twin and write its Recording to `path`.

    Parameters
    ----------
    sc : Scenario
        What to simulate.
    path : str or Path
        The Recording to create.
    progress : callable, optional
        ``progress(done_s, total_s)`` after each chunk, in virtual seconds.
    overwrite : bool
        Replace an existing file.
    flush_interval_s : float
        Wall-clock interval between flushes of the writer. [s]

    Returns
    -------
    SimulationSummary

    Raises
    ------
    LimitExceededError
        If the scenario asks a device for more than its limits (before anything is written).
    RecordingError
        If the file exists (without `overwrite`) or cannot be written.
    """
    wall0 = time.perf_counter()
    built = build_rig(sc)
    rig = built.rig
    steps = schedule_steps(sc, rig)
    total_s = steps[-1].t_end_s
    samples: dict[str, int] = {}
    with RecordingWriter(
        path, streams=rig_stream_specs(rig), metadata=_metadata(sc, rig), truth=built.truth,
        truth_streams=([imu_truth_stream_spec(n) for n in rig.imu_names]
                       if sc.store_truth_streams else ()),
        overwrite=overwrite, flush_interval_s=flush_interval_s,
    ) as writer:
        writer.log_event(0.0, "info", "twin", f"scenario {sc.name!r} started "
                         f"({len(steps)} steps, {total_s:,.1f} s virtual)")
        begun = ended = 0
        t = 0.0
        while True:
            t_next = min(t + sc.chunk_s, total_s)
            chunk = rig.generate(t_next)
            for key, n in write_chunk(writer, rig, chunk,
                                      truth_streams=sc.store_truth_streams).items():
                samples[key] = samples.get(key, 0) + n
            while begun < len(steps) and (steps[begun].t_start_s < t_next or t_next >= total_s):
                s = steps[begun]
                writer.begin_step(s.kind, s.label, s.t_start_s, commanded=s.commanded)
                begun += 1
            while ended < begun and (steps[ended].t_end_s <= t_next):
                s = steps[ended]
                fields: dict[str, Any] = {"t_end_s": s.t_end_s, "status": "done"}
                if s.valid_start_s is not None:
                    fields.update(valid_start_s=s.valid_start_s, valid_end_s=s.valid_end_s)
                if s.note:
                    fields["note"] = s.note
                writer.update_step(s.index, **fields)
                ended += 1
            if progress is not None:
                progress(t_next, total_s)
            t = t_next
            if t >= total_s:
                break
        writer.log_event(total_s, "info", "twin", f"scenario {sc.name!r} finished")
    return SimulationSummary(path=Path(path), scenario=sc.name, steps=tuple(steps),
                             virtual_duration_s=total_s,
                             wall_time_s=time.perf_counter() - wall0, samples=samples)
