"""Recover a Recording that a crashed writer left open: copy what it flushed into a clean file.

Contents
--------
:func:`recover_recording`
    Read the file in SWMR mode, copy every readable object into ``<stem>.recovered.h5``,
    verify the copy and return a :class:`RecoveryReport`.
:class:`RecoveryReport`, :class:`RecoveredStream`
    What was copied and what was dropped; ``summary()`` renders it for the CLI.

The original is never modified. Each stream is copied up to its committed row count (see the
``/commit`` entry of the format in :mod:`imucalib.io.recording`), capped by the shortest of its
columns so that they stay aligned; rows a writer had not committed, or that cannot be read, are
dropped and reported. The copy is written to a temporary name, verified (it must open normally,
and every column's SHA-256 must match what was read from the original), then renamed.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import h5py
import numpy as np

from imucalib.errors import InvalidInputError, RecordingCorruptError, RecordingError
from imucalib.io._schema import (
    COMMIT_GROUP,
    LOG_GROUP,
    STEPS_GROUP,
    STREAMS_GROUP,
    TRUTH_GROUP,
    TRUTH_STREAMS_GROUP,
    decode_attr,
)
from imucalib.io.reader import Recording, open_recording

__all__ = ["RecoveredStream", "RecoveryReport", "recover_recording"]

_BLOCK_ROWS = 1 << 20


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


def _like(dst: h5py.Group, name: str, src: h5py.Dataset, n: int) -> h5py.Dataset:
    out = dst.create_dataset(
        name, shape=(n,), maxshape=(None,), chunks=src.chunks, dtype=src.dtype,
        compression=src.compression, compression_opts=src.compression_opts,
        fillvalue=src.fillvalue)
    for key, value in src.attrs.items():
        out.attrs[key] = value
    return out


def _copy_table(src: h5py.Group, dst_file: h5py.File, path: str, names: list[str],
                committed: int | None, hashes: dict[str, str]) -> RecoveredStream:
    """Copy aligned 1-D columns `names` of group `src` into `dst_file[path]`, block by block."""
    dsets = [_refresh(src[c]) for c in names]
    lengths = [d.shape[0] for d in dsets]
    found = max(lengths, default=0)
    n = min(lengths, default=0)
    if committed is not None:
        n = min(n, committed)
    dst = dst_file.require_group(path)
    for key, value in src.attrs.items():
        dst.attrs[key] = value
    outs = [_like(dst, c, d, n) for c, d in zip(names, dsets, strict=True)]
    digests = [hashlib.sha256() for _ in names]
    copied, note = n, ""
    for a in range(0, n, _BLOCK_ROWS):
        b = min(a + _BLOCK_ROWS, n)
        try:
            blocks = [d[a:b] for d in dsets]
        except OSError as exc:
            copied, note = a, f"rows from {a} unreadable: {exc}"
            break
        for out, blk, h in zip(outs, blocks, digests, strict=True):
            out[a:b] = blk
            h.update(np.ascontiguousarray(blk).tobytes())
    if copied < n:
        for out in outs:
            out.resize((copied,))
    elif committed is not None and found > n:
        note = "rows after the last flush"
    for c, h in zip(names, digests, strict=True):
        hashes[f"{path}/{c}"] = h.hexdigest()
    return RecoveredStream(path, copied, found, note)


def _copy(rec: Recording, dst: h5py.File, hashes: dict[str, str]) -> list[RecoveredStream]:
    src: h5py.File = rec._file
    committed = rec.committed_rows()
    for key, value in src.attrs.items():
        dst.attrs[key] = value
    dst.attrs["recovered_from"] = str(rec.path.name)
    dst.attrs["recovered_utc"] = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")
    tables: list[RecoveredStream] = []
    dst.require_group(STREAMS_GROUP)
    if TRUTH_GROUP in src:
        tg = dst.require_group(TRUTH_GROUP)
        for key, value in src[TRUTH_GROUP].attrs.items():
            tg.attrs[key] = value
        if "arrays" in src[TRUTH_GROUP]:
            ag = tg.require_group("arrays")
            for key, ds in src[TRUTH_GROUP]["arrays"].items():
                ag.create_dataset(key, data=ds[()])
        dst.require_group(TRUTH_STREAMS_GROUP)
    for base in (STREAMS_GROUP, TRUTH_STREAMS_GROUP):
        for path in rec._stream_paths(base):
            group = src[path]
            names = [c["name"] for c in json.loads(decode_attr(group.attrs["columns_json"]))]
            tables.append(_copy_table(group, dst, path, names, committed.get(path), hashes))
    for name in (STEPS_GROUP, LOG_GROUP):
        group = src[name]
        tables.append(_copy_table(group, dst, name, list(group), committed.get(name), hashes))
    if COMMIT_GROUP in src:
        entries = json.loads(decode_attr(src[COMMIT_GROUP].attrs["entries_json"]))
        copied = {t.name: t.rows_copied for t in tables}
        cg = dst.create_group(COMMIT_GROUP)
        cg.attrs["entries_json"] = src[COMMIT_GROUP].attrs["entries_json"]
        cg.create_dataset("rows", data=np.array([copied.get(e, 0) for e in entries],
                                                dtype=np.int64))
    return tables


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


def recover_recording(path: str | os.PathLike[str], out_path: str | os.PathLike[str] | None = None,
                      *, overwrite: bool = False) -> RecoveryReport:
    """Copy everything readable of a Recording into a new, cleanly closed file.

    Parameters
    ----------
    path : str or Path
        The Recording, typically one a crashed writer left open. It is only read.
    out_path : str or Path, optional
        Where to write the copy; default ``<stem>.recovered.h5`` beside `path`.
    overwrite : bool
        Replace an existing `out_path`.

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
        If the original cannot be read at all (see :func:`~imucalib.io.reader.open_recording`).
    """
    src = Path(path)
    out = Path(out_path) if out_path is not None else src.with_name(f"{src.stem}.recovered.h5")
    if out.resolve() == src.resolve():
        raise InvalidInputError(f"`out_path` must differ from the original {src}; the original "
                                "is never modified")
    if out.exists() and not overwrite:
        raise RecordingError(f"{out} exists; choose another output path or remove it first")
    tmp = out.with_name(f".{out.name}.partial")
    hashes: dict[str, str] = {}
    with open_recording(src) as rec:
        was_open = rec.was_open_for_write
        try:
            with h5py.File(tmp, "w", libver="latest") as dst:
                tables = _copy(rec, dst, hashes)
            unfinished = tuple(s.index for s in rec.steps if s.status == "running")
            _verify(tmp, tables, hashes)
            os.replace(tmp, out)
        except OSError as exc:
            tmp.unlink(missing_ok=True)
            raise RecordingCorruptError(f"recovering {src} failed: {exc}") from exc
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
    return RecoveryReport(source=src, output=out, was_open_for_write=was_open,
                          tables=tuple(tables), unfinished_steps=unfinished, verified=True)
