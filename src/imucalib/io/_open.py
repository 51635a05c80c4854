"""Open an HDF5 file as a Recording: diagnose damage, fall back to SWMR, check the format (private).

A file that a writer left open (crashed, or still running) keeps HDF5's "open for write" flag in
its superblock, and HDF5 refuses a normal open; it is then opened in SWMR-read mode. A cleanly
closed file shorter than the end-of-file address in its superblock is reported as truncated
before HDF5 gets to it (in SWMR mode HDF5 would otherwise read zeros past the cut).
"""

from __future__ import annotations

import os
import struct
from dataclasses import dataclass
from pathlib import Path

import h5py

from imucalib import __version__
from imucalib.errors import RecordingCorruptError, RecordingError, RecordingFormatError
from imucalib.io._schema import FORMAT_NAME, FORMAT_VERSION, decode_attr

__all__ = ["check_format", "marked_open_for_write", "open_h5"]

_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


@dataclass(frozen=True)
class _Superblock:
    version: int
    open_for_write: bool
    eof_address: int | None


def _read_superblock(path: Path) -> _Superblock | None:
    """Parse the HDF5 superblock enough to tell truncation and the open-for-write flag apart."""
    with open(path, "rb") as fh:
        for offset in (0, 512, 1024, 2048, 4096):
            fh.seek(offset)
            head = fh.read(48)
            if head[:8] != _HDF5_SIGNATURE:
                continue
            version = head[8] if len(head) > 8 else -1
            if version in (2, 3) and len(head) >= 36 and head[9] == 8:
                flags = head[11]
                (eof,) = struct.unpack_from("<Q", head, 28)
                return _Superblock(version, bool(flags & 0x05), offset + eof)
            return _Superblock(version, False, None)
    return None


def marked_open_for_write(path: str | os.PathLike[str]) -> bool:
    """Whether the file's superblock says a writer holds it (read from the bytes on disk).

    Unlike an HDF5 open, this also sees a writer in the same process (HDF5 shares an open file
    between handles of one process, so a second open there succeeds).
    """
    sb = _read_superblock(Path(path))
    return sb is not None and sb.open_for_write


#: HDF5's chunk cache per open dataset of a file opened for reading (HDF5 2.0 defaults to
#: 8 MiB). A Recording keeps a column's dataset open from one window to the next so the chunk
#: two windows share is decompressed once, and the row search's probes (the time column's
#: first and last rows, then the probe's chunk) stay cached from one search to the next: 2 MiB
#: holds four 512 KiB chunks of a float64 column (eight of an int32 one), as fast as 4 and
#: 8 MiB on the bench's analyses, while 1 MiB (two float64 chunks: the probes evict each
#: other) made P1 9–33 % slower. With the sixteen columns of a P1 file open the caches hold at
#: most 32 MiB (64 MiB at 4 MiB): the memory that grew with a recording's length
#: (docs/performance.md, "Memory and the chunk cache").
CHUNK_CACHE_BYTES = 1 << 21


def open_h5(path: str | os.PathLike[str]) -> tuple[h5py.File, bool]:
    """Open an HDF5 file read-only, in SWMR mode if a writer left it open (package-private).

    Returns the file and whether it was open for write.
    """
    p = Path(path)
    if not p.is_file():
        raise RecordingError(f"no such recording: {p}")
    size = p.stat().st_size
    sb = _read_superblock(p)
    if sb is None:
        raise RecordingCorruptError(
            f"{p} is not an HDF5 file (no HDF5 signature in its first bytes; {size} bytes): it is "
            "damaged or not a recording at all")
    if sb.eof_address is not None and size < sb.eof_address and not sb.open_for_write:
        raise RecordingCorruptError(
            f"{p} is truncated: {size} of its {sb.eof_address} bytes are present. Rows past the "
            "cut are lost and HDF5 cannot open the rest; restore the file from a copy (imucalib "
            "recover cannot rebuild a truncated, cleanly closed file)")
    try:
        return h5py.File(p, "r", rdcc_nbytes=CHUNK_CACHE_BYTES), False
    except OSError as exc:
        msg = str(exc)
    if sb.open_for_write or "open for write" in msg:
        try:
            return h5py.File(p, "r", swmr=True, libver="latest",
                             rdcc_nbytes=CHUNK_CACHE_BYTES), True
        except OSError as exc:
            raise RecordingCorruptError(
                f"{p} was left open by a writer and cannot be read even in SWMR mode ({exc})"
            ) from exc
    if "truncated" in msg:
        raise RecordingCorruptError(f"{p} is truncated ({msg}); restore it from a copy")
    raise RecordingCorruptError(f"{p} cannot be opened by HDF5 ({msg}); it is damaged")


def check_format(f: h5py.File, p: Path) -> int:
    fmt = f.attrs.get("format")
    if fmt is None:
        attrs = sorted(f.attrs.keys())[:10]
        objs = sorted(f.keys())[:10]
        raise RecordingFormatError(
            f"{p} is an HDF5 file but not an imucalib recording: its root has no `format` "
            f"attribute (found attributes {attrs} and objects {objs})")
    fmt = decode_attr(fmt)
    if fmt != FORMAT_NAME:
        raise RecordingFormatError(
            f"{p} is not an imucalib recording: its `format` attribute is {fmt!r}, "
            f"expected {FORMAT_NAME!r}")
    raw = decode_attr(f.attrs.get("format_version"))
    if not isinstance(raw, int) or isinstance(raw, bool) or raw < 1:
        raise RecordingFormatError(f"{p} has an invalid `format_version` {raw!r}; "
                                   "expected a positive int")
    if raw > FORMAT_VERSION:
        raise RecordingFormatError(
            f"{p} has format_version {raw}, newer than imucalib {__version__} reads "
            f"(up to {FORMAT_VERSION}); upgrade imucalib")
    return raw
