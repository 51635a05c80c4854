"""Read a Recording: streams by time range, by step or in chunks; steps, log, metadata, truth.

Contents
--------
:class:`Recording`
    The opened file: ``metadata``, ``streams``, ``read_stream``, ``iter_stream``, ``steps``,
    ``read_step``, ``log``, ``events``, ``truth``, ``read_truth_stream``, ``to_dataframe``.
    Made by :func:`~imucalib.io.opening.open_recording`, which checks the file first.
:class:`StreamInfo`, :class:`StreamData`, :class:`StepRecord`, :class:`LogEvent`
    What it returns.

Time windows are half-open: ``t_start_s <= time_s < t_end_s``. They are located by bisection on
the ``time_s`` dataset (single-element reads, then one block), so only the rows needed are read.
The format is described in :mod:`imucalib.io.recording` and ``docs/recording-format.md``.

Opening (:mod:`imucalib.io.opening`) validates the layout, the commit counts, the committed rows
of the steps and log and every stream's time base; every h5py exception met later while reading
becomes a :class:`~imucalib.errors.RecordingCorruptError` with one line naming the file, what was
found and what was expected.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any, TypeVar

import h5py
import numpy as np
from numpy.typing import NDArray

from imucalib.conventions import TIME_COLUMN
from imucalib.errors import CalibrationError, InvalidInputError
from imucalib.io._schema import (
    COMMIT_GROUP,
    LOG_FIELDS,
    LOG_GROUP,
    STEPS_GROUP,
    STREAMS_GROUP,
    TRUTH_GROUP,
    TRUTH_STREAMS_GROUP,
    ColumnSpec,
    decode_attr,
    decode_counts,
    decode_text,
    parse_string_list,
    step_fields,
)
from imucalib.io._search import scan_sorted_dataset, search_sorted_dataset
from imucalib.io._v1 import v1_plan, v1_role_and_tags
from imucalib.io._validate import H5PY_ERRORS, Layout, damaged, from_h5py, parse_columns
from imucalib.io.events import EventKind, as_event_kind, event_kind

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["LogEvent", "Recording", "StepRecord", "StreamData", "StreamInfo"]

#: Window ends from which :meth:`Recording.iter_windows` finds its rows by one pass over the
#: time column rather than a search per end (a search costs a few small reads).
_SCAN_WINDOWS = 32
#: Rows :meth:`Recording.iter_windows` reads at most in one call per column when it reads
#: several nearby windows together (a window longer than this is read alone; a chunk of the
#: default layout, 65,536 rows: memory stays bounded by what one window needs).
_GROUP_ROWS = 1 << 16


def _read_groups(spans: Sequence[tuple[int, int]], chunk_rows: int, max_rows: int
                 ) -> Iterator[tuple[int, int, list[tuple[int, int]]]]:
    """Group consecutive row spans ``[i0, i1)`` into reads: (g0, g1, the spans in it).

    A span joins the group before it when it starts at most one chunk after the group's end
    (the rows between cost at most the decompression of a chunk the two would share anyway)
    and the group stays within `max_rows`; spans out of order start a new group. Reading
    a group once per column replaces one h5py call per window and column, whose fixed cost
    (about 50 µs) dominated the reading of short windows: a P2 lot's 768 windows of
    6,000 rows made 9,235 calls.
    """
    group: list[tuple[int, int]] = []
    g0 = g1 = 0
    for i0, i1 in spans:
        if group and g0 <= i0 and i0 - g1 <= chunk_rows and max(g1, i1) - g0 <= max_rows:
            group.append((i0, i1))
            g1 = max(g1, i1)
            continue
        if group:
            yield g0, g1, group
        group, g0, g1 = [(i0, i1)], i0, i1
    if group:
        yield g0, g1, group

_T = TypeVar("_T")


@dataclass(frozen=True)
class StreamInfo:
    """One stream: its name, columns (``time_s`` first) and extent."""

    device: str
    unit: str
    columns: dict[str, ColumnSpec]
    n_samples: int
    t_first_s: float  # NaN when empty [s]
    t_last_s: float  # NaN when empty [s]

    @property
    def name(self) -> str:
        """``"<device>/<unit>"``."""
        return f"{self.device}/{self.unit}"


@dataclass(frozen=True)
class StreamData:
    """Rows of one stream: ``time_s`` and the other requested columns, with their units."""

    time_s: NDArray[np.float64]
    columns: dict[str, NDArray[Any]]
    units: dict[str, str]  # column name (``time_s`` included) -> unit string

    def __len__(self) -> int:
        return int(self.time_s.shape[0])


@dataclass(frozen=True)
class StepRecord:
    """One executed plan step, as recorded.

    ``role``, ``tags`` and ``units`` are stored since format version 2; for a version 1 file the
    reader derives ``role`` and ``tags`` from the step's ``commanded`` state or the stored plan,
    and ``units`` is empty (``docs/recording-format.md``, "Reading version 1").
    """

    index: int
    kind: str
    label: str
    commanded: Any  # decoded JSON (usually a dict); None when not given
    t_start_s: float
    t_end_s: float  # NaN while running [s]
    valid_start_s: float  # NaN until known [s]
    valid_end_s: float  # NaN until known [s]
    status: str
    note: str
    role: str = ""  # e.g. "p1.accel-position" (its procedure's roles.py); "" when none
    tags: tuple[str, ...] = ()
    units: tuple[str, ...] = ()  # IMU unit names the step concerns; () = every IMU

    @property
    def has_valid_window(self) -> bool:
        """Whether both ends of the valid window are known."""
        return math.isfinite(self.valid_start_s) and math.isfinite(self.valid_end_s)

    def tag_value(self, key: str) -> str | None:
        """Return the value of the first ``"key=value"`` tag, or None.

        Examples
        --------
        >>> StepRecord(0, "static", "", None, 0.0, 1.0, 0.0, 1.0, "done", "",
        ...            tags=("calibration", "repetition=2")).tag_value("repetition")
        '2'
        """
        prefix = f"{key}="
        for tag in self.tags:
            if tag.startswith(prefix):
                return tag[len(prefix):]
        return None

    def concerns(self, unit: str) -> bool:
        """Whether the step concerns IMU `unit` (every step with no ``units`` does)."""
        return not self.units or unit in self.units


@dataclass(frozen=True)
class LogEvent:
    """One logged event."""

    time_s: float
    level: str
    source: str
    message: str

    @property
    def kind(self) -> EventKind | None:
        """The station event this is (a remount, a swap, a load), or None for any other event.

        Read from ``source`` (``"event:<kind>"``), or for a Recording written before the events
        were typed by the frozen version 1 mapping (:mod:`imucalib.io.events`;
        ``docs/recording-format.md``, "Station events").
        """
        return event_kind(self.source, self.message)


@dataclass(frozen=True)
class _Layout:
    """The fixed part of a stream: names and column specifications."""

    device: str
    unit: str
    columns: dict[str, ColumnSpec]

    @property
    def name(self) -> str:
        return f"{self.device}/{self.unit}"


def _decode_text_array(values: NDArray[Any]) -> list[str]:
    return [decode_text(v) for v in values.tolist()]


class Recording:
    """An opened Recording (thin: it reads on demand).

    Make it with :func:`~imucalib.io.opening.open_recording`.
    """

    def __init__(self, file: h5py.File, path: Path, format_version: int, *,
                 was_open_for_write: bool, layout: Layout | None = None,
                 times: dict[str, NDArray[np.float64]] | None = None) -> None:
        self._file = file
        self.path = path
        self.format_version = format_version
        self.was_open_for_write = was_open_for_write
        # layout cannot change after creation (SWMR forbids it): cache it
        self._datasets: dict[str, h5py.Dataset] = {}
        self._layouts: dict[str, _Layout] = {}
        self._commit_entries: list[str] | None = None
        # the steps table parsed once: a file not open for SWMR reading cannot change under us
        self._steps_cache: tuple[StepRecord, ...] | None = None
        # the same for the streams' extents (each reads a stream's first and last time stamps:
        # two chunks decompressed per stream, a P2 analysis asked for them once per unit)
        self._infos_cache: dict[str, tuple[StreamInfo, ...]] = {}
        # committed time columns the opening's time-base check read whole, by stream path: the
        # first read of a whole column takes its array, a part is copied out of it
        self._times: dict[str, NDArray[np.float64]] = dict(times or {})
        if layout is not None:  # validated when opened
            self._commit_entries = list(layout.commit_entries)
            for s in layout.streams:
                self._layouts[s.path] = _Layout(s.device, s.unit, dict(s.columns))

    # --------------------------------------------------------------------------- basics
    def close(self) -> None:
        """Close the file (idempotent)."""
        if self._file.id.valid:
            self._file.close()

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()

    def __repr__(self) -> str:
        flag = ", was open for write" if self.was_open_for_write else ""
        return f"Recording({str(self.path)!r}, format v{self.format_version}{flag})"

    def _dataset(self, path: str) -> h5py.Dataset:
        ds = self._datasets.get(path)
        if ds is None:
            ds = self._datasets[path] = self._file[path]
        elif self._file.swmr_mode:
            ds.refresh()
        return ds

    def _guard(self, what: str, func: Callable[..., _T], *args: Any) -> _T:
        """Call ``func(*args)``, turning what h5py raises into :class:`RecordingCorruptError`."""
        try:
            return func(*args)
        except CalibrationError:
            raise
        except H5PY_ERRORS as exc:
            if not from_h5py(exc):
                raise
            raise damaged(self.path, f"{what} is unreadable ({exc})",
                          "to copy out what is readable") from exc

    @property
    def metadata(self) -> dict[str, Any]:
        """Root attributes; values of ``*_json`` attributes are decoded."""
        return self._guard("the root attributes", self._metadata)

    def _metadata(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for key, value in self._file.attrs.items():
            v = decode_attr(value)
            if key.endswith("_json") and isinstance(v, str):
                try:
                    v = json.loads(v)
                except ValueError:
                    pass
            out[key] = v
        return out

    def committed_rows(self) -> dict[str, int]:
        """Rows known durable per entry (``"streams/imu/IMU-0001"``, ``"steps"``, ``"log"``)."""
        return self._guard("the commit counts", self._committed_rows)

    def _committed_rows(self) -> dict[str, int]:
        if self._commit_entries is None:
            if COMMIT_GROUP not in self._file:
                return {}
            entries = self._json(decode_attr(self._file[COMMIT_GROUP].attrs.get("entries_json")),
                                 "/commit `entries_json`")
            if not isinstance(entries, list):
                raise damaged(self.path, f"/commit `entries_json` is {entries!r}; expected a "
                                         "JSON list")
            self._commit_entries = [str(e) for e in entries]
        rows = self._dataset(f"{COMMIT_GROUP}/rows")[()]
        if rows.shape != (len(self._commit_entries),):
            raise damaged(self.path, f"/commit/rows has shape {rows.shape}; expected one count "
                                     f"for each of the {len(self._commit_entries)} entries")
        return {e: int(n) for e, n in zip(self._commit_entries, rows.tolist(), strict=True)}

    # --------------------------------------------------------------------------- streams
    def _stream_paths(self, base: str) -> list[str]:
        return self._guard(f"/{base}", self._list_streams, base)

    def _list_streams(self, base: str) -> list[str]:
        group = self._file.get(base)
        if not isinstance(group, h5py.Group):
            return []
        return [f"{base}/{dev}/{unit}" for dev in sorted(group)
                if isinstance(group[dev], h5py.Group)
                for unit in sorted(group[dev]) if isinstance(group[dev][unit], h5py.Group)]

    def _layout(self, path: str) -> _Layout:
        layout = self._layouts.get(path)
        if layout is None:
            group = self._file[path]
            cols = parse_columns(self.path, path, decode_attr(group.attrs.get("columns_json")))
            for name in cols:  # opening through the group is cheaper than by full path
                self._datasets.setdefault(f"{path}/{name}", group[name])
            device, unit = path.rsplit("/", 2)[-2:]
            layout = _Layout(device, unit, cols)
            self._layouts[path] = layout
        return layout

    def _n_rows(self, path: str, committed: dict[str, int] | None = None) -> int:
        """Rows readable in every column and committed by the writer."""
        n = committed.get(path) if committed is not None else self.committed_rows().get(path)
        for name in self._layout(path).columns:
            length = self._dataset(f"{path}/{name}").shape[0]
            n = length if n is None else min(n, length)
        return int(n or 0)

    def _info(self, path: str, committed: dict[str, int] | None = None) -> StreamInfo:
        layout = self._layout(path)
        n = self._n_rows(path, committed)
        if n:
            kept = self._times.get(path)
            t = kept if kept is not None and n <= kept.size else self._dataset(
                f"{path}/{TIME_COLUMN}")
            t_first, t_last = float(t[0]), float(t[n - 1])
        else:
            t_first = t_last = math.nan
        return StreamInfo(layout.device, layout.unit, dict(layout.columns), n, t_first, t_last)

    def _infos(self, base: str) -> list[StreamInfo]:
        cached = self._infos_cache.get(base)
        if cached is None:
            committed = self.committed_rows()
            cached = tuple(self._guard(f"stream {p}", self._info, p, committed)
                           for p in self._stream_paths(base))
            if not self._file.swmr_mode:  # a file read while it is written changes
                self._infos_cache[base] = cached
        return [dataclasses.replace(i, columns=dict(i.columns)) for i in cached]

    @property
    def streams(self) -> list[StreamInfo]:
        """Every stream, sorted by device then unit."""
        return self._infos(STREAMS_GROUP)

    @property
    def truth_streams(self) -> list[StreamInfo]:
        """Every truth stream (twin recordings only)."""
        return self._infos(TRUTH_STREAMS_GROUP)

    def stream_info(self, device: str, unit: str) -> StreamInfo:
        """Describe one stream (a :class:`StreamInfo`)."""
        return self._guard("stream", self._info, self._stream_path(STREAMS_GROUP, device, unit))

    def _stream_path(self, base: str, device: str, unit: str) -> str:
        path = f"{base}/{device}/{unit}"
        if path in self._layouts:
            return path
        if (not isinstance(device, str) or not isinstance(unit, str) or "/" in device + unit
                or not self._guard(f"/{path}", self._file.__contains__, path)):
            known = ", ".join(p.removeprefix(base + "/") for p in self._stream_paths(base))
            what = "truth stream" if base == TRUTH_STREAMS_GROUP else "stream"
            raise InvalidInputError(f"no {what} {device}/{unit} in {self.path.name}; "
                                    f"streams: {known or 'none'}")
        return path

    @staticmethod
    def _select(info: StreamInfo | _Layout, columns: Sequence[str] | None) -> list[str]:
        if columns is None:
            return [c for c in info.columns if c != TIME_COLUMN]
        if isinstance(columns, str):
            raise InvalidInputError("`columns` must be a sequence of names, not a str")
        unknown = [c for c in columns if c not in info.columns]
        if unknown:
            raise InvalidInputError(f"stream {info.name} has no column(s) {unknown}; columns: "
                                    f"{list(info.columns)}")
        return [c for c in dict.fromkeys(columns) if c != TIME_COLUMN]

    def _search(self, ds: h5py.Dataset, n: int, t: float, side: str) -> int:
        return search_sorted_dataset(ds, n, t, side)

    def _row_range(self, path: str, n: int, t_start_s: float | None,
                   t_end_s: float | None) -> tuple[int, int]:
        for name, v in (("t_start_s", t_start_s), ("t_end_s", t_end_s)):
            if v is not None and (not isinstance(v, int | float | np.floating) or math.isnan(v)):
                raise InvalidInputError(f"`{name}` must be a number [s] or None; got {v!r}")
        if t_start_s is not None and t_end_s is not None and t_end_s < t_start_s:
            raise InvalidInputError(f"`t_end_s` ({t_end_s}) is before `t_start_s` ({t_start_s})")
        ds = self._dataset(f"{path}/{TIME_COLUMN}")
        i0 = 0 if t_start_s is None else self._search(ds, n, float(t_start_s), "left")
        i1 = n if t_end_s is None else self._search(ds, n, float(t_end_s), "left")
        return i0, max(i0, i1)

    def row_range(self, device: str, unit: str, t_start_s: float | None = None,
                  t_end_s: float | None = None) -> tuple[int, int]:
        """Row indices ``[i0, i1)`` of a stream's rows with ``t_start_s <= time_s < t_end_s``."""
        path = self._stream_path(STREAMS_GROUP, device, unit)
        n = self._guard(f"stream {device}/{unit}", self._n_rows, path)
        return self._guard(f"stream {device}/{unit} time_s", self._row_range,
                           path, n, t_start_s, t_end_s)

    def _read_rows(self, path: str, info: StreamInfo | _Layout, names: list[str], i0: int, i1: int,
                   dsets: dict[str, h5py.Dataset] | None = None) -> StreamData:
        def read() -> StreamData:
            ds = dsets if dsets is not None else self._open_columns(path, names)
            t = self._kept_time(path, i0, i1)
            if t is None:
                t = ds[TIME_COLUMN][i0:i1]
            cols = {c: decode_counts(ds[c][i0:i1], info.columns[c].scale) for c in names}
            units = {TIME_COLUMN: info.columns[TIME_COLUMN].unit}
            units.update({c: info.columns[c].unit for c in names})
            return StreamData(t, cols, units)

        return self._guard(f"stream {info.name} rows {i0}:{i1}", read)

    def _kept_time(self, path: str, i0: int, i1: int) -> NDArray[np.float64] | None:
        """Rows ``[i0, i1)`` of the kept time column of `path` (None: not kept).

        The whole column is handed over (the reader keeps it no longer); a part is a copy.
        """
        kept = self._times.get(path)
        if kept is None or not 0 <= i0 <= i1 <= kept.size:
            return None
        if (i0, i1) == (0, kept.size):
            return self._times.pop(path)
        return kept[i0:i1].copy()

    def _open_columns(self, path: str, names: list[str]) -> dict[str, h5py.Dataset]:
        return {c: self._dataset(f"{path}/{c}") for c in (TIME_COLUMN, *names)}

    def _read(self, base: str, device: str, unit: str, columns: Sequence[str] | None,
              t_start_s: float | None, t_end_s: float | None) -> StreamData:
        path = self._stream_path(base, device, unit)
        layout = self._guard(f"stream {device}/{unit}", self._layout, path)
        names = self._select(layout, columns)
        n = self._guard(f"stream {device}/{unit}", self._n_rows, path)
        i0, i1 = self._guard(f"stream {device}/{unit} time_s", self._row_range, path, n,
                             t_start_s, t_end_s)
        return self._read_rows(path, layout, names, i0, i1)

    def iter_windows(self, device: str, unit: str, windows: Sequence[tuple[float, float]],
                     columns: Sequence[str] | None = None) -> Iterator[StreamData]:
        """Read several time windows ``[t0, t1)`` of one stream in turn.

        The same as :meth:`read_stream` once per window, but the column datasets stay open
        from one window to the next, so HDF5's chunk cache serves windows that share a
        (compressed) chunk: reading many short windows in time order costs about what
        reading their rows in one pass does (bench/bench_p2.py). The handles are the
        iterator's own, closed with it (memory does not grow with the streams read).

        Raises
        ------
        InvalidInputError
            Unknown stream or column, or a bad window.
        RecordingCorruptError
            If the data cannot be read.
        """
        path = self._stream_path(STREAMS_GROUP, device, unit)
        layout = self._guard(f"stream {device}/{unit}", self._layout, path)
        names = self._select(layout, columns)
        n = self._guard(f"stream {device}/{unit}", self._n_rows, path)
        # HDF5 keeps one chunk cache (2 MiB a column: _open.CHUNK_CACHE_BYTES) per open dataset
        # while any handle to it is open: the reader's cached handles of these columns are
        # dropped, and the iterator's own closed with it, so reading stream after stream does
        # not pile caches up
        for c in (TIME_COLUMN, *names):
            self._datasets.pop(f"{path}/{c}", None)
        dsets = self._guard(f"stream {device}/{unit}",
                            lambda: {c: self._file[f"{path}/{c}"] for c in (TIME_COLUMN, *names)})
        time_ds = dsets[TIME_COLUMN]
        for t_start_s, t_end_s in windows:
            for name, v in (("t_start_s", t_start_s), ("t_end_s", t_end_s)):
                if not isinstance(v, int | float | np.floating) or math.isnan(v):
                    raise InvalidInputError(f"`{name}` must be a number [s]; got {v!r}")
            if t_end_s < t_start_s:
                raise InvalidInputError(f"`t_end_s` ({t_end_s}) is before `t_start_s` "
                                        f"({t_start_s})")
        ends = np.asarray(windows, dtype=np.float64).reshape(-1)
        if ends.size >= _SCAN_WINDOWS:  # many windows: one pass over the time column
            rows = self._guard(f"stream {device}/{unit} time_s", scan_sorted_dataset, time_ds,
                               n, ends)
        else:
            rows = np.array([self._guard(f"stream {device}/{unit} time_s", self._search,
                                         time_ds, n, float(t), "left") for t in ends],
                            dtype=np.int64)
        spans = [(int(rows[2 * k]), max(int(rows[2 * k]), int(rows[2 * k + 1])))
                 for k in range(len(windows))]
        chunk = time_ds.chunks[0] if time_ds.chunks else _GROUP_ROWS
        for g0, g1, members in _read_groups(spans, chunk, _GROUP_ROWS):
            block = self._read_rows(path, layout, names, g0, g1, dsets)
            for i0, i1 in members:
                yield block if (i0, i1) == (g0, g1) else StreamData(
                    block.time_s[i0 - g0:i1 - g0].copy(),
                    {c: v[i0 - g0:i1 - g0].copy() for c, v in block.columns.items()},
                    block.units)

    def read_stream(self, device: str, unit: str, columns: Sequence[str] | None = None,
                    t_start_s: float | None = None, t_end_s: float | None = None) -> StreamData:
        """Read a stream, or the rows with ``t_start_s <= time_s < t_end_s``.

        Parameters
        ----------
        device, unit : str
            The stream.
        columns : sequence of str, optional
            Columns besides ``time_s`` (default: all).
        t_start_s, t_end_s : float, optional
            Half-open time window [s]; ``None`` means unbounded.

        Returns
        -------
        StreamData
            ``time_s``, the columns and their units.

        Raises
        ------
        InvalidInputError
            Unknown stream or column, or a bad window.
        RecordingCorruptError
            If the data cannot be read.
        """
        return self._read(STREAMS_GROUP, device, unit, columns, t_start_s, t_end_s)

    def read_truth_stream(self, device: str, unit: str, columns: Sequence[str] | None = None,
                          t_start_s: float | None = None,
                          t_end_s: float | None = None) -> StreamData:
        """Read a truth stream (twin only); like :meth:`read_stream`."""
        return self._read(TRUTH_STREAMS_GROUP, device, unit, columns, t_start_s, t_end_s)

    def iter_stream(self, device: str, unit: str, chunk_samples: int = 1 << 18,
                    columns: Sequence[str] | None = None, t_start_s: float | None = None,
                    t_end_s: float | None = None) -> Iterator[StreamData]:
        """Yield a stream (or a window of it) in pieces of at most `chunk_samples` rows.

        Memory is bounded by `chunk_samples` rows of the requested columns. The extent is fixed
        when iteration starts.
        """
        if not isinstance(chunk_samples, int | np.integer) or chunk_samples < 1:
            raise InvalidInputError(f"`chunk_samples` must be a positive int; got "
                                    f"{chunk_samples!r}")
        path = self._stream_path(STREAMS_GROUP, device, unit)
        layout = self._guard(f"stream {device}/{unit}", self._layout, path)
        names = self._select(layout, columns)
        n = self._guard(f"stream {device}/{unit}", self._n_rows, path)
        i0, i1 = self._guard(f"stream {device}/{unit} time_s", self._row_range, path, n,
                             t_start_s, t_end_s)
        return self._iter(path, layout, names, i0, i1, int(chunk_samples))

    def _iter(self, path: str, info: StreamInfo | _Layout, names: list[str], i0: int, i1: int,
              chunk: int) -> Iterator[StreamData]:
        dsets = self._open_columns(path, names)
        for a in range(i0, i1, chunk):
            yield self._read_rows(path, info, names, a, min(a + chunk, i1), dsets)

    def to_dataframe(self, device: str, unit: str, columns: Sequence[str] | None = None,
                     t_start_s: float | None = None, t_end_s: float | None = None,
                     step: int | None = None) -> pd.DataFrame:
        """Read a stream (window, or step's valid window) as a DataFrame indexed by ``time_s``.

        Units are in ``df.attrs["units"]``.
        """
        import pandas as pd

        if step is not None:
            data = self.read_step(step, device, unit, columns)
        else:
            data = self.read_stream(device, unit, columns, t_start_s, t_end_s)
        df = pd.DataFrame(data.columns, index=pd.Index(data.time_s, name=TIME_COLUMN))
        df.attrs["units"] = dict(data.units)
        return df

    # ---------------------------------------------------------------------- steps and log
    def _table(self, group: str, fields: dict[str, Any]) -> dict[str, list[Any]]:
        n = self.committed_rows().get(group)
        out: dict[str, list[Any]] = {}
        for name in fields:
            ds = self._dataset(f"{group}/{name}")
            n = ds.shape[0] if n is None else min(n, ds.shape[0])
        for name, spec in fields.items():
            values = self._dataset(f"{group}/{name}")[: n or 0]
            out[name] = _decode_text_array(values) if spec.kind == "text" else values.tolist()
        return out

    @property
    def steps(self) -> list[StepRecord]:
        """The executed steps, in order (those of a version 1 file with derived roles and tags).

        Read and parsed once per opened file; a file read while it is written (SWMR) is read
        again on every access, since its steps change.
        """
        if self._steps_cache is not None:
            return list(self._steps_cache)
        out = self._read_steps()
        if not self._file.swmr_mode:
            self._steps_cache = tuple(out)
        return out

    def _read_steps(self) -> list[StepRecord]:
        fields = step_fields(self.format_version)
        t = self._guard("the steps table", self._table, STEPS_GROUP, fields)
        v1 = self.format_version < 2
        plan = v1_plan(self.metadata) if v1 and t["index"] else None
        out = []
        for i in range(len(t["index"])):
            cmd = t["commanded"][i]
            commanded = self._json(cmd, f"/steps/commanded row {i}") if cmd else None
            if plan is not None:
                role, tags = v1_role_and_tags(t["kind"][i], commanded, plan)
                units: tuple[str, ...] = ()
            else:
                role = t["role"][i]
                tags = self._string_list(t["tags"][i], f"/steps/tags row {i}")
                units = self._string_list(t["units"][i], f"/steps/units row {i}")
            out.append(StepRecord(
                index=int(t["index"][i]), kind=t["kind"][i], label=t["label"][i],
                commanded=commanded, t_start_s=t["t_start_s"][i], t_end_s=t["t_end_s"][i],
                valid_start_s=t["valid_start_s"][i], valid_end_s=t["valid_end_s"][i],
                status=t["status"][i], note=t["note"][i], role=role, tags=tags, units=units))
        return out

    def _string_list(self, text: str, what: str) -> tuple[str, ...]:
        try:
            return parse_string_list(text)
        except ValueError as exc:
            raise damaged(self.path, f"{what} is {text[:40]!r} ({exc}); expected a JSON list "
                                     "of strings") from exc

    def step(self, step_index: int) -> StepRecord:
        """One step by index."""
        steps = self.steps
        for st in steps:
            if st.index == step_index:
                return st
        raise InvalidInputError(f"no step {step_index!r} in {self.path.name}; it has "
                                f"{len(steps)} step(s)")

    def step_window(self, step_index: int, *,
                    valid_only: bool = True) -> tuple[float, float | None]:
        """Return a step's valid window, or with ``valid_only=False`` its whole span [s]."""
        st = self.step(step_index)
        if valid_only:
            if not st.has_valid_window:
                raise InvalidInputError(
                    f"step {st.index} ({st.label!r}, status {st.status!r}) has no valid window; "
                    "pass valid_only=False for its whole duration")
            return st.valid_start_s, st.valid_end_s
        return st.t_start_s, st.t_end_s if math.isfinite(st.t_end_s) else None

    def read_step(self, step_index: int, device: str, unit: str,
                  columns: Sequence[str] | None = None, valid_only: bool = True) -> StreamData:
        """Rows of a stream inside a step's valid window (or its whole span).

        Raises
        ------
        InvalidInputError
            Unknown step, or no valid window while `valid_only` is true.
        """
        t0, t1 = self.step_window(step_index, valid_only=valid_only)
        return self.read_stream(device, unit, columns, t0, t1)

    @property
    def log(self) -> list[LogEvent]:
        """The logged events, in the order logged."""
        t = self._guard("the log", self._table, LOG_GROUP, LOG_FIELDS)
        return [LogEvent(*row) for row in zip(t["time_s"], t["level"], t["source"], t["message"],
                                              strict=True)]

    def events(self, kind: EventKind | str | None = None) -> list[LogEvent]:
        """Return the logged station events of `kind` (every kind when None), in the order logged.

        A station event is a remount, a unit swap or a centrifuge load change
        (:class:`~imucalib.io.events.EventKind`; ``docs/recording-format.md``, "Station
        events"); files written before the events were typed are read by the frozen version 1
        mapping.

        Parameters
        ----------
        kind : EventKind or str, optional
            ``"remount"``, ``"swap"`` or ``"load"``.

        Returns
        -------
        list of LogEvent

        Raises
        ------
        InvalidInputError
            `kind` is no event kind.
        """
        wanted = None if kind is None else as_event_kind(kind)
        return [e for e in self.log
                if (k := e.kind) is not None and (wanted is None or k is wanted)]

    # ----------------------------------------------------------------------------- truth
    @property
    def has_truth(self) -> bool:
        """Whether the file holds a digital-twin truth."""
        return self._guard("/truth", self._file.__contains__, TRUTH_GROUP)

    @property
    def truth(self) -> dict[str, Any]:
        """Digital-twin truth (empty for a real station): JSON values, and arrays exactly."""
        return self._guard("the truth", self._truth)

    def _json(self, text: str, what: str) -> Any:
        try:
            return json.loads(text)
        except ValueError as exc:
            raise damaged(self.path, f"{what} is not JSON ({exc}); expected JSON text") from exc

    def _truth(self) -> dict[str, Any]:
        if TRUTH_GROUP not in self._file:
            return {}
        group = self._file[TRUTH_GROUP]
        out: dict[str, Any] = {}
        for key, value in group.attrs.items():
            if key.endswith("_json"):
                out[key.removesuffix("_json")] = self._json(decode_attr(value),
                                                            f"/truth `{key}`")
        if "arrays" in group:
            for key, ds in group["arrays"].items():
                out[key] = ds[()]
        return out
