"""Validate a Recording when it is opened (private): layout, commit counts, tables, time bases.

:func:`check_layout` reads every piece of structure the reader relies on and raises a typed
error, one line naming the file, what was found and what was expected, at the first problem:

- root attributes ``format`` (str) and ``format_version`` (int, supported);
- the groups ``/streams``, ``/steps``, ``/log`` and ``/commit``;
- ``/commit``: ``entries_json`` a JSON list of distinct names, one non-negative integer count per
  entry in ``rows``, every entry an existing stream, ``steps`` or ``log``, every stream counted;
- each stream group (``/streams`` and ``/truth/streams``): ``columns_json`` a JSON list of
  column specifications, ``time_s`` first, one 1-D dataset per column of the declared dtype and
  nothing else, every column holding at least the committed rows;
- ``/steps`` and ``/log``: every field present as a 1-D dataset of the right kind holding the
  committed rows (the step fields of the file's format version); in the committed rows, steps
  numbered 0, 1, 2, …, known statuses, ``commanded`` empty or JSON, ``tags`` and ``units``
  (version 2) empty or JSON lists of strings, step times finite or NaN; known log levels and
  finite log times;
- ``/truth``: ``*_json`` attributes that decode.

:func:`check_time_bases` then reads each stream's committed ``time_s`` in blocks (no more than
:data:`TIME_BLOCK_ROWS` rows in memory) and checks that it is finite, never decreases, and lies in
``[0, MAX_TIME_S]``. :func:`touch_all` reads every attribute and dataset header of a file, so that
a forked probe (:mod:`imucalib.io._probe`) meets any metadata that makes HDF5 hang or crash
before the reader or recovery does.

Every exception h5py raises while doing so (``OSError``, ``KeyError``, ``RuntimeError``,
``ValueError``, ``TypeError``, ``IndexError``) becomes :class:`RecordingCorruptError`.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, TypeVar

import h5py
import numpy as np
from numpy.typing import NDArray

from imucalib import __version__
from imucalib.conventions import TIME_COLUMN
from imucalib.errors import RecordingCorruptError, RecordingFormatError
from imucalib.io._schema import (
    COMMIT_GROUP,
    FORMAT_NAME,
    FORMAT_VERSION,
    LOG_FIELDS,
    LOG_GROUP,
    LOG_LEVELS,
    QUANTITIES,
    STEP_STATUSES,
    STEPS_GROUP,
    STREAMS_GROUP,
    TRUTH_GROUP,
    TRUTH_STREAMS_GROUP,
    ColumnSpec,
    FieldSpec,
    decode_attr,
    decode_text,
    dtype_code,
    parse_string_list,
    step_fields,
)

__all__ = [
    "H5PY_ERRORS",
    "MAX_TIME_S",
    "REQUIRED_GROUPS",
    "TIME_BLOCK_ROWS",
    "Layout",
    "StreamLayout",
    "check_layout",
    "check_root",
    "check_time_bases",
    "damaged",
    "first_bad_time",
    "from_h5py",
    "h5call",
    "parse_columns",
    "touch_all",
]

_T = TypeVar("_T")

#: Latest plausible time stamp [s] (31.7 years after the start of a run).
MAX_TIME_S: Final = 1e9
#: Rows of ``time_s`` read at once by the time-base check (8 MiB of float64).
TIME_BLOCK_ROWS: Final = 1 << 20
#: The groups every Recording has.
REQUIRED_GROUPS: Final = (STREAMS_GROUP, STEPS_GROUP, LOG_GROUP, COMMIT_GROUP)
#: The exception types h5py raises for unreadable files and objects.
H5PY_ERRORS: Final = (OSError, LookupError, RuntimeError, ValueError, TypeError)

_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.\-]{0,63}$")
_COLUMN_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,62}$")
_H5PY_DIR = os.path.dirname(h5py.__file__)
_MAX_TEXT = "1e9"  # MAX_TIME_S in messages
_MAX_DEPTH = 8  # deeper than any Recording (truth/streams/<device>/<unit>/<column> is 5)


@dataclass(frozen=True)
class StreamLayout:
    """One validated stream (or truth stream): its group, columns and committed rows."""

    path: str  # "streams/<device>/<unit>" or "truth/streams/<device>/<unit>"
    device: str
    unit: str
    columns: dict[str, ColumnSpec]
    committed: int

    @property
    def label(self) -> str:
        """``"stream imu/IMU-0001"`` or ``"truth stream imu/IMU-0001"``, for messages."""
        kind = "truth stream" if self.path.startswith(TRUTH_STREAMS_GROUP + "/") else "stream"
        return f"{kind} {self.device}/{self.unit}"


@dataclass(frozen=True)
class Layout:
    """What :func:`check_layout` found valid (plain data: it travels back from a probe)."""

    format_version: int
    commit_entries: tuple[str, ...]
    committed: dict[str, int]
    streams: tuple[StreamLayout, ...]  # streams, then truth streams


# ----------------------------------------------------------------------------- errors
def damaged(p: Path, detail: str, remedy: str = "to copy out what is valid"
            ) -> RecordingCorruptError:
    """Make the error for a damaged file: ``<p> is damaged: <detail>; run `imucalib recover …```."""
    return RecordingCorruptError(f"{p} is damaged: {detail}; run `imucalib recover {p}` {remedy}")


def from_h5py(exc: BaseException) -> bool:
    """Whether `exc` is an ``OSError`` or was raised inside h5py (not by imucalib's own code)."""
    if isinstance(exc, OSError):
        return True
    tb = exc.__traceback__
    while tb is not None:
        name = tb.tb_frame.f_code.co_filename
        if name.startswith(_H5PY_DIR) or name.startswith("h5py/"):
            return True
        tb = tb.tb_next
    return False


def h5call(p: Path, what: str, func: Callable[..., _T], *args: Any) -> _T:
    """Call ``func(*args)``; an h5py failure becomes :class:`RecordingCorruptError` on `what`."""
    try:
        return func(*args)
    except H5PY_ERRORS as exc:
        if not from_h5py(exc):
            raise
        raise damaged(p, f"HDF5 cannot read {what} ({exc})",
                      "to copy out what is readable") from exc


def _attrs(obj: h5py.HLObject) -> dict[str, Any]:
    return {k: decode_attr(v) for k, v in obj.attrs.items()}


def _some_attrs(obj: h5py.HLObject, names: tuple[str, ...]) -> dict[str, Any]:
    """Read the attributes `names` that `obj` has (far cheaper than reading all of them)."""
    attrs = obj.attrs
    return {k: decode_attr(attrs[k]) for k in names if k in attrs}


def _json(p: Path, text: Any, what: str, expected: str) -> Any:
    if not isinstance(text, str):
        raise damaged(p, f"{what} is {type(text).__name__} {text!r}; expected {expected}")
    try:
        return json.loads(text)
    except ValueError as exc:
        raise damaged(p, f"{what} is not JSON ({_short(text)}: {exc}); expected {expected}"
                      ) from exc


def _short(text: str, n: int = 40) -> str:
    return repr(text if len(text) <= n else text[:n] + "…")


# ----------------------------------------------------------------------------- root, groups
def check_root(p: Path, f: h5py.File) -> int:
    """Check the root attributes ``format`` and ``format_version``; return the version.

    Raises
    ------
    RecordingFormatError
        No or another ``format``, or a ``format_version`` newer than this reader.
    RecordingCorruptError
        A missing or mistyped ``format_version``.
    """
    try:
        attrs = _some_attrs(f, ("format", "format_version"))
    except H5PY_ERRORS as exc:
        if not from_h5py(exc):
            raise
        try:
            readable = isinstance(f.get(STREAMS_GROUP), h5py.Group)
        except H5PY_ERRORS:
            readable = False
        if readable:  # recovery can still copy the streams
            raise damaged(p, f"HDF5 cannot read the root attributes ({exc})",
                          "to copy out what is readable") from exc
        raise RecordingCorruptError(
            f"{p} is damaged: HDF5 cannot read its root group ({exc}); neither imucalib nor "
            "`imucalib recover` can read this file: restore it from a copy") from exc
    fmt = attrs.get("format")
    if fmt is None:
        names = h5call(p, "the root attributes", lambda: sorted(f.attrs.keys())[:10])
        objs = h5call(p, "the root group", lambda: sorted(f.keys())[:10])
        raise RecordingFormatError(
            f"{p} is an HDF5 file but not an imucalib recording: its root has no `format` "
            f"attribute (found attributes {names} and objects {objs})")
    if fmt != FORMAT_NAME:
        raise RecordingFormatError(f"{p} is not an imucalib recording: its `format` attribute "
                                   f"is {fmt!r}, expected {FORMAT_NAME!r}")
    if "format_version" not in attrs:
        raise damaged(p, "its root has no `format_version` attribute; expected the int "
                         f"{FORMAT_VERSION}")
    raw = attrs["format_version"]
    if not isinstance(raw, int) or isinstance(raw, bool) or raw < 1:
        raise damaged(p, f"its `format_version` attribute is {type(raw).__name__} {raw!r}; "
                         "expected a positive int")
    if raw > FORMAT_VERSION:
        raise RecordingFormatError(
            f"{p} has format_version {raw}, newer than imucalib {__version__} reads "
            f"(up to {FORMAT_VERSION}); upgrade imucalib")
    return raw


_Links = dict[str, set[str]]  # the link names of each group listed so far, by path


def _child(p: Path, group: h5py.Group, name: str, path: str, links: _Links
           ) -> h5py.HLObject | None:
    """``group[name]``, or None if `group` has no such link (a damaged one raises instead).

    ``group.get`` would take an unreadable link table for a missing name; listing the links
    first tells the two apart. Each group is listed once (`links` remembers).
    """
    parent = path.rsplit("/", 1)[0] if "/" in path else ""
    names = links.get(parent)
    if names is None:
        names = links[parent] = h5call(p, f"/{parent}" if parent else "the root group", set,
                                       group)
    if name not in names:
        return None
    return h5call(p, f"/{path}", group.__getitem__, name)


def _group(p: Path, f: h5py.File, name: str, links: _Links) -> h5py.Group:
    obj = _child(p, f, name, name, links)
    if obj is None:
        raise damaged(p, f"the group /{name} is missing; expected the groups /streams, /steps, "
                         "/log and /commit of a recording")
    if not isinstance(obj, h5py.Group):
        raise damaged(p, f"/{name} is a {type(obj).__name__}; expected a group")
    return obj


def _commit(p: Path, f: h5py.File, links: _Links) -> tuple[tuple[str, ...], dict[str, int]]:
    group = _group(p, f, COMMIT_GROUP, links)
    attrs = h5call(p, "the attributes of /commit", _some_attrs, group, ("entries_json",))
    if "entries_json" not in attrs:
        raise damaged(p, "/commit has no `entries_json` attribute; expected the JSON list of "
                         "the entries it counts")
    entries = _json(p, attrs["entries_json"], "/commit `entries_json`",
                    "a JSON list of entry names")
    if (not isinstance(entries, list) or not all(isinstance(e, str) for e in entries)
            or len(set(entries)) != len(entries)):
        raise damaged(p, f"/commit `entries_json` is {_short(str(entries))}; expected a JSON "
                         "list of distinct entry names")
    ds = _child(p, group, "rows", "commit/rows", links)
    if not isinstance(ds, h5py.Dataset):
        raise damaged(p, "/commit/rows is missing; expected one row count per entry")
    if ds.ndim != 1 or ds.dtype.kind not in "iu":
        raise damaged(p, f"/commit/rows is {ds.dtype} of shape {ds.shape}; expected 1-D "
                         "integers")
    if group.file.swmr_mode:
        h5call(p, "/commit/rows", ds.refresh)
    rows = h5call(p, "/commit/rows", ds.__getitem__, ())
    if rows.shape[0] != len(entries):
        raise damaged(p, f"/commit/rows holds {rows.shape[0]} counts for {len(entries)} entries "
                         "in `entries_json`; expected one count per entry")
    counts: dict[str, int] = {}
    for entry, n in zip(entries, rows.tolist(), strict=True):
        if n < 0:
            raise damaged(p, f"/commit/rows counts {n} rows for {entry}; expected a count ≥ 0")
        counts[entry] = int(n)
    return tuple(entries), counts


# ----------------------------------------------------------------------------- streams
def _stream_paths(p: Path, f: h5py.File, base: str) -> list[str]:
    root = h5call(p, f"/{base}", f.__getitem__, base)
    paths = []
    for dev in h5call(p, f"/{base}", lambda: sorted(root)):
        d = h5call(p, f"/{base}/{dev}", root.__getitem__, dev)
        if not isinstance(d, h5py.Group) or not _NAME_RE.match(dev):
            raise damaged(p, f"/{base}/{dev} is not a device group; expected groups "
                             f"/{base}/<device>/<unit> only")
        for unit in h5call(p, f"/{base}/{dev}", lambda d=d: sorted(d)):
            u = h5call(p, f"/{base}/{dev}/{unit}", d.__getitem__, unit)
            if not isinstance(u, h5py.Group) or not _NAME_RE.match(unit):
                raise damaged(p, f"/{base}/{dev}/{unit} is not a stream group; expected groups "
                                 f"/{base}/<device>/<unit> only")
            paths.append(f"{base}/{dev}/{unit}")
    return paths


def parse_columns(p: Path, path: str, text: Any) -> dict[str, ColumnSpec]:
    """Decode and check a stream's ``columns_json`` (names, ``time_s`` first, dtypes)."""
    where = f"/{path} `columns_json`"
    specs = _json(p, text, where, "a JSON list of column specifications")
    if not isinstance(specs, list) or not specs:
        raise damaged(p, f"{where} is {_short(str(specs))}; expected a non-empty JSON list")
    cols: dict[str, ColumnSpec] = {}
    for i, c in enumerate(specs):
        keys = ("name", "unit", "dtype", "quantity", "description")
        if not isinstance(c, dict) or not all(isinstance(c.get(k), str) for k in keys):
            raise damaged(p, f"{where} item {i} is {_short(str(c))}; expected an object with "
                             f"the strings {list(keys)}")
        name = c["name"]
        if not _COLUMN_RE.match(name) or name in cols:
            raise damaged(p, f"{where} item {i} names the column {name!r}; expected a distinct "
                             "identifier")
        try:
            dt: np.dtype[Any] = np.dtype(c["dtype"])
        except TypeError:
            dt = np.dtype("O")
        if dt.kind not in "biuf" or c["quantity"] not in QUANTITIES or not c["unit"]:
            raise damaged(p, f"{where} column {name!r} has dtype {c['dtype']!r}, quantity "
                             f"{c['quantity']!r}, unit {c['unit']!r}; expected a numeric dtype, "
                             f"one of {list(QUANTITIES)} and a unit")
        scale = c.get("scale")
        if scale is not None and (isinstance(scale, bool) or not isinstance(scale, int | float)
                                  or not math.isfinite(scale) or scale <= 0 or dt.kind not in "iu"):
            raise damaged(p, f"{where} column {name!r} has scale {scale!r} with dtype "
                             f"{c['dtype']!r}; expected a positive finite number on an integer "
                             "column")
        cols[name] = ColumnSpec(unit=c["unit"], dtype=dtype_code(dt), quantity=c["quantity"],
                                description=c["description"],
                                scale=None if scale is None else float(scale))
    first = next(iter(cols))
    if first != TIME_COLUMN or cols[first].dtype != "f8":
        raise damaged(p, f"{where} starts with {first!r} ({cols[first].dtype}); expected "
                         "time_s (f8) first")
    return cols


def _stream(p: Path, f: h5py.File, path: str, committed: int) -> StreamLayout:
    group = h5call(p, f"/{path}", f.__getitem__, path)
    attrs = h5call(p, f"the attributes of /{path}", _some_attrs, group, ("columns_json",))
    device, unit = path.rsplit("/", 2)[-2:]
    if "columns_json" not in attrs:
        raise damaged(p, f"/{path} has no `columns_json` attribute; expected its column "
                         "specifications")
    cols = parse_columns(p, path, attrs["columns_json"])
    names = h5call(p, f"/{path}", lambda: list(group))
    extra = sorted(set(names) - set(cols))
    if extra:
        raise damaged(p, f"/{path} holds {extra}, which `columns_json` does not declare; "
                         f"expected the columns {list(cols)} only")
    swmr = f.swmr_mode
    for name, spec in cols.items():
        if name not in names:
            raise damaged(p, f"/{path}/{name} is missing; expected the columns {list(cols)} "
                             "that `columns_json` declares")
        ds = h5call(p, f"/{path}/{name}", group.__getitem__, name)
        if not isinstance(ds, h5py.Dataset) or len(ds.shape) != 1:
            raise damaged(p, f"/{path}/{name} is not a 1-D dataset; expected a column")
        if dtype_code(ds.dtype) != spec.dtype:
            raise damaged(p, f"/{path}/{name} holds {dtype_code(ds.dtype)}; expected "
                             f"{spec.dtype} as `columns_json` declares")
        if swmr and ds.shape[0] < committed:
            h5call(p, f"/{path}/{name}", ds.refresh)
        if ds.shape[0] < committed:
            raise damaged(p, f"/{path}/{name} holds {ds.shape[0]} rows but {committed} are "
                             "committed; expected every column to hold the committed rows")
    return StreamLayout(path, device, unit, cols, committed)


# ----------------------------------------------------------------------------- tables
def _table(p: Path, f: h5py.File, name: str, fields: Mapping[str, FieldSpec],
           committed: int, links: _Links, read: Collection[str] | None = None
           ) -> dict[str, NDArray[Any]]:
    """Check a table's fields (kind, shape, rows); return the committed rows of those `read`.

    `read` None: every field's.
    """
    group = _group(p, f, name, links)
    out: dict[str, NDArray[Any]] = {}
    for field, spec in fields.items():
        ds = _child(p, group, field, f"{name}/{field}", links)
        if ds is None:
            raise damaged(p, f"the field /{name}/{field} is missing; expected the fields "
                             f"{list(fields)}")
        kind = "S" if spec.kind == "text" else spec.kind[0]
        if not isinstance(ds, h5py.Dataset) or len(ds.shape) != 1 or ds.dtype.kind != kind:
            found = (f"{ds.dtype} of shape {ds.shape}" if isinstance(ds, h5py.Dataset)
                     else "a group")
            raise damaged(p, f"/{name}/{field} is {found}; expected a 1-D "
                             f"{'text' if kind == 'S' else spec.kind} dataset")
        if f.swmr_mode:
            h5call(p, f"/{name}/{field}", ds.refresh)
        if ds.shape[0] < committed:
            raise damaged(p, f"/{name}/{field} holds {ds.shape[0]} rows but {committed} are "
                             f"committed; expected every field of /{name} to hold them")
        if read is not None and field not in read:
            continue
        rows = () if ds.shape[0] == committed else slice(0, committed)  # () reads faster
        out[field] = h5call(p, f"/{name}/{field}", ds.__getitem__, rows)
    return out


def _check_steps(p: Path, t: dict[str, NDArray[Any]]) -> None:
    for i in range(t["index"].shape[0]):
        if int(t["index"][i]) != i:
            raise damaged(p, f"/steps/index row {i} is {int(t['index'][i])}; expected {i}")
        status = decode_text(t["status"][i])
        if status not in STEP_STATUSES:
            raise damaged(p, f"/steps/status row {i} is {_short(status)}; expected one of "
                             f"{list(STEP_STATUSES)}")
        cmd = decode_text(t["commanded"][i])
        if cmd:
            _json(p, cmd, f"/steps/commanded row {i}", "JSON text or an empty string")
        for field in ("tags", "units"):
            if field in t:
                text = decode_text(t[field][i])
                try:
                    parse_string_list(text)
                except ValueError:
                    raise damaged(p, f"/steps/{field} row {i} is {_short(text)}; expected a "
                                     "JSON list of strings or an empty string") from None
        for field in ("t_start_s", "t_end_s", "valid_start_s", "valid_end_s"):
            if math.isinf(float(t[field][i])):
                raise damaged(p, f"/steps/{field} row {i} is {float(t[field][i])}; expected a "
                                 "finite time or NaN")


def _check_log(p: Path, t: dict[str, NDArray[Any]]) -> None:
    bad = np.flatnonzero(~np.isfinite(t["time_s"]))
    if bad.size:
        i = int(bad[0])
        raise damaged(p, f"/log/time_s row {i} is {float(t['time_s'][i])}; expected a finite "
                         "time")
    for i, raw in enumerate(t["level"].tolist()):
        if decode_text(raw) not in LOG_LEVELS:
            raise damaged(p, f"/log/level row {i} is {_short(decode_text(raw))}; expected one "
                             f"of {list(LOG_LEVELS)}")


def _check_truth(p: Path, f: h5py.File, links: _Links) -> None:
    group = _child(p, f, TRUTH_GROUP, TRUTH_GROUP, links)
    if group is None:
        return
    if not isinstance(group, h5py.Group):
        raise damaged(p, "/truth is not a group; expected the digital-twin truth")
    for key, value in h5call(p, "the attributes of /truth", _attrs, group).items():
        if key.endswith("_json"):
            _json(p, value, f"/truth `{key}`", "JSON text")
    arrays = _child(p, group, "arrays", "truth/arrays", links)
    if arrays is not None:
        for key in h5call(p, "/truth/arrays", lambda: list(arrays)):
            ds = _child(p, arrays, key, f"truth/arrays/{key}", links)
            if not isinstance(ds, h5py.Dataset):
                raise damaged(p, f"/truth/arrays/{key} is not a dataset; expected an array")


# ----------------------------------------------------------------------------- whole file
#: The fields of /steps and /log whose rows a check looks into (:func:`_check_steps`,
#: :func:`_check_log`); a sealed file's other fields are not read (:func:`check_layout`).
_STEP_FIELDS_CHECKED: Final = frozenset({"index", "status", "commanded", "tags", "units",
                                         "t_start_s", "t_end_s", "valid_start_s",
                                         "valid_end_s"})
_LOG_FIELDS_CHECKED: Final = frozenset({"time_s", "level"})


def check_layout(p: Path, f: h5py.File, *, sealed: bool = False) -> Layout:
    """Validate everything but the time bases; return what the reader needs.

    With `sealed` (a file whose seal holds, :mod:`imucalib.io._seal`) the rows of the steps' and
    log's fields that no check looks into are not read: they were read soundly when the file
    was validated and sealed, and their bytes have not changed since.

    Raises
    ------
    RecordingFormatError
        Not an imucalib recording, or a newer format version.
    RecordingCorruptError
        The first problem found, naming the object, what it holds and what was expected.
    """
    version = check_root(p, f)
    links: _Links = {}
    for name in REQUIRED_GROUPS:
        _group(p, f, name, links)
    entries, committed = _commit(p, f, links)
    paths = _stream_paths(p, f, STREAMS_GROUP)
    truth = _child(p, f, TRUTH_GROUP, TRUTH_GROUP, links)
    if isinstance(truth, h5py.Group) and _child(p, truth, "streams", TRUTH_STREAMS_GROUP, links):
        paths += _stream_paths(p, f, TRUTH_STREAMS_GROUP)
    known = {*paths, STEPS_GROUP, LOG_GROUP}
    for entry in entries:
        if entry not in known:
            raise damaged(p, f"/commit `entries_json` names {entry!r}, which the file does not "
                             "hold; expected its streams, steps and log")
    for entry in (*paths, STEPS_GROUP, LOG_GROUP):
        if entry not in committed:
            raise damaged(p, f"/commit has no count for {entry}; expected one for every "
                             "stream, steps and log")
    streams = tuple(_stream(p, f, path, committed[path]) for path in paths)
    _check_steps(p, _table(p, f, STEPS_GROUP, step_fields(version), committed[STEPS_GROUP],
                            links, _STEP_FIELDS_CHECKED if sealed else None))
    _check_log(p, _table(p, f, LOG_GROUP, LOG_FIELDS, committed[LOG_GROUP], links,
                         _LOG_FIELDS_CHECKED if sealed else None))
    _check_truth(p, f, links)
    return Layout(version, entries, committed, streams)


# ----------------------------------------------------------------------------- time bases
def _describe_time(t: NDArray[np.float64], k: int, prev: float) -> str:
    v = float(t[k])
    if not math.isfinite(v):
        return f"is {v}"
    if v < 0:
        return f"is {v!r}, negative"
    if v > MAX_TIME_S:
        return f"is {v!r}, later than {_MAX_TEXT} s"
    return f"is {v!r}, before the previous time stamp {prev!r}"


def first_bad_time(ds: h5py.Dataset, n: int, block_rows: int = TIME_BLOCK_ROWS,
                   out: NDArray[np.float64] | None = None) -> tuple[int, str] | None:
    """First row of ``ds[:n]`` that breaks the time base, and what is wrong with it.

    A time base is finite, never decreases and lies in ``[0, MAX_TIME_S]``. The dataset is read
    in blocks of `block_rows` into one reused buffer; a valid block costs one comparison pass.
    `out` is that buffer when given (float64, ``min(n, block_rows)`` rows): with ``n <=
    block_rows`` it then holds ``ds[:n]`` whole afterwards.
    """
    buf = np.empty(min(n, block_rows), dtype=np.float64) if out is None else out
    prev = 0.0
    for a in range(0, n, block_rows):
        b = min(a + block_rows, n)
        t = buf[: b - a]
        ds.read_direct(t, np.s_[a:b], np.s_[0:b - a])
        # non-decreasing from `prev` (>= 0) to a last value <= MAX_TIME_S; NaN fails both
        if t[0] >= prev and t[-1] <= MAX_TIME_S and bool(np.all(t[1:] >= t[:-1])):
            prev = float(t[-1])
            continue
        ok = np.isfinite(t) & (t >= 0) & (t <= MAX_TIME_S)
        ok[0] &= bool(t[0] >= prev)
        ok[1:] &= t[1:] >= t[:-1]
        k = int(np.argmin(ok))
        return a + k, _describe_time(t, k, prev if k == 0 else float(t[k - 1]))
    return None


def check_time_bases(p: Path, f: h5py.File, streams: tuple[StreamLayout, ...], *,
                     keep_bytes: int = 0) -> dict[str, NDArray[np.float64]]:
    """Check the committed ``time_s`` rows of every stream (see :func:`first_bad_time`).

    Returns the committed time columns it read whole and kept, by stream path: those of the
    streams (not truth streams) whose column fits one block and the room `keep_bytes` leaves
    after the ones kept before it (default: none). The reader hands them to the first read
    that wants them instead of reading them again (docs/recording-format.md, "Cost of
    opening").
    """
    kept: dict[str, NDArray[np.float64]] = {}
    room = keep_bytes
    for s in streams:
        if not s.committed:
            continue
        ds = h5call(p, f"/{s.path}/{TIME_COLUMN}", f.__getitem__, f"{s.path}/{TIME_COLUMN}")
        keep = (s.path.startswith(STREAMS_GROUP + "/") and s.committed <= TIME_BLOCK_ROWS
                and 8 * s.committed <= room)
        out = np.empty(s.committed, dtype=np.float64) if keep else None
        bad = h5call(p, f"{s.label} time_s", first_bad_time, ds, s.committed, TIME_BLOCK_ROWS,
                     out)
        if bad is not None:
            row, what = bad
            raise damaged(p, f"{s.label} time_s row {row} {what}; expected finite times from 0 "
                             f"to {_MAX_TEXT} s that never decrease",
                          f"to copy out the rows before row {row}")
        if out is not None:
            kept[s.path] = out
            room -= out.nbytes
    return kept


# ----------------------------------------------------------------------------- probing
def touch_all(f: h5py.File, progress: Callable[[str], None]) -> list[str]:
    """Read every attribute and dataset header below the root; return what was unreadable.

    Calls ``progress(name)`` before each object, so that a probe stopped by a time limit can
    say where HDF5 was stuck. Errors do not stop the walk (they are returned as text).
    """
    errors: list[str] = []

    def visit(obj: h5py.HLObject, name: str, depth: int) -> None:
        progress(name)
        try:
            _attrs(obj)
            if isinstance(obj, h5py.Dataset):
                (obj.shape, obj.dtype, obj.chunks, obj.compression, obj.fillvalue)  # noqa: B018
            if not isinstance(obj, h5py.Group) or depth >= _MAX_DEPTH:
                return
            children = list(obj)
        except H5PY_ERRORS as exc:
            errors.append(f"{name}: {exc}")
            return
        for child in children:
            sub = f"{name.rstrip('/')}/{child}"
            try:
                item = obj[child]
            except H5PY_ERRORS as exc:
                errors.append(f"{sub}: {exc}")
                continue
            visit(item, sub, depth + 1)

    visit(f, "/", 0)
    return errors
