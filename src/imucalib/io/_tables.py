"""The ``/steps`` and ``/log`` tables while a Recording is written (private).

:class:`StepLogTables` keeps the steps and pending log events in memory, validates every field
(text is refused, never truncated, when longer than its fixed-length field) and writes the changed
rows to their datasets on :meth:`StepLogTables.write`, which the writer calls at each flush.

A reopened file keeps the step fields of its own format version: in a version 1 file the step's
``role``, ``tags`` and ``units`` have no field and are not stored (the reader derives them as it
does for every version 1 file, see :mod:`imucalib.io._v1`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any

import h5py
import numpy as np

from imucalib.errors import InvalidInputError
from imucalib.io._schema import (
    LOG_FIELDS,
    LOG_LEVELS,
    STEP_FIELDS,
    STEP_STATUSES,
    FieldSpec,
    check_optional_time,
    check_time,
    encode_text,
    json_dumps,
    string_list_json,
)

__all__ = ["UPDATABLE_STEP_FIELDS", "StepLogTables", "create_table"]

UPDATABLE_STEP_FIELDS = tuple(k for k in STEP_FIELDS if k != "index")
_LIST_FIELDS = {"tags": False, "units": True}  # field -> items must be unit names


def create_table(group: h5py.Group, fields: Mapping[str, FieldSpec], chunk_rows: int) -> None:
    """Create one empty, resizable 1-D dataset per field in `group`."""
    for name, spec in fields.items():
        group.create_dataset(name, shape=(0,), maxshape=(None,), chunks=(chunk_rows,),
                             dtype=spec.dtype, fillvalue=np.nan if spec.kind == "f8" else None)


def _encode_commanded(value: Any, where: str) -> str:
    if value is None:
        return ""
    if isinstance(value, str):
        if value:
            try:
                json.loads(value)
            except ValueError as exc:
                raise InvalidInputError(f"{where} must be JSON text or a mapping ({exc})") from exc
        return value
    return json_dumps(value, where)


class StepLogTables:
    """Steps and log events of a Recording being written (all validation happens here)."""

    def __init__(self, steps_group: h5py.Group, log_group: h5py.Group,
                 step_fields: Mapping[str, FieldSpec] = STEP_FIELDS) -> None:
        self._fields = dict(step_fields)
        self._steps_group = steps_group
        self._log_group = log_group
        # opened once: a dataset opened at each write and freed after it is closed by HDF5
        # then, a write Python cannot see fail (docs/reliability.md, "A failed write")
        self._step_datasets: dict[str, h5py.Dataset] = {
            name: steps_group[name] for name in self._fields}
        self._log_datasets: dict[str, h5py.Dataset] = {
            name: log_group[name] for name in LOG_FIELDS}
        self._steps: list[dict[str, Any]] = []
        self._steps_dirty_from: int | None = None
        self.n_steps_written = 0
        self._log_pending: list[tuple[float, bytes, bytes, bytes]] = []
        self.n_log_written = 0

    def load_existing(self) -> None:
        """Take over the rows already in the datasets (reopening a closed Recording)."""
        n = self._step_datasets["index"].shape[0]
        cols = {name: self._step_datasets[name][:n] for name in self._fields}
        for i in range(n):
            row: dict[str, Any] = {}
            for name, spec in self._fields.items():
                value = cols[name][i]
                if spec.kind == "text":
                    row[name] = value.decode("utf-8") if isinstance(value, bytes) else str(value)
                elif spec.kind == "i8":
                    row[name] = int(value)
                else:
                    row[name] = float(value)
            self._steps.append(row)
        self.n_steps_written = n
        self.n_log_written = self._log_datasets["time_s"].shape[0]

    @property
    def n_steps(self) -> int:
        """Steps begun so far."""
        return len(self._steps)

    def begin_step(self, kind: str, label: str, t_start_s: float, commanded: Any, status: str,
                   note: str, role: str = "", tags: Any = (), units: Any = ()) -> int:
        """Validate and add a step; return its index."""
        index = len(self._steps)
        row: dict[str, Any] = {
            "index": index, "kind": "", "label": "", "commanded": "",
            "t_start_s": check_time(t_start_s, "`t_start_s`"), "t_end_s": math.nan,
            "valid_start_s": math.nan, "valid_end_s": math.nan, "status": "", "note": "",
        }
        fields = {"kind": kind, "label": label, "commanded": commanded, "status": status,
                  "note": note, "role": role, "tags": tags, "units": units}
        self._set_step_fields(row, fields)
        self._steps.append(row)
        self._mark_steps_dirty(index)
        return index

    def update_step(self, index: Any, fields: Mapping[str, Any]) -> None:
        """Validate and apply new values of a step's fields."""
        if not isinstance(index, int | np.integer) or not 0 <= index < len(self._steps):
            raise InvalidInputError(f"no step with index {index!r}; steps 0..{len(self._steps) - 1}"
                                    " have begun")
        unknown = [k for k in fields if k not in UPDATABLE_STEP_FIELDS]
        if unknown:
            raise InvalidInputError(f"cannot update step field(s) {unknown}; updatable: "
                                    f"{list(UPDATABLE_STEP_FIELDS)}")
        row = dict(self._steps[int(index)])
        self._set_step_fields(row, fields)
        self._steps[int(index)] = row
        self._mark_steps_dirty(int(index))

    def _set_step_fields(self, row: dict[str, Any], fields: Mapping[str, Any]) -> None:
        i = row["index"]
        for key, value in fields.items():
            where = f"step {i} `{key}`"
            spec = STEP_FIELDS[key]
            if key == "commanded":
                value = _encode_commanded(value, where)
            if key in _LIST_FIELDS:
                value = string_list_json(value, where, names=_LIST_FIELDS[key])
            if key == "status" and value not in STEP_STATUSES:
                raise InvalidInputError(f"{where} must be one of {STEP_STATUSES}; got {value!r}")
            if spec.kind == "text":
                encode_text(value, where, spec.max_bytes)
            elif key == "t_start_s":
                value = check_time(value, where)
            else:
                value = check_optional_time(value, where)
            if key in self._fields:  # a version 1 file has no role, tags or units
                row[key] = value
        for lo, hi in (("t_start_s", "t_end_s"), ("valid_start_s", "valid_end_s")):
            if row[hi] < row[lo]:
                raise InvalidInputError(f"step {i}: `{hi}` ({row[hi]!r} s) is before `{lo}` "
                                        f"({row[lo]!r} s)")

    def _mark_steps_dirty(self, index: int) -> None:
        if self._steps_dirty_from is None or index < self._steps_dirty_from:
            self._steps_dirty_from = index

    def log_event(self, time_s: float, level: str, source: str, message: str) -> None:
        """Validate and queue an event."""
        t = check_time(time_s, "`time_s`")
        if level not in LOG_LEVELS:
            raise InvalidInputError(f"`level` must be one of {LOG_LEVELS}; got {level!r}")
        src = encode_text(source, "`source`", LOG_FIELDS["source"].max_bytes)
        msg = encode_text(message, "`message`", LOG_FIELDS["message"].max_bytes)
        self._log_pending.append((t, level.encode(), src, msg))

    def write(self) -> None:
        """Write changed step rows and pending events (HDF5 errors propagate)."""
        self._write_steps()
        self._write_log()

    def _write_steps(self) -> None:
        start = self._steps_dirty_from
        if start is None:
            return
        rows = self._steps[start:]
        n1 = len(self._steps)
        for name, spec in self._fields.items():
            ds = self._step_datasets[name]
            if ds.shape[0] != n1:
                ds.resize((n1,))
            values = [r[name] for r in rows]
            data = (np.array([v.encode("utf-8") for v in values], dtype=spec.dtype)
                    if spec.kind == "text" else np.array(values, dtype=spec.dtype))
            ds[start:n1] = data
        self._steps_dirty_from = None
        self.n_steps_written = n1

    def _write_log(self) -> None:
        if not self._log_pending:
            return
        n0 = self.n_log_written
        n1 = n0 + len(self._log_pending)
        cols = list(zip(*self._log_pending, strict=True))
        for (name, spec), values in zip(LOG_FIELDS.items(), cols, strict=True):
            ds = self._log_datasets[name]
            if ds.shape[0] != n1:
                ds.resize((n1,))
            ds[n0:n1] = np.array(values, dtype=spec.dtype)
        self._log_pending.clear()
        self.n_log_written = n1
