"""Recover a Recording that a crashed writer left open, or a damaged one, into a clean file.

Contents
--------
:func:`recover_recording`
    Read the file (in SWMR mode if a writer left it open), copy every valid object into
    ``<stem>.recovered.h5``, verify the copy and return a :class:`RecoveryReport`.
:class:`RecoveryReport`, :class:`RecoveredStream`
    What was copied and what was dropped; ``summary()`` renders it for the CLI.

The original is never modified. Each stream is copied up to its committed row count (see the
``/commit`` entry of the format in :mod:`imucalib.io.recording`), capped by the shortest of its
columns so that they stay aligned, and cut before the first row whose ``time_s`` is not finite,
negative, implausibly late or decreasing; rows a writer had not committed, or that cannot be
read, are dropped and reported. Damage that :func:`~imucalib.io.opening.open_recording` refuses is
mended where it can be without inventing data: a missing ``/steps`` or ``/log`` is written empty,
missing step fields get empty values, a ``commanded`` that is not JSON is cleared (and ``tags`` or
``units`` that are not JSON lists of strings), an unknown step
status becomes ``invalid``, infinite step times become NaN, log events with an unknown level or a
non-finite time are dropped, negative or unreadable commit counts are replaced by what every
column holds, a damaged ``columns_json`` is rebuilt from the columns' own attributes, and
unreadable streams or columns are left out; every such change is reported. The copy is written to
a temporary name, verified (it must pass every check of ``open_recording``, and every column's
SHA-256 must match what was written), then renamed.

The copy keeps the original's format version (a version 1 file stays version 1, with its step
fields); a file whose root attributes cannot be read is copied as the current version.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, TypeVar

import h5py
import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import TIME_COLUMN
from imucalib.errors import (
    InvalidInputError,
    RecordingCorruptError,
    RecordingError,
    RecordingOpenForWriteError,
    RecordingWriteError,
)
from imucalib.io._abandon import (
    WRITE_ERRORS,
    abandon_copy,
    failure_text,
    freed_object_failure,
    watch_freed_objects,
)
from imucalib.io._layout import column_compression
from imucalib.io._open import marked_open_for_write
from imucalib.io._schema import (
    COMMIT_GROUP,
    FORMAT_NAME,
    FORMAT_VERSION,
    LOG_CHUNK_ROWS,
    LOG_FIELDS,
    LOG_GROUP,
    LOG_LEVELS,
    STEP_STATUSES,
    STEPS_CHUNK_ROWS,
    STEPS_GROUP,
    STREAMS_GROUP,
    TRUTH_GROUP,
    TRUTH_STREAMS_GROUP,
    ColumnSpec,
    FieldSpec,
    column_json,
    decode_attr,
    decode_text,
    dtype_code,
    json_dumps,
    parse_string_list,
    step_fields,
)
from imucalib.io._seal import seal
from imucalib.io._tables import create_table
from imucalib.io._validate import H5PY_ERRORS, first_bad_time, from_h5py, parse_columns
from imucalib.io.compression import (
    COMPRESSIONS,
    DEFAULT_COMPRESSION,
    column_filter_kwargs,
    copy_filter_kwargs,
    needs_plugin,
)
from imucalib.io.opening import open_damaged, open_recording
from imucalib.io.reader import Recording

__all__ = ["RecoveredStream", "RecoveryReport", "compact_recording", "recover_recording",
           "stale_partial"]

_BLOCK_ROWS = 1 << 20
_T = TypeVar("_T")


@dataclass(frozen=True)
class RecoveredStream:
    """How much of one stream (or of ``steps`` / ``log``) was copied."""

    name: str  # e.g. "streams/imu/IMU-0001", "steps", "log"
    rows_copied: int
    rows_found: int  # length of the longest column in the original
    note: str = ""

    @property
    def rows_dropped(self) -> int:
        """Rows present in the original but not copied (uncommitted or unreadable)."""
        return self.rows_found - self.rows_copied


@dataclass(frozen=True)
class RecoveryReport:
    """The outcome of :func:`recover_recording`."""

    source: Path
    output: Path
    was_open_for_write: bool
    tables: tuple[RecoveredStream, ...]  # streams, truth streams, then "steps" and "log"
    unfinished_steps: tuple[int, ...]  # steps whose status was still "running"
    verified: bool
    damage: str = ""  # the first problem open_recording found in the original ("" for none)
    notes: tuple[str, ...] = ()  # what else was changed or left out (root, commit, truth)

    @property
    def streams(self) -> tuple[RecoveredStream, ...]:
        """The stream and truth-stream entries."""
        return tuple(t for t in self.tables if t.name not in (STEPS_GROUP, LOG_GROUP))

    @property
    def rows_dropped(self) -> int:
        """Rows dropped over all streams, steps and log."""
        return sum(t.rows_dropped for t in self.tables)

    def summary(self) -> str:
        """Render the report as plain text for people (the CLI prints it)."""
        state = ("was left open by its writer" if self.was_open_for_write
                 else "was closed cleanly (copied anyway)")
        lines = [f"recovered {self.source} -> {self.output}", f"  the original {state}"]
        if self.damage:  # without the file name and the advice to run recover
            detail = self.damage.split(" is damaged: ", 1)[-1].split("; run `imucalib", 1)[0]
            lines.append(f"  the original is damaged: {detail}")
        lines += [f"  {note}" for note in self.notes]
        width = max((len(t.name) for t in self.tables), default=10)
        for t in self.tables:
            line = f"  {t.name:<{width}}  {t.rows_copied:>12,} rows copied"
            if t.rows_dropped:
                line += f", {t.rows_dropped:,} dropped"
            if t.note:
                line += f" ({t.note})"
            lines.append(line)
        if self.unfinished_steps:
            lines.append("  step(s) still running when the writer stopped: "
                         + ", ".join(map(str, self.unfinished_steps)))
        lines.append("  verified: the copy opens normally and every column matches"
                     if self.verified else "  NOT verified")
        return "\n".join(lines)


def _refresh(ds: h5py.Dataset) -> h5py.Dataset:
    if ds.file.swmr_mode:
        ds.refresh()
    return ds


def _try(func: Callable[..., _T], *args: Any) -> tuple[_T | None, str]:
    """``(func(*args), "")``, or ``(None, what h5py said)`` when h5py fails."""
    try:
        return func(*args), ""
    except H5PY_ERRORS as exc:
        if not from_h5py(exc):
            raise
        return None, str(exc)


def _raw_attrs(obj: h5py.HLObject) -> dict[str, Any]:
    return dict(obj.attrs.items())


def _set_attrs(obj: h5py.HLObject, attrs: Mapping[str, Any],
               notes: list[str] | None = None) -> None:
    """Write `attrs` on `obj`; text that is not valid UTF-8 is mended (:func:`_valid_text`)."""
    for key, value in attrs.items():
        obj.attrs[key] = _valid_text(value, f"{obj.name} attribute `{key}`", notes)


def _valid_text(value: Any, where: str, notes: list[str] | None = None) -> Any:
    """Return `value` with text that is not valid UTF-8 made valid (a note in `notes`).

    h5py reads the undecodable bytes of a UTF-8 attribute as surrogate escapes, which no
    UTF-8 attribute can hold: each is replaced by U+FFFD (the rest of the text is kept).
    """
    if isinstance(value, np.ndarray) and value.dtype.kind == "O":
        fixed = [_valid_text(v, where, None) for v in value.tolist()]
        if any(a is not b for a, b in zip(fixed, value.tolist(), strict=True)):
            if notes is not None:
                notes.append(f"{where} is not valid UTF-8: undecodable bytes replaced by U+FFFD")
            return np.array(fixed, dtype=value.dtype).reshape(value.shape)
        return value
    if not isinstance(value, str):
        return value
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        if notes is not None:
            notes.append(f"{where} is not valid UTF-8: undecodable bytes replaced by U+FFFD")
        return value.encode("utf-8", "surrogateescape").decode("utf-8", "replace")
    return value


def _like(dst: h5py.Group, name: str, src: h5py.Dataset, n: int, attrs: Mapping[str, Any],
          filters: dict[str, Any] | None) -> h5py.Dataset:
    """Create a dataset like `src` (chunks, dtype, fill) with `filters` (None: those of `src`)."""
    out = dst.create_dataset(
        name, shape=(n,), maxshape=(None,), chunks=src.chunks, dtype=src.dtype,
        fillvalue=src.fillvalue, **(copy_filter_kwargs(src) if filters is None else filters))
    _set_attrs(out, attrs)
    return out


class _Copier:
    """Copies what is valid of an opened (possibly damaged) Recording into a new file."""

    def __init__(self, rec: Recording, dst: h5py.File, *, filters: dict[str, Any] | None = None,
                 recovered: bool = True) -> None:
        self.src: h5py.File = rec._file
        self.dst = dst
        self.filters = filters  # of the stream columns; None: as in the original
        self.recovered = recovered  # stamp recovered_from / recovered_utc
        self.path = rec.path
        self.version = int(rec.format_version)
        self.hashes: dict[str, str] = {}
        self.notes: list[str] = []
        self.tables: list[RecoveredStream] = []
        self.unfinished: tuple[int, ...] = ()
        self.committed = self._commit_counts()

    # ------------------------------------------------------------------ pieces
    def _commit_counts(self) -> dict[str, int]:
        """Return the trustworthy commit counts (non-negative ints of a readable /commit)."""
        group, err = _try(self.src.get, COMMIT_GROUP)
        if not isinstance(group, h5py.Group):
            self.notes.append(f"/commit unreadable or missing ({err or 'absent'}): every "
                              "column's rows were taken as written")
            return {}
        try:
            entries = json.loads(decode_attr(group.attrs["entries_json"]))
            rows = _refresh(group["rows"])[()].tolist()
        except (*H5PY_ERRORS, ValueError) as exc:
            self.notes.append(f"/commit unreadable ({exc}): every column's rows were taken as "
                              "written")
            return {}
        if (not isinstance(entries, list) or not isinstance(rows, list)
                or len(entries) != len(rows)):
            self.notes.append("/commit counts do not match its entries: every column's rows "
                              "were taken as written")
            return {}
        out = {}
        for entry, n in zip(entries, rows, strict=True):
            if isinstance(entry, str) and isinstance(n, int) and n >= 0:
                out[entry] = n
            else:
                self.notes.append(f"/commit count {n!r} of {entry!r} is invalid: its rows were "
                                  "taken as written")
        return out

    def root(self) -> None:
        attrs, err = _try(_raw_attrs, self.src)
        if attrs is None:
            self.notes.append(f"root attributes unreadable ({err}): only format and "
                              "format_version were written")
            attrs = {}
        _set_attrs(self.dst, attrs, self.notes)
        self.dst.attrs["format"] = FORMAT_NAME
        self.dst.attrs["format_version"] = np.int64(min(self.version, FORMAT_VERSION))
        if self.recovered:
            self.dst.attrs["recovered_from"] = str(self.path.name)
            self.dst.attrs["recovered_utc"] = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")

    def truth(self) -> None:
        group, err = _try(self.src.get, TRUTH_GROUP)
        if group is None and not err:
            return
        if not isinstance(group, h5py.Group):
            self.notes.append(f"/truth unreadable ({err or 'not a group'}): not copied")
            return
        tg = self.dst.require_group(TRUTH_GROUP)
        attrs, err = _try(_raw_attrs, group)
        for key, value in (attrs or {}).items():
            value = _valid_text(value, f"/truth attribute `{key}`", self.notes)
            if key.endswith("_json"):
                try:
                    json.loads(decode_attr(value))
                except (TypeError, ValueError):
                    self.notes.append(f"/truth `{key}` is not JSON: not copied")
                    continue
            tg.attrs[key] = value
        if err:
            self.notes.append(f"/truth attributes unreadable ({err}): not copied")
        arrays, err = _try(group.get, "arrays")
        if isinstance(arrays, h5py.Group):
            ag = tg.require_group("arrays")
            for key in _try(list, arrays)[0] or []:
                value, err = _try(lambda k=key: arrays[k][()])
                if value is None:
                    self.notes.append(f"/truth/arrays/{key} unreadable ({err}): not copied")
                else:
                    ag.create_dataset(key, data=value)
        self.dst.require_group(TRUTH_STREAMS_GROUP)

    def streams(self) -> None:
        self.dst.require_group(STREAMS_GROUP)
        for base in (STREAMS_GROUP, TRUTH_STREAMS_GROUP):
            group, err = _try(self.src.get, base)
            if not isinstance(group, h5py.Group):
                if base == STREAMS_GROUP or err:
                    self.notes.append(f"/{base} unreadable ({err}): no streams copied" if err
                                      else f"/{base} missing in the original: no streams copied")
                continue
            devices, err = _try(lambda g=group: sorted(g))
            if devices is None:
                self.notes.append(f"/{base} unreadable ({err}): no streams copied")
            for dev in devices or []:
                units, err = _try(lambda g=group, d=dev: sorted(g[d]))
                if units is None:
                    self.notes.append(f"/{base}/{dev} unreadable ({err}): its streams were not "
                                      "copied")
                for unit in units or []:
                    self.tables.append(self._stream(f"{base}/{dev}/{unit}"))

    def _columns(self, group: h5py.Group, path: str, attrs: dict[str, Any]
                 ) -> tuple[dict[str, ColumnSpec] | None, str]:
        """Return the columns from ``columns_json``, or rebuilt from the datasets' units."""
        try:
            return parse_columns(self.path, path, decode_attr(attrs.get("columns_json"))), ""
        except RecordingCorruptError:
            pass
        names: list[str] | None = _try(list, group)[0]
        cols: dict[str, ColumnSpec] = {}
        for name in sorted(names or [], key=lambda c: c != TIME_COLUMN):
            ds, _ = _try(group.get, name)
            if not isinstance(ds, h5py.Dataset):
                return None, f"its columns_json is damaged and {name} is not a column"
            a, _ = _try(_raw_attrs, ds)
            if a is None or not isinstance(decode_attr(a.get("unit")), str):
                return None, "its columns_json is damaged and its columns carry no units"
            scale = decode_attr(a.get("scale"))
            if scale is not None and not (isinstance(scale, float) and math.isfinite(scale)
                                          and scale > 0 and ds.dtype.kind in "iu"):
                return None, f"its columns_json is damaged and {name} has a bad scale"
            cols[name] = ColumnSpec(decode_attr(a["unit"]), dtype_code(ds.dtype),
                                    str(decode_attr(a.get("quantity", "si"))),
                                    str(decode_attr(a.get("description", ""))), scale)
        if TIME_COLUMN not in cols:
            return None, "its columns_json is damaged and it has no time_s"
        return cols, "columns_json rebuilt from the datasets"

    def _stream(self, path: str) -> RecoveredStream:
        group, err = _try(self.src.__getitem__, path)
        attrs, err2 = _try(_raw_attrs, group) if group is not None else (None, err)
        if not isinstance(group, h5py.Group) or attrs is None:
            return RecoveredStream(path, 0, 0, f"unreadable ({err or err2 or 'not a group'}): "
                                               "not copied")
        cols, note = self._columns(group, path, attrs)
        if cols is None:
            return RecoveredStream(path, 0, 0, f"{note}: not copied")
        notes = [note] if note else []
        present: list[str] = _try(list, group)[0] or []
        undeclared = sorted(set(present) - set(cols))
        if undeclared:
            notes.append(f"{', '.join(undeclared)} not declared in columns_json: not copied")
        dsets: dict[str, h5py.Dataset] = {}
        for name, spec in cols.items():
            ds, err = _try(lambda c=name: _refresh(group[c]))
            if (not isinstance(ds, h5py.Dataset) or ds.ndim != 1
                    or dtype_code(ds.dtype) != spec.dtype):
                if name == TIME_COLUMN:
                    return RecoveredStream(path, 0, 0, "time_s unreadable: not copied")
                notes.append(f"column {name} unreadable or of another dtype: dropped")
                continue
            dsets[name] = ds
        lengths = [d.shape[0] for d in dsets.values()]
        found, n = max(lengths), min(lengths)
        committed = self.committed.get(path)
        if committed is not None and committed < n:
            n = committed
            if found > n:
                notes.append("rows after the last flush")
        bad, err = _try(first_bad_time, dsets[TIME_COLUMN], n)
        if err:
            n, bad = 0, None
            notes.append(f"time_s unreadable ({err}): no rows copied")
        if bad is not None:
            n = bad[0]
            notes.append(f"rows from {n} dropped: time_s row {n} {bad[1]}")
        kept = {c: s for c, s in cols.items() if c in dsets}
        device, unit = path.rsplit("/", 2)[-2:]
        attrs.update(device=device, unit=unit, columns_json=json_dumps(
            [column_json(c, s) for c, s in kept.items()], "columns"))
        return self._copy_columns(path, attrs, dsets, kept, n, found, notes)

    def _copy_columns(self, path: str, attrs: dict[str, Any], dsets: dict[str, h5py.Dataset],
                      cols: dict[str, ColumnSpec], n: int, found: int, notes: list[str]
                      ) -> RecoveredStream:
        """Copy rows ``[0, n)`` of the aligned columns `dsets`, block by block, with hashes."""
        dst = self.dst.require_group(path)
        _set_attrs(dst, attrs, notes)
        outs = {}
        for c, d in dsets.items():
            col_attrs, _ = _try(_raw_attrs, d)
            spec = cols[c]
            outs[c] = _like(dst, c, d, n, col_attrs if col_attrs is not None else {
                "unit": spec.unit, "quantity": spec.quantity, "description": spec.description},
                self.filters)
        digests = {c: hashlib.sha256() for c in dsets}
        copied = n
        for a in range(0, n, _BLOCK_ROWS):
            b = min(a + _BLOCK_ROWS, n)
            blocks, err = _try(lambda a=a, b=b: {c: d[a:b] for c, d in dsets.items()})
            if blocks is None:
                copied = a
                notes.append(f"rows from {a} unreadable: {err}")
                break
            for c, blk in blocks.items():
                outs[c][a:b] = blk
                digests[c].update(np.ascontiguousarray(blk).tobytes())
        if copied < n:
            for out in outs.values():
                out.resize((copied,))
        for c, h in digests.items():
            self.hashes[f"{path}/{c}"] = h.hexdigest()
        return RecoveredStream(path, copied, found, "; ".join(notes))

    def table(self, name: str, fields: Mapping[str, FieldSpec]
              ) -> tuple[dict[str, NDArray[Any]], int, list[str]]:
        """Read the rows of ``/steps`` or ``/log`` (missing fields get empty values).

        Returns the columns, the length of the longest field, and notes.
        """
        group, err = _try(self.src.get, name)
        notes = []
        if isinstance(group, h5py.Group):
            err = _try(list, group)[1]  # a damaged link table fails here, not field by field
        if not isinstance(group, h5py.Group) or err:
            notes.append(f"unreadable in the original ({err}): written empty" if err
                         else "missing in the original: written empty")
            group = None
        dsets: dict[str, h5py.Dataset] = {}
        for field, spec in fields.items():
            ds = _try(group.get, field)[0] if group is not None else None
            kind = "S" if spec.kind == "text" else spec.kind[0]
            if isinstance(ds, h5py.Dataset) and ds.ndim == 1 and ds.dtype.kind == kind:
                dsets[field] = _refresh(ds)
            elif group is not None:
                notes.append(f"field {field} missing or unreadable: filled with empty values")
        lengths = [d.shape[0] for d in dsets.values()]
        found, n = max(lengths, default=0), min(lengths, default=0)
        committed = self.committed.get(name)
        if committed is not None and committed < n:
            n = committed
            if found > n:
                notes.append("rows after the last flush")
        data: dict[str, NDArray[Any]] = {}
        for field, spec in fields.items():
            values = _try(lambda f=field: dsets[f][:n])[0] if field in dsets else None
            if values is None:
                if field in dsets:
                    notes.append(f"field {field} unreadable: filled with empty values")
                values = (np.full(n, b"", dtype=spec.dtype) if spec.kind == "text"
                          else np.full(n, np.nan) if spec.kind == "f8" else np.arange(n))
            data[field] = np.asarray(values, dtype=spec.dtype)
        return data, found, notes

    def write_table(self, name: str, fields: Mapping[str, FieldSpec], chunk_rows: int,
                    data: dict[str, NDArray[Any]], found: int, notes: list[str]) -> None:
        """Write a repaired ``/steps`` or ``/log`` table and remember its hashes."""
        group = self.dst.create_group(name)
        create_table(group, fields, chunk_rows)
        n = len(next(iter(data.values())))
        for field, values in data.items():
            group[field].resize((n,))
            group[field][:] = values
            self.hashes[f"{name}/{field}"] = hashlib.sha256(
                np.ascontiguousarray(group[field][:]).tobytes()).hexdigest()
        self.tables.append(RecoveredStream(name, n, max(found, n), "; ".join(notes)))

    def steps(self) -> None:
        fields = step_fields(self.version)
        data, found, notes = self.table(STEPS_GROUP, fields)
        notes += _repair_steps(data)
        self.unfinished = tuple(int(i) for i in np.flatnonzero(data["status"] == b"running"))
        self.write_table(STEPS_GROUP, fields, STEPS_CHUNK_ROWS, data, found, notes)

    def log(self) -> None:
        data, found, notes = self.table(LOG_GROUP, LOG_FIELDS)
        levels = np.array([decode_text(v) in LOG_LEVELS for v in data["level"].tolist()],
                          dtype=bool)
        keep = np.isfinite(data["time_s"]) & levels
        if not keep.all():
            notes.append(f"{int((~keep).sum())} event(s) with an unknown level or a non-finite "
                         "time dropped")
            data = {k: v[keep] for k, v in data.items()}
        self.write_table(LOG_GROUP, LOG_FIELDS, LOG_CHUNK_ROWS, data, found, notes)

    def commit(self) -> None:
        entries = [t.name for t in self.tables if t.name in (STEPS_GROUP, LOG_GROUP)
                   or t.name in self.dst]
        copied = {t.name: t.rows_copied for t in self.tables}
        cg = self.dst.create_group(COMMIT_GROUP)
        cg.attrs["entries_json"] = json_dumps(entries, "commit entries")
        cg.create_dataset("rows", data=np.array([copied[e] for e in entries], dtype=np.int64))


def _repair_steps(data: dict[str, NDArray[Any]]) -> list[str]:
    """Make the steps valid in place: numbering, statuses, commanded JSON, infinite times."""
    notes = []
    n = data["index"].shape[0]
    if not np.array_equal(data["index"], np.arange(n)):
        data["index"] = np.arange(n, dtype=np.int64)
        notes.append("step numbers rewritten as 0, 1, 2, …")
    for i in range(n):
        status = decode_text(data["status"][i])
        if status not in STEP_STATUSES:
            data["status"][i] = b"invalid"
            notes.append(f"step {i} status {status!r} unknown: set to 'invalid'")
        cmd = decode_text(data["commanded"][i])
        if cmd:
            try:
                json.loads(cmd)
            except ValueError:
                data["commanded"][i] = b""
                notes.append(f"step {i} commanded state not JSON: cleared")
        for field in ("tags", "units"):
            if field not in data:
                continue
            try:
                parse_string_list(decode_text(data[field][i]))
            except ValueError:
                data[field][i] = b""
                notes.append(f"step {i} {field} not a JSON list of strings: cleared")
    for field in ("t_start_s", "t_end_s", "valid_start_s", "valid_end_s"):
        inf = np.isinf(data[field])
        if inf.any():
            data[field][inf] = np.nan
            notes.append(f"{int(inf.sum())} infinite {field} set to NaN")
    return notes


def _check_recognizable(rec: Recording) -> None:
    """Refuse a file whose root attributes are unreadable unless its groups are a recording's."""
    fmt, err = _try(lambda: rec._file.attrs.get("format"))
    if not err and decode_attr(fmt) == FORMAT_NAME:
        return
    groups = [g for g in (STREAMS_GROUP, STEPS_GROUP, LOG_GROUP, COMMIT_GROUP)
              if isinstance(_try(rec._file.get, g)[0], h5py.Group)]
    if STREAMS_GROUP not in groups or len(groups) < 3:
        raise RecordingCorruptError(
            f"{rec.path} is damaged beyond recovery: its root attributes are unreadable "
            f"({err or 'no format'}) and the groups of a recording (/streams and two of /steps, "
            f"/log, /commit) are not readable either (found {groups}); restore it from a copy")


def _copy(rec: Recording, dst: h5py.File, *, filters: dict[str, Any] | None = None,
          recovered: bool = True) -> _Copier:
    copier = _Copier(rec, dst, filters=filters, recovered=recovered)
    copier.root()
    copier.truth()
    copier.streams()
    copier.steps()
    copier.log()
    copier.commit()
    return copier


def _verify(path: Path, tables: list[RecoveredStream], hashes: dict[str, str]) -> None:
    with open_recording(path, strict=True) as rec:
        f = rec._file
        committed = rec.committed_rows()
        for t in tables:
            if committed.get(t.name, t.rows_copied) != t.rows_copied:
                raise RecordingError(f"verification of {path} failed: {t.name} commits "
                                     f"{committed.get(t.name)} rows, {t.rows_copied} were copied")
        for key, digest in hashes.items():
            ds = f[key]
            h = hashlib.sha256()
            for a in range(0, ds.shape[0], _BLOCK_ROWS):
                h.update(np.ascontiguousarray(ds[a:a + _BLOCK_ROWS]).tobytes())
            if h.hexdigest() != digest:
                raise RecordingError(f"verification of {path} failed: {key} differs from the "
                                     "original")
        rec.streams  # noqa: B018 -- every stream must describe itself
        rec.steps  # noqa: B018
        rec.log  # noqa: B018


def _write_copy(tmp: Path, what: str, fill: Callable[[h5py.File], _T]) -> _T:
    """Create the HDF5 file `tmp`, fill it with ``fill(file)`` and close it; return its result.

    Raises
    ------
    RecordingWriteError
        When HDF5 fails to create, write or close `tmp` (``what failed: ...``): `tmp` is
        removed, and an h5py file of it is abandoned (:mod:`imucalib.io._abandon`), never
        closed, so that the process can end without crashing.
    """
    watch_freed_objects()
    try:
        dst = h5py.File(tmp, "w", libver="latest")
    except OSError as exc:
        _remove(tmp)
        raise RecordingWriteError(f"{what} failed: HDF5 could not create {tmp.name}: "
                                  f"{failure_text(exc)}") from exc
    try:
        result = fill(dst)
    except WRITE_ERRORS as exc:
        raise _abandoned(tmp, what, exc, dst) from exc
    except BaseException:
        _close_copy(tmp, what, dst)
        _remove(tmp)
        raise
    _close_copy(tmp, what, dst)
    return result


def _close_copy(tmp: Path, what: str, dst: h5py.File) -> None:
    """Close a copy: h5py closes its datasets and groups, then the file (abandoned on failure)."""
    try:
        freed = freed_object_failure(tmp)  # HDF5 may crash flushing a file it failed to write
        if freed is not None:
            raise RuntimeError(str(freed)) from freed
        dst.close()
    except WRITE_ERRORS as exc:
        raise _abandoned(tmp, what, exc, dst) from exc


def _abandoned(tmp: Path, what: str, exc: BaseException, dst: h5py.File) -> RecordingWriteError:
    """Abandon the copy `tmp` after a failed write; return the error to raise."""
    reason = abandon_copy(tmp, what, exc, dst)
    return RecordingWriteError(f"{what} failed: HDF5 could not write {tmp.name}: {reason}")


def _remove(path: Path) -> None:
    """Remove a temporary file, quietly when the file system fails too."""
    try:
        path.unlink(missing_ok=True)
    except OSError:
        pass


def stale_partial(path: str | os.PathLike[str]) -> Path:
    """Return the name of the partial copy a compaction of `path` writes (it may not exist).

    A process killed while it compacted a Recording leaves it beside the file; no reader opens
    it, and the next compaction of the file (``imucalib run --resume FILE``, ``imucalib compact
    FILE``) or a recovery of it (``imucalib recover FILE``) removes it.
    """
    p = Path(path)
    return p.with_name(f".{p.name}.compact.partial")


def recover_recording(path: str | os.PathLike[str], out_path: str | os.PathLike[str] | None = None,
                      *, overwrite: bool = False,
                      compression: str | None = DEFAULT_COMPRESSION) -> RecoveryReport:
    """Copy everything readable of a Recording into a new, cleanly closed file.

    Parameters
    ----------
    path : str or Path
        The Recording, typically one a crashed writer left open. It is only read.
    out_path : str or Path, optional
        Where to write the copy; default ``<stem>.recovered.h5`` beside `path`.
    overwrite : bool
        Replace an existing `out_path`.
    compression : str or None
        Compression of the copy's stream columns (:data:`~imucalib.io.compression.COMPRESSIONS`;
        the copy is written once, so it can be compressed without the cost SWMR appends have).
        A file of format version 1 or 2 keeps its own filters instead of a Blosc compression,
        which the readers of its version lack.

    Returns
    -------
    RecoveryReport
        Rows copied and dropped per stream, unfinished steps, verification; ``summary()``
        renders it.

    Raises
    ------
    InvalidInputError
        If `out_path` is `path` itself.
    RecordingError
        If `out_path` exists (and not `overwrite`), or the copy fails verification.
    RecordingFormatError, RecordingCorruptError
        If the original cannot be read at all (see :func:`~imucalib.io.opening.open_recording`).
    """
    src = Path(path)
    out = Path(out_path) if out_path is not None else src.with_name(f"{src.stem}.recovered.h5")
    if out.resolve() == src.resolve():
        raise InvalidInputError(f"`out_path` must differ from the original {src}; the original "
                                "is never modified")
    if out.exists() and not overwrite:
        raise RecordingError(f"{out} exists; choose another output path or remove it first")
    if compression not in COMPRESSIONS:
        raise InvalidInputError(f"`compression` must be one of {COMPRESSIONS}; "
                                f"got {compression!r}")
    tmp = out.with_name(f".{out.name}.partial")
    rec, damage = open_damaged(src)
    with rec:
        was_open = rec.was_open_for_write
        _check_recognizable(rec)
        try:
            # a file of version 1 or 2 keeps its own filters rather than gain Blosc, which its
            # readers lack (Blosc came with version 3)
            keep = needs_plugin(compression) and rec.format_version < FORMAT_VERSION
            filters = None if keep else column_filter_kwargs(compression)
            copier = _write_copy(tmp, f"recovering {src} (the original is unchanged)",
                                 lambda dst: _copy(rec, dst, filters=filters))
            _verify(tmp, copier.tables, copier.hashes)
            seal(tmp)  # validated: later opens skip the probe while its metadata is unchanged
            os.replace(tmp, out)
        except OSError as exc:
            tmp.unlink(missing_ok=True)
            raise RecordingCorruptError(f"recovering {src} failed: {exc}") from exc
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
    _remove(stale_partial(src))  # a compaction of the original was killed: its copy is junk
    return RecoveryReport(source=src, output=out, was_open_for_write=was_open,
                          tables=tuple(copier.tables), unfinished_steps=copier.unfinished,
                          verified=True, damage=str(damage) if damage is not None else "",
                          notes=tuple(copier.notes))


def compact_recording(path: str | os.PathLike[str], compression: str | None) -> str | None:
    """Rewrite a cleanly closed Recording in place with another compression of its columns.

    The copy holds what every reader of the file sees: each stream's committed rows (rows a
    column holds past its commit count, which no reader shows, are not copied), the steps, the
    log, the attributes and the truth.

    The copy is written beside the original (``.<name>.compact.partial``), checked as
    :func:`recover_recording` checks its copies (every check of
    :func:`~imucalib.io.opening.open_recording`, every column's SHA-256), and only then
    replaces the original (:func:`os.replace`, atomic on POSIX filesystems). A process killed
    before that leaves the original untouched (and the partial file behind). This is how a
    :class:`~imucalib.io.recording.RecordingWriter` compresses a file when it closes it, and
    uncompresses one it reopens: under SWMR HDF5 never reuses the space of a rewritten chunk,
    and a compressed chunk is rewritten (in a new place) at every flush until it is full
    (``docs/recording-format.md``, *Size and compression*).

    Parameters
    ----------
    path : str or Path
        A cleanly closed Recording.
    compression : str or None
        One of :data:`~imucalib.io.compression.COMPRESSIONS`. A Blosc compression makes a
        file of format version 2 version 3 (what a writer stamps on a Blosc file: the readers
        of version 2 lack the filter) and is refused for a file of version 1.

    Returns
    -------
    str or None
        The compression the file had (:func:`~imucalib.io.compression.compression_of` of its
        first filtered column; None: uncompressed).

    Raises
    ------
    InvalidInputError
        For an unknown compression, or Blosc for a file of format version 1.
    RecordingOpenForWriteError, RecordingFormatError, RecordingCorruptError
        If the file is not a cleanly closed, valid Recording (it is then not touched).
    RecordingError
        If the copy would differ from the original in anything (it is then not touched).
    """
    if compression not in COMPRESSIONS:
        raise InvalidInputError(f"`compression` must be one of {COMPRESSIONS}; "
                                f"got {compression!r}")
    src = Path(path)
    if src.is_file() and marked_open_for_write(src):
        raise RecordingOpenForWriteError(
            f"{src} is open for write (a writer holds it, or one was stopped): it can be "
            "compacted once closed; `imucalib recover FILE` copies out a stopped writer's file")
    tmp = stale_partial(src)
    try:
        with open_recording(src, strict=True) as rec:
            visible = rec.committed_rows()  # rows past a commit count are shown to no reader
            had = column_compression(rec._file)[1]
            stamp = needs_plugin(compression) and rec.format_version < FORMAT_VERSION
            if stamp and rec.format_version < 2:
                raise InvalidInputError(
                    f"{src} is of format version {rec.format_version}, whose step fields "
                    f"predate the Blosc filter (format version {FORMAT_VERSION}): compress it "
                    "with 'gzip', 'lzf' or none")
            filters = column_filter_kwargs(compression)

            def fill(dst: h5py.File) -> _Copier:
                copier = _copy(rec, dst, filters=filters, recovered=False)
                if stamp:  # version 2 readers lack the Blosc filter: they must refuse it
                    dst.attrs["format_version"] = np.int64(FORMAT_VERSION)
                return copier

            copier = _write_copy(tmp, f"compacting {src} (the file is unchanged)", fill)
        changed = [f"{t.name}: {t.rows_copied} of {visible.get(t.name)} rows ({t.note})"
                   for t in copier.tables if t.rows_copied != visible.get(t.name)]
        if copier.notes or changed:
            raise RecordingError(
                f"compacting {src} stopped, the file is unchanged: the copy would differ "
                f"({'; '.join(copier.notes + changed)})")
        _verify(tmp, copier.tables, copier.hashes)
        seal(tmp)  # validated: later opens skip the probe while its metadata is unchanged
        os.replace(tmp, src)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise RecordingError(f"compacting {src} failed, the file is unchanged: {exc}") from exc
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return had
