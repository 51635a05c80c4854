"""A Recording from IMU data without step records: a CSV file plus its step file (docs/import.md).

:func:`recording_from_csv` writes a version 2 Recording that the procedure its step roles name
analyses as it does a planned run (P1, Allan, the tumble …: a procedure that reads the IMU stream,
the table stream and the steps' roles, tags and commanded states):

- ``/streams/imu/<unit>``: the CSV's samples in SI (:func:`~imucalib.io.csv_import.iter_imu_csv`,
  written chunk by chunk: a log larger than memory imports).
  Columns the CSV lacks are filled: ``counter`` from the time column and the sample rate
  (each sample advances it by ``max(1, round(Δt·f_s))``, so a gap of k sample periods stays
  visible to the time-base reconstruction and equal times still count up),
  ``device_time_s`` = ``time_s``, ``temperature_degc`` NaN, ``saturated`` false.
- ``/streams/table/commanded``, when the steps give table angles or turns
  (:attr:`~imucalib.io.step_file.StepFile.has_table`): a table stream **reconstructed from the
  step file**, not measured: inside each step's interval, at the IMU's own sample times, the
  commanded angles (a rate step: the angle at ``start_s``, 0 when not given, plus
  ``rate_dps``·(t − ``start_s``) on its axis) and rates. Its columns say so in their
  descriptions, the metadata key ``table_feedback`` is ``"reconstructed from the step file"``,
  and the equipment's accuracy enters the analysis as its Type B uncertainty (the step file's
  ``table_position_accuracy_arcsec``; the default otherwise). Without table states (an Allan
  record) there is no table stream.
- ``/steps``: one row per step with a role, status ``done``, its interval as both span and
  valid window, its role, tags and commanded state (``angles_deg``, ``axis`` as an index,
  ``rate_dps``) in the plan's step vocabulary.
- metadata: ``source = "csv-import"``, ``source_file``, ``source_sha256``, ``step_file_toml``
  (the step file as read), ``latitude_deg``, ``heading_deg``, ``imu_identity_json`` (the sample
  rate, the bandwidth when given) and, when the step file gives them, ``equipment_json`` and
  ``imu_spec_json`` (accuracies and held-out limits, read by the analysis in place of a plan's).

The step intervals must lie inside the data (each needs at least 10 samples); an interval
that does not is refused with its step named, before anything is written. The roles are checked
for their grammar only (:mod:`imucalib.io.step_file`); that a procedure has them is the caller's
check against the registry (:func:`imucalib.procedures.registry.check_roles`, which ``imucalib
import`` and ``imucalib calibrate --steps`` run).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import (
    ACCEL_COLUMNS,
    COUNTER_COLUMN,
    GYRO_COLUMNS,
    IMU_COLUMNS,
    TEMPERATURE_COLUMN,
    TIME_COLUMN,
)
from imucalib.errors import InvalidInputError
from imucalib.io._schema import ColumnSpec, StreamSpec
from imucalib.io.context import RecordingContext
from imucalib.io.csv_import import DEFAULT_CHUNK_ROWS, iter_imu_csv
from imucalib.io.hashing import file_sha256
from imucalib.io.import_spec import ImportSpec, iter_imu_table
from imucalib.io.recording import RecordingWriter
from imucalib.io.step_file import StepEntry, StepFile, step_file_to_toml
from imucalib.io.streams import DEVICE_TABLE, axis_columns, imu_stream_spec

if TYPE_CHECKING:
    from collections.abc import Iterator, Mapping

    import pandas as pd

__all__ = ["RECONSTRUCTED_TABLE", "TABLE_FEEDBACK_RECONSTRUCTED", "recording_from_csv"]

#: The name of the reconstructed table stream (``/streams/table/commanded``).
RECONSTRUCTED_TABLE = "commanded"
#: The ``table_feedback`` metadata value of an imported recording.
TABLE_FEEDBACK_RECONSTRUCTED = "reconstructed from the step file"
#: Fewest IMU samples in a step's interval.
MIN_STEP_SAMPLES = 10

_F64 = NDArray[np.float64]


def _counter(t: _F64, rate_hz: float) -> NDArray[np.int64]:
    """Return the counter of times `t`: cᵢ = max(cᵢ₋₁ + 1, round((tᵢ − t₀)·f_s)).

    Each sample gets the index of its time on the nominal grid, one more than its
    predecessor's at least. A dropout of k samples advances it by k + 1; receive-time jitter
    does not accumulate into false dropouts (rounding each Δt·f_s would count a late sample's
    long interval as a lost sample and not take it back at the short one that follows: 4 % of
    the samples of a log received with ±0.7 ms of jitter at 1 kHz).
    """
    grid = np.round((t - t[0]) * rate_hz).astype(np.int64)
    # cᵢ − i is the running maximum of gridᵢ − i: the "+1 at least" rule in one pass
    index = np.arange(t.size, dtype=np.int64)
    return np.asarray(np.maximum.accumulate(grid - index) + index, dtype=np.int64)


def _imu_rows(df: pd.DataFrame, counter: NDArray[np.int64] | None) -> dict[str, Any]:
    """Return the IMU stream's columns of one chunk; `counter` None: the file's own, rounded."""
    t = df.index.to_numpy(dtype=np.float64)
    n = t.size
    cols: dict[str, Any] = {
        TIME_COLUMN: t,
        COUNTER_COLUMN: (np.asarray(np.round(df[COUNTER_COLUMN].to_numpy()), dtype=np.int64)
                         if counter is None else counter),
        "device_time_s": (df["device_time_s"].to_numpy() if "device_time_s" in df.columns
                          else t)}
    for col in (*GYRO_COLUMNS, *ACCEL_COLUMNS):
        cols[col] = df[col].to_numpy(dtype=np.float64)
    cols[TEMPERATURE_COLUMN] = (df[TEMPERATURE_COLUMN].to_numpy(dtype=np.float64)
                                if TEMPERATURE_COLUMN in df.columns else np.full(n, np.nan))
    cols["saturated"] = (df["saturated"].to_numpy() != 0 if "saturated" in df.columns
                         else np.zeros(n, dtype=bool))
    return cols


def _sample_rate(t: _F64, given: float | None, source: str) -> float:
    if given is not None:
        return float(given)
    dt = np.diff(t)
    dt = dt[dt > 0]
    if dt.size == 0:
        raise InvalidInputError(f"{source}: the time column never advances; give the step "
                                "file's `sample_rate_hz`")
    return float(1.0 / np.median(dt))


def _table_rows(step: StepEntry, steps: StepFile, t: _F64) -> dict[str, _F64]:
    """Return the reconstructed table at the IMU times `t` of one step (module docstring)."""
    cols: dict[str, _F64] = {TIME_COLUMN: t}
    angles = step.angles_deg
    turning = steps.axis_index(step.axis) if step.axis is not None else None
    for i, name in enumerate(steps.table_axes):
        a_col, r_col = axis_columns(name)
        a0 = math.radians(angles[i]) if angles else 0.0
        if i == turning and step.rate_dps:
            rate = math.radians(step.rate_dps)
            cols[a_col] = a0 + rate * (t - step.start_s)
            cols[r_col] = np.full(t.size, rate)
        else:
            cols[a_col] = np.full(t.size, a0)
            cols[r_col] = np.zeros(t.size)
    return cols


def _table_spec(axes: tuple[str, ...]) -> StreamSpec:
    cols: dict[str, ColumnSpec] = {}
    for axis in axes:
        a_col, r_col = axis_columns(axis)
        cols[a_col] = ColumnSpec("rad", description=f"commanded {axis} angle from the step "
                                 "file (reconstructed, not measured)")
        cols[r_col] = ColumnSpec("rad/s", description=f"commanded {axis} rate from the step "
                                 "file (reconstructed, not measured)")
    return StreamSpec(DEVICE_TABLE, RECONSTRUCTED_TABLE, cols)


def _commanded(step: StepEntry, steps: StepFile) -> dict[str, Any]:
    cmd: dict[str, Any] = {"source": "step file"}
    if step.angles_deg is not None:
        cmd["angles_deg"] = list(step.angles_deg)
    if step.axis is not None:
        cmd["axis"] = steps.axis_index(step.axis)
        cmd["rate_dps"] = step.rate_dps
    return cmd


def recording_from_csv(csv_path: str | os.PathLike[str], steps: StepFile,
                       out_path: str | os.PathLike[str], *, unit: str | None = None,
                       column_map: Mapping[str, str] | None = None,
                       units: Mapping[str, str] | None = None, overwrite: bool = False,
                       spec: ImportSpec | None = None,
                       step_file_text: str | None = None,
                       chunk_rows: int = DEFAULT_CHUNK_ROWS) -> Path:
    """Write a Recording from a CSV of IMU samples and its step file (module docstring).

    Parameters
    ----------
    csv_path : str or Path
        IMU samples with a ``time_s`` column and the six gyro and accelerometer columns
        (:func:`~imucalib.io.csv_import.read_imu_csv`, whose `column_map` and `units` apply).
    steps : StepFile
        What each interval is.
    out_path : str or Path
        The Recording to write.
    unit : str, optional
        The IMU's name; default: the step file's ``unit``, else the CSV's stem.
    overwrite : bool
        Replace an existing `out_path`.
    spec : ImportSpec, optional
        How to read the log (:func:`~imucalib.io.import_spec.read_imu_table`: column map,
        units, counts scale and offset, sample rate …); replaces `column_map` and `units`.
    step_file_text : str, optional
        The step file as the user wrote it, stored in the metadata (default: its TOML).
    chunk_rows : int
        Rows read and written at a time. A log of more rows is read twice (first its checks and
        times, then its samples, chunk by chunk): memory holds a chunk or two plus the time and
        counter columns (16 bytes a sample), not the whole log.

    Returns
    -------
    Path
        `out_path`.

    Raises
    ------
    InvalidInputError
        A missing column, a step interval outside the data or with fewer than
        :data:`MIN_STEP_SAMPLES` samples, a bad unit name (the CSV's own errors are
        :func:`~imucalib.io.csv_import.read_imu_csv`'s).
    RecordingError
        `out_path` exists and `overwrite` is false, or it cannot be written.
    """
    src = Path(csv_path)

    def frames() -> Iterator[pd.DataFrame]:
        if spec is not None:
            return iter_imu_table(src, spec, chunk_rows=chunk_rows)
        return iter_imu_csv(src, column_map=column_map, units=units, chunk_rows=chunk_rows)

    # first pass: every check of the rows, the times and whether the file's counter is usable;
    # a file of one chunk is kept, a larger one read again for the writing
    times: list[_F64] = []
    kept: list[pd.DataFrame] | None = []
    file_counter = True
    for k, df in enumerate(frames()):
        if k == 0:
            missing = [c for c in IMU_COLUMNS if c not in df.columns]
            if missing:
                raise InvalidInputError(
                    f"{src}: a calibration needs the gyro and accelerometer columns "
                    f"{list(IMU_COLUMNS)}; missing {missing} (found {list(df.columns)})")
        times.append(df.index.to_numpy(dtype=np.float64))
        file_counter = file_counter and COUNTER_COLUMN in df.columns and bool(
            np.all(np.isfinite(df[COUNTER_COLUMN].to_numpy())))
        kept = [df] if k == 0 else None
    name = unit or steps.unit or src.stem
    t = times[0] if len(times) == 1 else np.concatenate(times)
    del times
    rate_hz = _sample_rate(t, steps.sample_rate_hz, str(src))
    used = steps.used_steps
    bounds: list[tuple[int, int]] = []
    for k, step in enumerate(used):
        i0, i1 = (int(v) for v in np.searchsorted(t, [step.start_s, step.end_s], side="left"))
        where = f"step {k} ({step.label or step.role}, {step.start_s:g}–{step.end_s:g} s)"
        if step.start_s < t[0] or step.end_s > t[-1]:
            raise InvalidInputError(f"{src}: {where} is not inside the data, which run from "
                                    f"{t[0]:g} to {t[-1]:g} s")
        if i1 - i0 < MIN_STEP_SAMPLES:
            raise InvalidInputError(f"{src}: {where} holds {i1 - i0} samples; at least "
                                    f"{MIN_STEP_SAMPLES} are needed")
        bounds.append((i0, i1))
    ident: dict[str, Any] = {"serial": name, "sample_rate_hz": rate_hz, "source": "csv-import"}
    if steps.bandwidth_hz is not None:
        ident["bandwidth_hz"] = steps.bandwidth_hz
    meta: dict[str, str | int | float | bool] = {
        "source": "csv-import", "source_file": src.name, "source_sha256": file_sha256(src),
        "step_file_toml": step_file_text or step_file_to_toml(steps),
        "heading_deg": steps.heading_deg, "imu_identity_json": json.dumps({name: ident}),
    }
    if steps.has_table:
        meta["table_feedback"] = TABLE_FEEDBACK_RECONSTRUCTED
    if steps.latitude_deg is not None:
        meta["latitude_deg"] = steps.latitude_deg
    # what the step file gives of the context, in the keys a run writes (io/context.py)
    context = RecordingContext(
        equipment={k: float(v) for k, v in (
            ("table_position_accuracy_arcsec", steps.table_position_accuracy_arcsec),
            ("table_orthogonality_arcsec", steps.table_orthogonality_arcsec)) if v is not None},
        imu_spec={k: float(v) for k, v in (("accel_accuracy_g", steps.accel_accuracy_g),
                                           ("gyro_accuracy_dps", steps.gyro_accuracy_dps))
                  if v is not None},
        imu_unit={"grade": steps.grade} if steps.grade is not None else {})
    meta.update(context.metadata())

    counter = None if file_counter else _counter(t, rate_hz)
    n = t.size
    streams = [imu_stream_spec(name)]
    if steps.has_table:
        streams.append(_table_spec(steps.table_axes))
    with RecordingWriter(out_path, streams=streams, metadata=meta, overwrite=overwrite,
                         flush_interval_s=math.inf) as writer:
        a = 0
        for df in (kept if kept is not None else frames()):
            writer.append("imu", name, _imu_rows(df, None if counter is None
                                                 else counter[a:a + len(df)]))
            a += len(df)
        for step, (i0, i1) in zip(used, bounds, strict=True):
            if steps.has_table:
                writer.append(DEVICE_TABLE, RECONSTRUCTED_TABLE,
                              _table_rows(step, steps, t[i0:i1]))
            idx = writer.begin_step(step.kind, step.label or step.role, step.start_s,
                                    commanded=_commanded(step, steps), role=step.role,
                                    tags=step.tags)
            writer.update_step(idx, t_end_s=step.end_s, valid_start_s=step.start_s,
                               valid_end_s=step.end_s, status="done")
        writer.log_event(float(t[0]), "info", "import",
                         f"imported {n:,} samples of {name} from {src.name} with "
                         f"{len(used)} steps from the step file"
                         + ("; the table stream is reconstructed from the commanded states"
                            if steps.has_table else ""))
    return Path(out_path)
