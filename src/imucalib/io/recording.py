"""The Recording: one crash-safe HDF5 file per station run, and its writer.

Contents
--------
:class:`RecordingWriter`
    Creates a Recording, then appends samples, steps and log events under SWMR.
:class:`StreamSpec`, :class:`ColumnSpec`
    Declarations of the streams (given up front: SWMR forbids new datasets later).
:data:`FORMAT_NAME`, :data:`FORMAT_VERSION`, :data:`DEFAULT_CHUNK_ROWS`, :data:`STEP_FIELDS`,
:data:`LOG_FIELDS`, :data:`STEP_STATUSES`, :data:`LOG_LEVELS`, :data:`EXTRA_UNITS`
    Format constants.

File format, version 3
----------------------
An HDF5 file (``libver="latest"``, superblock v3) written in SWMR mode. Everything is created
before SWMR starts; afterwards the writer only appends to and overwrites datasets, so everything
known at creation is stored then.

Root attributes
    ``format`` = ``"imucalib-recording"``; ``format_version`` = 3 (int; 2 for a file without
    scaled columns or Blosc-compressed columns, which readers of version 2 read); ``created_utc``
    (ISO 8601, ``Z``); ``software_version`` (``imucalib.__version__``); and the caller's metadata,
    one attribute per key (str, int, float or bool). Keys ending in ``_json`` hold JSON text;
    the conventional keys are ``plan_toml``, ``station_json``, ``environment_json``,
    ``imu_identity_json`` and ``scenario_json``. A recovered copy adds ``recovered_from`` and
    ``recovered_utc``.
``/streams/<device>/<unit>/<column>``
    One group per stream (``device``: kind such as ``imu``, ``table``, ``chamber``,
    ``centrifuge``; ``unit``: the physical unit's name, e.g. ``IMU-0001`` or ``main``). Each column
    is a 1-D chunked dataset with unlimited ``maxshape`` (64 Ki rows per chunk; uncompressed while
    written, by default HDF5's shuffle + deflate once closed, which every HDF5 tool reads:
    :mod:`imucalib.io.compression`),
    attributes ``unit`` (a unit
    string, checked against
    :func:`imucalib.units.parse_unit` or :data:`EXTRA_UNITS`), ``quantity`` (``"si"`` or ``"raw"``)
    and ``description``. ``time_s`` (float64, ``"s"``, non-decreasing, finite) is mandatory and is
    the stream's time base. Float columns have fill value NaN. An integer column with a
    ``scale`` attribute (version 3) holds counts of that LSB: readers return ``counts × scale``
    as float64, exactly the values the writer was given. The group has attributes
    ``device``, ``unit`` and ``columns_json``: the column specifications in declared order, a
    JSON list of ``{"name", "unit", "dtype", "quantity", "description"}`` plus ``"scale"`` for a
    scaled column (the same facts as the datasets' attributes, in one attribute so that a reader
    opens a stream quickly).
``/steps/<field>``
    The executed plan steps as one 1-D dataset per field (row ``i`` is step ``index == i``):
    ``index`` (int64), ``kind``, ``label``, ``commanded`` (JSON text), ``t_start_s``, ``t_end_s``,
    ``valid_start_s``, ``valid_end_s`` (float64, NaN until known), ``status`` (one of
    :data:`STEP_STATUSES`), ``note``, and (since version 2) ``role`` (what the step is for in its
    procedure, e.g. ``"p1.accel-position"``), ``tags`` (JSON list of strings) and ``units``
    (JSON list of the IMU unit names the step concerns; ``[]``: every IMU). Text fields are
    fixed-length UTF-8 with the capacities of :data:`STEP_FIELDS`; longer text is refused, never
    truncated. Rows are overwritten in place when a step is updated. A version 1 file has the
    fields up to ``note`` only (``docs/recording-format.md`` says how readers map it).
``/log/<field>``
    Events: ``time_s`` (float64), ``level`` (one of :data:`LOG_LEVELS`), ``source``, ``message``.
    A station event (a remount, a unit swap, a load change) has ``source = "event:<kind>"``
    (:meth:`RecordingWriter.log_station_event`, :mod:`imucalib.io.events`).
``/truth`` (digital twin only; analysis code never reads it)
    Attributes ``<key>_json`` (JSON of each truth value) and datasets ``/truth/arrays/<key>``
    (numpy-array values, exact), and truth streams under ``/truth/streams/<device>/<unit>/``
    laid out as ``/streams``.
``/commit``
    Dataset ``rows`` (int64) with, for each entry named in the group's ``entries_json``
    attribute (``"streams/imu/IMU-0001"``, ``"truth/streams/…"``, ``"steps"``, ``"log"``), the
    number of rows known to be durable. The writer updates it only after an HDF5 flush of the
    data has returned, then flushes again, so after a crash it never counts rows whose data
    did not reach the file. Readers use ``min(commit count, dataset lengths)``.

Crash safety
------------
Appended rows are buffered in memory and written in large blocks. :meth:`RecordingWriter.flush`
(called automatically every ``flush_interval_s`` of wall-clock time, checked on each call, and
when the buffers exceed ``buffer_limit_bytes``) writes every buffer, flushes HDF5, then
commits the row counts. A writer killed at any moment loses at most what was appended after its
last completed flush; the file then refuses a normal HDF5 open (its "open for write" flag stays
set) but :func:`imucalib.io.opening.open_recording` reads it in SWMR mode, and
:func:`imucalib.io.recover.recover_recording` copies it into a cleanly closed file. The flush
makes data durable against the process dying (SIGKILL), not against power loss (no fsync).

A write, flush or close that HDF5 fails (ENOSPC or EIO behind the free-space checks) gives the
file up as a killed writer leaves it: no HDF5 call touches it again, its h5py objects are kept
alive so that Python never frees them (:mod:`imucalib.io._abandon`), and
:class:`~imucalib.errors.RecordingWriteError` says what failed, in one line; the process must
then end with :func:`os._exit` (:func:`abandoned_files`), as the command line does.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

import h5py
import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib.conventions import TIME_COLUMN
from imucalib.errors import (
    InvalidInputError,
    RecordingError,
    RecordingWriteError,
    StorageFullError,
)
from imucalib.io._abandon import (
    WRITE_ERRORS,
    abandon,
    abandoned_files,
    failure_text,
    freed_object_failure,
    watch_freed_objects,
)
from imucalib.io._layout import (
    StreamState,
    check_stream_specs,
    check_truth,
    column_compression,
    create_layout,
    open_stream,
)
from imucalib.io._schema import (
    COMMIT_GROUP,
    DEFAULT_CHUNK_ROWS,
    EXTRA_UNITS,
    FORMAT_NAME,
    FORMAT_VERSION,
    LOG_CHUNK_ROWS,
    LOG_FIELDS,
    LOG_GROUP,
    LOG_LEVELS,
    STEP_FIELDS,
    STEP_STATUSES,
    STEPS_CHUNK_ROWS,
    STEPS_GROUP,
    TRUTH_STREAMS_GROUP,
    ColumnSpec,
    FieldSpec,
    StreamSpec,
    as_column,
    check_metadata,
    decode_attr,
    encode_counts,
    step_fields,
)
from imucalib.io._tables import StepLogTables
from imucalib.io.compression import (
    COMPRESSIONS,
    DEFAULT_COMPRESSION,
    needs_plugin,
)
from imucalib.io.events import EventKind, event_message, event_source
from imucalib.io.storage import DEFAULT_RESERVE_BYTES, format_bytes, room_bytes

__all__ = [
    "DEFAULT_CHUNK_ROWS",
    "EXTRA_UNITS",
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "KEEP",
    "LOG_CHUNK_ROWS",
    "LOG_FIELDS",
    "LOG_LEVELS",
    "STEPS_CHUNK_ROWS",
    "STEP_FIELDS",
    "STEP_STATUSES",
    "ColumnSpec",
    "FieldSpec",
    "RecordingWriter",
    "StreamSpec",
    "abandoned_files",
]

_METADATA_SLACK_BYTES = 64 << 10  # B-tree and heap growth that may come with a block write
#: The writer's HDF5 chunk cache per dataset: the chunk being appended stays cached between the
#: partial flushes; HDF5 2's default (8 MiB a dataset) kept every written chunk, never read
#: again, until 8 MiB — about 220 MiB for a P2 run's 28 columns at 1 kHz (docs/web.md,
#: "Measured"). [bytes]
WRITE_CHUNK_CACHE_BYTES = 1 << 20


class _Keep:
    """The type of :data:`KEEP`."""

    def __repr__(self) -> str:
        return "KEEP"


#: ``RecordingWriter.reopen(..., compression=KEEP)``: close the file with the compression it had.
KEEP = _Keep()


class RecordingWriter:
    """Write a Recording: create the file, then append under SWMR (a context manager).

    Parameters
    ----------
    path : str or Path
        File to create (``.h5``). Must be on a local filesystem (SWMR needs POSIX semantics).
    streams : sequence of StreamSpec
        Every stream the run will write; none can be added later.
    metadata : mapping of str to str, int, float or bool, optional
        Root attributes (``plan_toml``, ``station_json``, …); keys ending in ``_json`` must hold
        JSON text.
    truth : mapping of str to any, optional
        Digital-twin truth, stored under ``/truth`` (numpy arrays exactly, the rest as JSON).
    truth_streams : sequence of StreamSpec
        Truth time series, written with :meth:`append_truth`.
    flush_interval_s : float
        Wall-clock interval between automatic flushes [s]; ``0`` flushes on every call and
        ``math.inf`` only on :meth:`flush` / :meth:`close` (and when the buffers fill).
    overwrite : bool
        Replace an existing file; otherwise an existing `path` is an error.
    chunk_rows : int
        Rows per HDF5 chunk of a stream column.
    compression : {"gzip", None, "lzf", "blosc-lz4", "blosc-zstd"}
        Column compression of the closed file (:mod:`imucalib.io.compression`): ``"gzip"``
        (HDF5's byte shuffle + deflate level 1) by default, which every HDF5 library and tool
        reads; ``"blosc-lz4"`` or ``"blosc-zstd"`` (Blosc after a bit-shuffle: faster to close
        and read, but read outside imucalib only where the HDF5 Blosc plugin is installed);
        ``"lzf"``; ``None`` for none. While the file is written its
        columns are uncompressed (under SWMR every flush would rewrite a compressed chunk in a
        new place and HDF5 never reuses the old one); :meth:`close` then rewrites it compressed
        (:func:`~imucalib.io.recover.compact_recording`: copied, verified, atomically renamed).
        ``docs/recording-format.md``, *Size and compression*, has the measurements.
    buffer_limit_bytes : int
        Buffered bytes (all streams) above which the writer flushes.
    reserve_bytes : int
        Room (free disk space, and what the file-size limit leaves) that every block write must
        leave free, so that the last flush and the close always fit [bytes]. A write that would
        not leave it raises :class:`~imucalib.errors.StorageFullError` before touching the file:
        the rows buffered then are dropped, later appends are refused, and steps, log events,
        :meth:`flush` and :meth:`close` still work (see ``docs/reliability.md``).

    Raises
    ------
    InvalidInputError, UnitError
        For bad specifications or metadata (checked before the file is created).
    RecordingError
        If `path` exists and `overwrite` is false, or the file cannot be created.
    StorageFullError
        If less than `reserve_bytes` of room is left where the file is to be created.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> spec = StreamSpec("imu", "IMU-0001", {"gyro_x_rps": ColumnSpec("rad/s")})
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "run.h5"
    >>> with RecordingWriter(path, streams=[spec], metadata={"operator": "ab"}) as w:
    ...     w.append("imu", "IMU-0001", {"time_s": [0.0, 0.01], "gyro_x_rps": [1e-5, 2e-5]})
    ...     i = w.begin_step("static", "position 1", 0.0)
    ...     w.update_step(i, t_end_s=0.01, status="done")
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        streams: Sequence[StreamSpec],
        metadata: Mapping[str, str | int | float | bool] | None = None,
        truth: Mapping[str, Any] | None = None,
        truth_streams: Sequence[StreamSpec] = (),
        flush_interval_s: float = 1.0,
        overwrite: bool = False,
        chunk_rows: int = DEFAULT_CHUNK_ROWS,
        compression: str | None = DEFAULT_COMPRESSION,
        buffer_limit_bytes: int = 64 << 20,
        reserve_bytes: int = DEFAULT_RESERVE_BYTES,
    ) -> None:
        self._path = Path(path)
        meta = check_metadata(metadata or {})
        stream_specs = check_stream_specs(streams, "streams")
        truth_specs = check_stream_specs(truth_streams, "truth_streams")
        truth_items = check_truth(truth)
        if not (isinstance(flush_interval_s, int | float) and flush_interval_s >= 0):
            raise InvalidInputError(f"`flush_interval_s` must be ≥ 0 [s]; got {flush_interval_s!r}")
        if not isinstance(chunk_rows, int) or chunk_rows < 1:
            raise InvalidInputError(f"`chunk_rows` must be a positive int; got {chunk_rows!r}")
        if compression not in COMPRESSIONS:
            raise InvalidInputError(f"`compression` must be one of {COMPRESSIONS}; "
                                    f"got {compression!r}")
        if not isinstance(buffer_limit_bytes, int) or buffer_limit_bytes < 1:
            raise InvalidInputError(f"`buffer_limit_bytes` must be a positive int; "
                                    f"got {buffer_limit_bytes!r}")
        if self._path.exists() and not overwrite:
            raise RecordingError(f"{self._path} exists; pass overwrite=True to replace it")
        if not isinstance(reserve_bytes, int) or reserve_bytes < 0:
            raise InvalidInputError(f"`reserve_bytes` must be a non-negative int; "
                                    f"got {reserve_bytes!r}")
        self._flush_interval_s = float(flush_interval_s)
        self._buffer_limit_bytes = buffer_limit_bytes
        self._reserve_bytes = reserve_bytes
        self._compression = compression
        self._full: StorageFullError | None = None
        self._buffered_bytes = 0
        self._closed = True
        watch_freed_objects()
        try:
            self._file = h5py.File(self._path, "w", libver="latest",
                                   rdcc_nbytes=WRITE_CHUNK_CACHE_BYTES)
        except OSError as exc:
            raise RecordingError(f"cannot create {self._path}: {failure_text(exc)}") from exc
        try:
            layout = create_layout(self._file, meta, stream_specs, truth_specs, truth_items,
                                   chunk_rows, compression)
            self._raise_freed_failure()
            self._file.swmr_mode = True
        except WRITE_ERRORS as exc:
            raise self._abandon_new(exc) from exc
        except BaseException:
            self._file.close()
            self._path.unlink(missing_ok=True)
            raise
        self._streams: dict[tuple[str, str], StreamState] = layout.streams
        self._truth_streams: dict[tuple[str, str], StreamState] = layout.truth_streams
        self._entries = layout.entries
        self._commit_ds = layout.commit_rows
        self._tables = layout.tables
        self._closed = False
        self._committed = np.zeros(len(self._entries), dtype=np.int64)
        self._last_flush = time.monotonic()

    @classmethod
    def reopen(cls, path: str | os.PathLike[str], *, flush_interval_s: float = 1.0,
               buffer_limit_bytes: int = 64 << 20,
               reserve_bytes: int = DEFAULT_RESERVE_BYTES,
               compression: str | _Keep | None = KEEP) -> RecordingWriter:
        """Reopen a cleanly closed Recording to append to its streams, steps and log.

        The streams and truth streams are those declared when the file was created; rows
        already written, steps (which :meth:`update_step` may still change) and events are kept.
        A file a crashed writer left open must first be recovered
        (:func:`imucalib.io.recover.recover_recording`). A file with compressed columns is
        first rewritten uncompressed (:func:`~imucalib.io.recover.compact_recording`), and
        :meth:`close` compresses it with `compression`: by default (:data:`KEEP`) the one it
        had, so that a file of format version 1 or 2 stays readable by the readers of its
        version; a Blosc compression (version 3 only) is refused for an older file.

        Raises
        ------
        RecordingOpenForWriteError
            If the file is still marked open by a writer.
        RecordingFormatError, RecordingCorruptError, RecordingError
            If it is not a readable Recording of this format.
        """
        from imucalib.io.opening import open_recording
        from imucalib.io.recover import compact_recording

        if not isinstance(compression, _Keep) and compression not in COMPRESSIONS:
            raise InvalidInputError(f"`compression` must be one of {COMPRESSIONS} or KEEP; "
                                    f"got {compression!r}")
        p = Path(path)
        with open_recording(p, strict=True) as rec:  # diagnoses foreign, newer, damaged and
            filtered, had = column_compression(rec._file)  # still-open files clearly
            version = rec.format_version
        if isinstance(compression, _Keep):
            compression = had
        elif needs_plugin(compression) and version < FORMAT_VERSION:
            raise InvalidInputError(f"{p} is of format version {version}, whose readers lack the "
                                    f"Blosc filter: `compression` {compression!r} needs version "
                                    f"{FORMAT_VERSION}; use KEEP, None, 'gzip' or 'lzf'")
        if filtered:
            compact_recording(p, None)
        self = cls.__new__(cls)
        self._path = p
        self._compression = compression
        self._flush_interval_s = float(flush_interval_s)
        self._buffer_limit_bytes = int(buffer_limit_bytes)
        self._reserve_bytes = int(reserve_bytes)
        self._full = None
        self._check_room(0, "append to the file")
        self._buffered_bytes = 0
        self._streams = {}
        self._truth_streams = {}
        self._closed = True
        watch_freed_objects()
        try:
            self._file = h5py.File(p, "r+", libver="latest",
                                   rdcc_nbytes=WRITE_CHUNK_CACHE_BYTES)
        except OSError as exc:
            raise RecordingError(f"cannot reopen {p} for appending: {failure_text(exc)}"
                                 ) from exc
        try:
            f = self._file
            cg = f[COMMIT_GROUP]
            self._entries = json.loads(decode_attr(cg.attrs["entries_json"]))
            self._commit_ds = cg["rows"]
            for entry in self._entries:
                if entry in (STEPS_GROUP, LOG_GROUP):
                    continue
                st = open_stream(f, entry)
                table = (self._truth_streams if entry.startswith(TRUTH_STREAMS_GROUP + "/")
                         else self._streams)
                table[(st.spec.device, st.spec.unit)] = st
            version = int(decode_attr(f.attrs["format_version"]))
            self._tables = StepLogTables(f[STEPS_GROUP], f[LOG_GROUP], step_fields(version))
            self._tables.load_existing()
            self._raise_freed_failure()
            f.swmr_mode = True
        except WRITE_ERRORS as exc:
            raise self._abandon("reopening for appending", exc) from exc
        except BaseException:
            self._file.close()
            raise
        self._closed = False
        self._committed = np.array(self._commit_ds[:], dtype=np.int64)
        self._last_flush = time.monotonic()
        return self

    # ------------------------------------------------------------------------------ appending
    @property
    def path(self) -> Path:
        """The file being written."""
        return self._path

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has run."""
        return self._closed

    def _check_open(self, action: str) -> None:
        if self._closed:
            raise RecordingError(f"cannot {action}: the writer of {self._path} is closed")

    def append(self, device: str, unit: str, columns: Mapping[str, ArrayLike]) -> None:
        """Append rows to a stream.

        Parameters
        ----------
        device, unit : str
            The stream, as declared.
        columns : mapping of str to array_like, shape (n,)
            Every declared column (``time_s`` included), all of the same length. ``time_s``
            must be finite and non-decreasing, within this call and after the previous one [s].
            NaN in other float columns is data and is kept.

        Raises
        ------
        InvalidInputError
            Unknown stream or column, missing column, wrong length or dtype, bad ``time_s``;
            the message names the stream and column. Nothing is appended then.
        RecordingError
            After :meth:`close`.
        """
        self._check_open(f"append to {device}/{unit}")
        if self._full is not None:
            raise StorageFullError(str(self._full))
        self._append(self._streams, "stream", device, unit, columns)

    def append_truth(self, device: str, unit: str, columns: Mapping[str, ArrayLike]) -> None:
        """Append rows to a truth stream; same rules as :meth:`append`."""
        self._check_open(f"append to truth stream {device}/{unit}")
        if self._full is not None:
            raise StorageFullError(str(self._full))
        self._append(self._truth_streams, "truth stream", device, unit, columns)

    def _append(self, table: dict[tuple[str, str], StreamState], what: str, device: str,
                unit: str, columns: Mapping[str, ArrayLike]) -> None:
        st = table.get((device, unit))
        if st is None:
            known = ", ".join(s.spec.name for s in table.values()) or "none"
            raise InvalidInputError(f"unknown {what} {device}/{unit}; declared: {known}")
        name = st.spec.name
        if not isinstance(columns, Mapping):
            raise InvalidInputError(f"{what} {name}: `columns` must be a mapping of column name "
                                    f"to array; got {type(columns).__name__}")
        missing = [c for c in st.dtypes if c not in columns]
        if missing:
            raise InvalidInputError(f"{what} {name}: missing column(s) {missing}")
        unknown = [c for c in columns if c not in st.dtypes]
        if unknown:
            raise InvalidInputError(f"{what} {name}: unknown column(s) {unknown}; declared: "
                                    f"{list(st.dtypes)}")
        t = as_column(columns[TIME_COLUMN], st.dtypes[TIME_COLUMN], f"{what} {name}, column time_s")
        n = t.shape[0]
        if n == 0:
            for col in st.dtypes:
                if np.size(columns[col]) != 0:
                    raise InvalidInputError(f"{what} {name}, column {col!r}: length "
                                            f"{np.size(columns[col])} differs from time_s length 0")
            return
        finite = np.isfinite(t)
        if not finite.all():
            i = int(np.argmin(finite))
            raise InvalidInputError(f"{what} {name}, column time_s: must be finite; row {i} of "
                                    f"this append is {float(t[i])}")
        if t[0] < st.last_time_s:
            raise InvalidInputError(f"{what} {name}, column time_s: must be non-decreasing across "
                                    f"appends; this append starts at {float(t[0])!r} s, before the "
                                    f"previous last time {st.last_time_s!r} s")
        if n > 1:
            back = np.flatnonzero(t[1:] < t[:-1])
            if back.size:
                i = int(back[0]) + 1
                raise InvalidInputError(f"{what} {name}, column time_s: must be non-decreasing; "
                                        f"row {i} ({float(t[i])!r} s) is before row {i - 1} "
                                        f"({float(t[i - 1])!r} s)")
        arrays = {TIME_COLUMN: t}
        for col, dt in st.dtypes.items():
            if col == TIME_COLUMN:
                continue
            where = f"{what} {name}, column {col!r}"
            scaled = st.scaled.get(col)
            arr = (as_column(columns[col], dt, where) if scaled is None
                   else encode_counts(columns[col], scaled, where))
            if arr.shape[0] != n:
                raise InvalidInputError(f"{what} {name}, column {col!r}: length {arr.shape[0]} "
                                        f"differs from time_s length {n}")
            arrays[col] = arr
        nbytes = 0
        for col, arr in arrays.items():
            st.buffers[col].append(arr)
            nbytes += arr.nbytes
        st.n_buffered += n
        st.last_time_s = float(t[-1])
        self._buffered_bytes += nbytes
        if st.n_buffered >= st.datasets[TIME_COLUMN].chunks[0]:
            self._write_stream(st)
        self._maybe_flush()

    def _maybe_flush(self) -> None:
        if (self._buffered_bytes > self._buffer_limit_bytes
                or time.monotonic() - self._last_flush >= self._flush_interval_s):
            self.flush()

    def _write_stream(self, st: StreamState) -> None:
        """Write a stream's buffer: every column to the same length, idempotent on retry."""
        n = st.n_buffered
        if n == 0:
            return
        n0, n1 = st.n_written, st.n_written + n
        # HDF5 allocates whole chunks: count every chunk the rows touch, plus metadata slack
        rows = st.datasets[TIME_COLUMN].chunks[0]
        n_chunks = -(-n1 // rows) - n0 // rows
        self._check_room(n_chunks * rows * sum(dt.itemsize for dt in st.dtypes.values())
                         + _METADATA_SLACK_BYTES, f"write rows {n0}:{n1} of stream {st.entry}")
        nbytes = 0
        try:
            for col, ds in st.datasets.items():
                parts = st.buffers[col]
                block = parts[0] if len(parts) == 1 else np.concatenate(parts)
                if len(parts) > 1:
                    parts[:] = [block]
                if ds.shape[0] != n1:
                    ds.resize((n1,))
                ds.write_direct(block, dest_sel=np.s_[n0:n1])
                nbytes += block.nbytes
            self._raise_freed_failure()
        except (*WRITE_ERRORS, ValueError) as exc:
            raise self._abandon(f"writing stream {st.entry} rows {n0}:{n1}", exc) from exc
        for parts in st.buffers.values():
            parts.clear()
        st.n_written = n1
        st.n_buffered = 0
        self._buffered_bytes -= nbytes

    # ------------------------------------------------------------------------------- storage
    @property
    def room_bytes(self) -> int:
        """Bytes the file can still grow by (free space, file-size limit). [bytes]"""
        allocated = self._file.id.get_filesize() if not self._closed else None
        return room_bytes(self._path, file_size_bytes=allocated)

    @property
    def reserve_bytes(self) -> int:
        """Room every block write leaves free for the last flush and the close. [bytes]"""
        return self._reserve_bytes

    def _check_room(self, n_bytes: int, what: str) -> None:
        """Refuse (before touching the file) a write of `n_bytes` that would eat the reserve."""
        file = getattr(self, "_file", None)
        allocated = file.id.get_filesize() if file is not None and file.id.valid else None
        room = room_bytes(self._path, file_size_bytes=allocated)
        if room - n_bytes >= self._reserve_bytes:
            return
        exc = StorageFullError(
            f"no room to {what} in {self._path}: {format_bytes(room)} left on its filesystem "
            f"(or under the file-size limit), the write needs {format_bytes(n_bytes)} and "
            f"{format_bytes(self._reserve_bytes)} must stay free for a clean close; free some "
            "space, then continue with `imucalib run --resume FILE`")
        if not hasattr(self, "_streams"):  # creating or reopening: nothing buffered yet
            raise exc
        if room < _METADATA_SLACK_BYTES:  # not even a clean close fits: touch the file no more
            raise self._give_up_for_room(exc)
        self._full = exc
        dropped = 0
        for state in (*self._streams.values(), *self._truth_streams.values()):
            dropped += state.n_buffered
            for parts in state.buffers.values():
                parts.clear()
            state.n_buffered = 0
        self._buffered_bytes = 0
        raise StorageFullError(f"{exc} ({dropped} buffered row(s) not written)")

    def _check_flush_room(self) -> None:
        """Give the file up, before HDF5 fails on it, when not even a flush's metadata fits."""
        room = room_bytes(self._path, file_size_bytes=self._file.id.get_filesize())
        if room >= _METADATA_SLACK_BYTES:
            return
        raise self._give_up_for_room(StorageFullError(
            f"no room to flush {self._path}: {format_bytes(room)} left on its filesystem (or "
            f"under the file-size limit), less than the {format_bytes(_METADATA_SLACK_BYTES)} "
            "HDF5's metadata may need; free some space, then continue with `imucalib run "
            "--resume FILE`"))

    def _give_up_for_room(self, exc: StorageFullError) -> StorageFullError:
        """Abandon the file when not even a clean close fits; return the error to raise."""
        self._closed = True
        abandon(self._path, str(exc), None, self, self._file)
        return StorageFullError(f"{exc}; the file could not be closed cleanly and keeps what "
                                "was committed before, as a stopped writer leaves it")

    def _abandon(self, what: str, exc: BaseException) -> RecordingWriteError:
        """Give the file up after HDF5 failed to write it: no further HDF5 call touches it.

        The writer, its h5py file and `exc` (whose traceback holds the h5py objects of the
        frames the failure went through) are kept alive for the rest of the process
        (:mod:`imucalib.io._abandon`), which must end with :func:`os._exit`.
        """
        self._closed = True
        return abandon(
            self._path,
            f"{what} to {self._path} failed: {failure_text(exc)}; the file keeps everything "
            "committed before and is left as a stopped writer leaves it: continue with "
            "`imucalib run --resume FILE`, or copy it out with `imucalib recover FILE`",
            exc, self, getattr(self, "_file", None))

    def _abandon_new(self, exc: BaseException) -> RecordingWriteError:
        """Give up a file HDF5 failed to write while it was being created, and remove it."""
        self._closed = True
        error = abandon(
            self._path,
            f"creating {self._path} failed: {failure_text(exc)}; nothing was recorded (the "
            "file is removed): mend the storage or free some space, then start the run again",
            exc, self, self._file)
        try:
            self._path.unlink(missing_ok=True)
        except OSError:
            pass  # the storage failed: the file holds no commit, and no reader takes it
        return error

    # ------------------------------------------------------------------------- steps and log
    def begin_step(self, kind: str, label: str, t_start_s: float, *,
                   commanded: Mapping[str, Any] | str | None = None, note: str = "",
                   role: str = "", tags: Sequence[str] = (), units: Sequence[str] = (),
                   status: str = "running") -> int:
        """Record the start of a plan step and return its index (0, 1, 2, … in call order).

        Parameters
        ----------
        kind : str
            Step kind, e.g. ``"static"``, ``"rate"``, ``"thermal_soak"``.
        label : str
            Human-readable label.
        t_start_s : float
            Start time on the recording's time base [s].
        commanded : mapping or JSON str, optional
            Commanded state (positions, rates, temperatures), stored as JSON text.
        note : str
            Free text.
        role : str
            What the step is for in its procedure, e.g. ``"p1.accel-position"`` (``""``: none);
            the roles are listed in ``docs/recording-format.md``.
        tags : sequence of str
            The step's tags, e.g. ``("calibration", "six-position", "rep2")``.
        units : sequence of str
            The IMU unit names the step concerns; empty: every IMU of the file.
        status : str
            One of :data:`STEP_STATUSES`.

        Returns
        -------
        int
            The step index, for :meth:`update_step`.

        Raises
        ------
        InvalidInputError
            For a bad status, a non-finite time, text longer than its field, tags or units that
            are not a sequence of strings, or a unit name that is not one.
        """
        self._check_open("begin a step")
        index = self._tables.begin_step(kind, label, t_start_s, commanded, status, note,
                                        role, tags, units)
        self._maybe_flush()
        return index

    def update_step(self, index: int, /, **fields: Any) -> None:
        """Overwrite fields of a recorded step (``t_end_s``, ``valid_start_s``, ``status``, …).

        Raises
        ------
        InvalidInputError
            Unknown step or field, bad value, text too long, or an end before its start.
        """
        self._check_open("update a step")
        self._tables.update_step(index, fields)
        self._maybe_flush()

    def log_event(self, time_s: float, level: str, source: str, message: str) -> None:
        """Record an event (guard trip, fault, operator action).

        Parameters
        ----------
        time_s : float
            Event time on the recording's time base [s].
        level : str
            One of :data:`LOG_LEVELS`.
        source, message : str
            Who reports it and what; refused (not truncated) when longer than their fields.
        """
        self._check_open("log an event")
        self._tables.log_event(time_s, level, source, message)
        self._maybe_flush()

    def log_station_event(self, time_s: float, kind: EventKind | str, detail: str) -> str:
        """Record a station event (a remount, a unit swap, a load change) and return its message.

        The one way a station event is written: source ``"event:<kind>"``, level ``"info"``,
        message the kind's label and `detail` (:mod:`imucalib.io.events`;
        ``docs/recording-format.md``, "Station events").

        Parameters
        ----------
        time_s : float
            Event time on the recording's time base [s].
        kind : EventKind or str
            ``"remount"``, ``"swap"`` or ``"load"``.
        detail : str
            What was done, for people (``"+x up, yaw 90°"``, ``"A ↔ B"``, ``"5 kg"``).

        Returns
        -------
        str
            The message logged.

        Raises
        ------
        InvalidInputError
            Unknown `kind`, or a message longer than its field.
        """
        message = event_message(kind, detail)
        self.log_event(time_s, "info", event_source(kind), message)
        return message

    # ------------------------------------------------------------------------ flush / close
    def flush(self) -> None:
        """Write every buffer and make it durable: after this returns, a killed writer keeps it.

        The order makes a step's record never run ahead of its samples: (1) the stream rows are
        written and flushed, (2) their commit counts are written and flushed, and only then
        (3) the step and log rows are written and flushed and (4) their counts committed. A
        step marked ``done`` after its last sample was appended therefore reaches the file in
        the same flush as that sample or after it, whatever instant the writer dies at.

        Raises
        ------
        RecordingError
            After :meth:`close`, or when HDF5 fails to write (buffered rows are kept).
        """
        self._check_open("flush")
        full: StorageFullError | None = None
        for st in (*self._streams.values(), *self._truth_streams.values()):
            try:
                self._write_stream(st)
            except StorageFullError as exc:  # the buffers are dropped: commit the rest
                if self._closed:  # given up: not even a clean close fits
                    raise
                full = exc
        n_streams = len(self._streams) + len(self._truth_streams)
        counts = self._committed.copy()
        counts[:n_streams] = ([st.n_written for st in self._streams.values()]
                              + [st.n_written for st in self._truth_streams.values()])
        self._check_flush_room()
        try:
            self._raise_freed_failure()
            self._file.flush()
            self._commit(counts)
            self._tables.write()
            self._raise_freed_failure()
            self._file.flush()
            counts = counts.copy()
            counts[n_streams:] = (self._tables.n_steps_written, self._tables.n_log_written)
            self._commit(counts)
        except (*WRITE_ERRORS, ValueError) as exc:
            raise self._abandon("flushing", exc) from exc
        self._last_flush = time.monotonic()
        if full is not None:
            raise full

    def _commit(self, counts: NDArray[np.int64]) -> None:
        """Write new commit counts and flush, when they changed (the data are already durable)."""
        if not np.array_equal(counts, self._committed):
            self._commit_ds[:] = counts
            self._file.flush()
            self._committed = counts

    def close(self) -> None:
        """Flush and close, then compress; the file then opens normally. Again: does nothing.

        The order is controlled: every buffer is written and flushed (:meth:`flush`), then
        h5py closes the file's datasets and groups, then the file. The compression
        (``compression`` of the constructor or :meth:`reopen`) rewrites the closed file
        (:func:`~imucalib.io.recover.compact_recording`). It is skipped when the room left is
        less than the file's size plus `reserve_bytes`, after the storage filled up (the caller
        has had the :class:`~imucalib.errors.StorageFullError`), or when the rewrite is refused;
        the file is then left complete and uncompressed, and :attr:`compression_skipped` says
        why.

        Raises
        ------
        StorageFullError
            When the last rows could not be written for lack of room (the file is closed).
        RecordingWriteError
            When HDF5 failed to write, flush or close the file (it is given up unclosed, as a
            killed writer leaves it), or to write the compressed copy (the file is then closed,
            complete and uncompressed; ``imucalib run --resume FILE`` compresses it).
        """
        if self._closed:
            return
        already_full = self._full is not None
        news: StorageFullError | None = None
        try:
            self.flush()  # a failed write abandons the file and propagates
        except StorageFullError as exc:
            if not already_full:  # news to the caller: rows buffered now were dropped
                news = exc
        if not self._closed:  # not abandoned for want of room even for a clean close
            self._close_file()
            if news is None:
                self._compress()
        if news is not None:
            raise news

    def _close_file(self) -> None:
        """Close the HDF5 file (its objects first, then the file), or give it up on a failure."""
        self._closed = True
        try:
            self._raise_freed_failure()
            self._file.close()
        except WRITE_ERRORS as exc:
            raise self._abandon("closing", exc) from exc

    def _raise_freed_failure(self) -> None:
        """Raise a write to this file that HDF5 failed while h5py freed an object.

        Such a failure never reaches the caller; HDF5 may crash at the next flush of the file,
        so every flush and close asks first.
        """
        exc = freed_object_failure(self._path)
        if exc is not None:
            raise RuntimeError(str(exc)) from exc

    def _compress(self) -> None:
        """Rewrite the closed file with its compression, or warn and leave it as it is.

        A write that fails in the copy (:class:`~imucalib.errors.RecordingWriteError`) leaves
        the file complete, closed and uncompressed, and is raised.
        """
        from imucalib.io.recover import compact_recording

        if self._compression is None:
            return
        size = self._path.stat().st_size
        room = room_bytes(self._path)
        why = ""
        if self._full is not None:
            why = "the storage filled up during the run"
        elif room - size < self._reserve_bytes:
            why = (f"the copy needs up to {format_bytes(size)} and {format_bytes(room)} is left "
                   f"(reserve {format_bytes(self._reserve_bytes)})")
        else:
            try:
                compact_recording(self._path, self._compression)
                return
            except RecordingWriteError as exc:  # HDF5 failed to write the copy
                raise RecordingWriteError(
                    f"{self._path} is complete and closed but was left uncompressed: {exc}; "
                    "compress it with `imucalib run --resume FILE` (a station run) or "
                    "`imucalib compact FILE`") from exc
            except (RecordingError, OSError) as exc:
                why = str(exc)
        self._compression_skipped = (f"{self._path} is complete but was left uncompressed "
                                     f"({why}); compress it later with `imucalib compact "
                                     "FILE` (imucalib.io.compact_recording)")

    @property
    def compression_skipped(self) -> str:
        """Why :meth:`close` left the file uncompressed (``""``: it did not, or none was asked)."""
        return getattr(self, "_compression_skipped", "")

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return (f"RecordingWriter({str(self._path)!r}, {len(self._streams)} stream(s), "
                f"{self._tables.n_steps} step(s), {state})")

