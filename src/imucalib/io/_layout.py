"""The layout of a Recording: its groups, datasets and attributes, created and read back.

:class:`~imucalib.io.recording.RecordingWriter` writes; this module lays out what it writes
into (docs/recording-format.md): a new file's root attributes, one group per stream with a
dataset per column, the truth, the steps and log tables and the commit counts
(:func:`create_layout`), and the state of a stream of an existing file it reopens
(:func:`open_stream`).

Contents
--------
:class:`StreamState`, :class:`Layout`, :func:`check_stream_specs`, :func:`check_truth`,
:func:`create_layout`, :func:`create_stream`, :func:`open_stream`, :func:`column_compression`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

import h5py
import numpy as np
from numpy.typing import NDArray

from imucalib import __version__
from imucalib.conventions import TIME_COLUMN
from imucalib.errors import InvalidInputError
from imucalib.io._schema import (
    COMMIT_GROUP,
    FORMAT_NAME,
    FORMAT_VERSION,
    FORMAT_VERSION_PLAIN,
    LOG_CHUNK_ROWS,
    LOG_FIELDS,
    LOG_GROUP,
    STEP_FIELDS,
    STEPS_CHUNK_ROWS,
    STEPS_GROUP,
    STREAMS_GROUP,
    TRUTH_GROUP,
    TRUTH_STREAMS_GROUP,
    ColumnSpec,
    StreamSpec,
    check_key,
    column_json,
    decode_attr,
    json_dumps,
)
from imucalib.io._tables import StepLogTables, create_table
from imucalib.io.compression import compression_of, needs_plugin

__all__ = [
    "Layout",
    "StreamState",
    "check_stream_specs",
    "check_truth",
    "column_compression",
    "create_layout",
    "create_stream",
    "open_stream",
]


class StreamState:
    """Buffers and bookkeeping of one stream while writing."""

    __slots__ = ("buffers", "datasets", "dtypes", "entry", "last_time_s", "n_buffered",
                 "n_written", "scaled", "spec")

    def __init__(self, spec: StreamSpec, entry: str, datasets: dict[str, h5py.Dataset]) -> None:
        self.spec = spec
        self.entry = entry
        self.datasets = datasets
        self.dtypes = {name: np.dtype(c.dtype) for name, c in spec.columns.items()}
        self.scaled = {name: c for name, c in spec.columns.items() if c.scale is not None}
        self.buffers: dict[str, list[NDArray[Any]]] = {name: [] for name in spec.columns}
        self.n_buffered = 0
        self.n_written = 0
        self.last_time_s = -math.inf


@dataclass
class Layout:
    """What :func:`create_layout` made: the streams' states, the commit entries and tables."""

    streams: dict[tuple[str, str], StreamState]
    truth_streams: dict[tuple[str, str], StreamState]
    entries: list[str]
    commit_rows: h5py.Dataset
    tables: StepLogTables


def check_stream_specs(specs: Sequence[StreamSpec], what: str) -> list[StreamSpec]:
    """Return `specs` as a list, refusing non-specs and a stream declared twice."""
    out: list[StreamSpec] = []
    seen: set[tuple[str, str]] = set()
    for spec in specs:
        if not isinstance(spec, StreamSpec):
            raise InvalidInputError(f"`{what}` must hold StreamSpec objects; "
                                    f"got {type(spec).__name__}")
        key = (spec.device, spec.unit)
        if key in seen:
            raise InvalidInputError(f"`{what}` declares stream {spec.name} twice")
        seen.add(key)
        out.append(spec)
    return out


def check_truth(truth: Mapping[str, Any] | None) -> dict[str, tuple[str, Any]]:
    """Return each truth value as ``("array", ndarray)`` or ``("json", text)``."""
    if truth is None:
        return {}
    if not isinstance(truth, Mapping):
        raise InvalidInputError(f"`truth` must be a mapping; got {type(truth).__name__}")
    items: dict[str, tuple[str, Any]] = {}
    for key, value in truth.items():
        check_key(key, "truth key")
        if isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
            items[key] = ("array", value)
        else:
            items[key] = ("json", json_dumps(value, f"truth[{key!r}]"))
    return items


def create_layout(f: h5py.File, meta: Mapping[str, Any], stream_specs: Sequence[StreamSpec],
                  truth_specs: Sequence[StreamSpec], truth_items: Mapping[str, tuple[str, Any]],
                  chunk_rows: int, compression: str | None) -> Layout:
    """Lay out a new Recording in the empty file `f` (before SWMR starts).

    The format version is the plain one (2) unless a column is scaled or the file is to be
    compressed with a filter that needs a plugin (docs/recording-format.md, versions).
    """
    f.attrs["format"] = FORMAT_NAME
    scaled = any(c.scale is not None for spec in (*stream_specs, *truth_specs)
                 for c in spec.columns.values())
    version = FORMAT_VERSION if scaled or needs_plugin(compression) else FORMAT_VERSION_PLAIN
    f.attrs["format_version"] = np.int64(version)
    f.attrs["created_utc"] = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")
    f.attrs["software_version"] = __version__
    for key, value in meta.items():
        f.attrs[key] = value
    f.create_group(STREAMS_GROUP)
    entries: list[str] = []
    streams: dict[tuple[str, str], StreamState] = {}
    truth_streams: dict[tuple[str, str], StreamState] = {}
    for spec in stream_specs:
        st = create_stream(f, STREAMS_GROUP, spec, chunk_rows)
        streams[(spec.device, spec.unit)] = st
        entries.append(st.entry)
    if truth_items or truth_specs:
        tg = f.create_group(TRUTH_GROUP)
        for key, (kind, value) in truth_items.items():
            if kind == "array":
                tg.require_group("arrays").create_dataset(key, data=value)
            else:
                tg.attrs[f"{key}_json"] = value
        f.create_group(TRUTH_STREAMS_GROUP)
        for spec in truth_specs:
            st = create_stream(f, TRUTH_STREAMS_GROUP, spec, chunk_rows)
            truth_streams[(spec.device, spec.unit)] = st
            entries.append(st.entry)
    sg = f.create_group(STEPS_GROUP)
    create_table(sg, STEP_FIELDS, STEPS_CHUNK_ROWS)
    lg = f.create_group(LOG_GROUP)
    create_table(lg, LOG_FIELDS, LOG_CHUNK_ROWS)
    entries += [STEPS_GROUP, LOG_GROUP]
    cg = f.create_group(COMMIT_GROUP)
    cg.attrs["entries_json"] = json_dumps(entries, "commit entries")
    rows = cg.create_dataset("rows", data=np.zeros(len(entries), dtype=np.int64))
    return Layout(streams, truth_streams, entries, rows, StepLogTables(sg, lg))


def create_stream(f: h5py.File, base: str, spec: StreamSpec, chunk_rows: int) -> StreamState:
    """Create one stream's group and column datasets (uncompressed while written)."""
    group = f.create_group(f"{base}/{spec.device}/{spec.unit}")
    group.attrs["device"] = spec.device
    group.attrs["unit"] = spec.unit
    group.attrs["columns_json"] = json_dumps(
        [column_json(name, c) for name, c in spec.columns.items()], "columns")
    datasets: dict[str, h5py.Dataset] = {}
    for name, col in spec.columns.items():
        dt = np.dtype(col.dtype)
        ds = group.create_dataset(
            name, shape=(0,), maxshape=(None,), chunks=(chunk_rows,), dtype=dt,
            fillvalue=np.nan if dt.kind == "f" else None)
        ds.attrs["unit"] = col.unit
        ds.attrs["quantity"] = col.quantity
        ds.attrs["description"] = col.description
        if col.scale is not None:
            ds.attrs["scale"] = np.float64(col.scale)
        datasets[name] = ds
    return StreamState(spec, f"{base}/{spec.device}/{spec.unit}", datasets)


def open_stream(f: h5py.File, entry: str) -> StreamState:
    """Return the state of a stream of an existing file (its rows already written)."""
    group = f[entry]
    cols = json.loads(decode_attr(group.attrs["columns_json"]))
    spec = StreamSpec(decode_attr(group.attrs["device"]), decode_attr(group.attrs["unit"]),
                      {c["name"]: ColumnSpec(c["unit"], c["dtype"], c["quantity"],
                                             c["description"], c.get("scale"))
                       for c in cols if c["name"] != TIME_COLUMN})
    datasets = {name: group[name] for name in spec.columns}
    st = StreamState(spec, entry, datasets)
    n = datasets[TIME_COLUMN].shape[0]
    st.n_written = n
    if n:
        st.last_time_s = float(datasets[TIME_COLUMN][n - 1])
    return st


def column_compression(f: h5py.File) -> tuple[bool, str | None]:
    """Whether any stream column of an open Recording is filtered, and its compression name."""
    found: list[h5py.Dataset] = []

    def visit(_: str, obj: Any) -> None:
        if isinstance(obj, h5py.Dataset) and obj._filters:
            found.append(obj)

    for base in (STREAMS_GROUP, TRUTH_STREAMS_GROUP):
        group = f.get(base)
        if isinstance(group, h5py.Group):
            group.visititems(visit)
    return bool(found), (compression_of(found[0]) if found else None)
