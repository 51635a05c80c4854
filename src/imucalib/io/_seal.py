"""A recording's seal: its metadata unchanged since it was validated, told by plain reads (private).

Opening a Recording first reads its HDF5 metadata in a forked probe (:mod:`imucalib.io._probe`),
because damaged metadata can make the HDF5 library hang or crash. A file that
:func:`~imucalib.io.recover.compact_recording` or
:func:`~imucalib.io.recover.recover_recording` wrote has been through every check of
:func:`~imucalib.io.opening.open_recording`, the probe included, before it took its name; it is
then *sealed*: an extended attribute of the file (``user.imucalib.seal``; the file's bytes are
not touched) holds its size, the byte ranges of its raw data (the chunks and contiguous
storage of every dataset) and a BLAKE2b digest (RFC 7693) of every other byte — the
superblock, object headers, heaps, B-trees and chunk indexes: everything HDF5 parses as
metadata — and of that description.

:func:`is_sealed` recomputes the digest from plain file reads, before h5py touches the file.
When it matches, the metadata HDF5 will parse is byte for byte what the probe read without
trouble when the file was validated, so the open skips the fork (docs/recording-format.md,
"Cost of opening"); the layout and time-base checks still run, in the process. Any change — a
damaged byte in the metadata, a file opened for writing (its superblock's flag), appended to,
truncated, or edited with another tool, a damaged seal — breaks the digest, and the file is
probed as any other; so is a file without the attribute (a copy that did not keep it, a file
system without extended attributes, a file written before seals). Damage in the raw data is
outside the digest; the probe never read it either (bulk reads cannot hang: their chunk
indexes, which the digest covers, carry checksums), and the time-base check and the reader
still see it.

The attribute's value: a UTF-8 JSON body ``{"version": 1, "size": N, "raw": [[offset,
length], ...]}`` (sorted, merged ranges), then the 32-byte BLAKE2b-256 of the body followed by
the bytes [0, N) of the file outside the ranges.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
from pathlib import Path
from typing import Any

import h5py

from imucalib.io._validate import H5PY_ERRORS

__all__ = ["ATTRIBUTE", "is_sealed", "seal"]

#: The extended attribute that holds the seal.
ATTRIBUTE = "user.imucalib.seal"
_DIGEST_BYTES = 32
#: Bytes read and hashed at a time.
_READ_BYTES = 1 << 20


def _raw_ranges(path: Path) -> list[tuple[int, int]]:
    """Return the sorted, merged byte ranges of every dataset's raw data in `path`."""
    ranges: list[tuple[int, int]] = []

    def chunk(info: Any) -> None:
        if info.size:
            ranges.append((int(info.byte_offset), int(info.size)))

    def visit(_name: str, obj: Any) -> None:
        if not isinstance(obj, h5py.Dataset):
            return
        if obj.chunks is not None:
            obj.id.chunk_iter(chunk)
            return
        offset = obj.id.get_offset()  # contiguous storage; None: compact or not allocated
        if offset is not None and obj.id.get_storage_size():
            ranges.append((int(offset), int(obj.id.get_storage_size())))

    with h5py.File(path, "r") as f:
        f.visititems(visit)
    merged: list[tuple[int, int]] = []
    for start, length in sorted(ranges):
        if merged and start <= merged[-1][0] + merged[-1][1]:
            a, n = merged[-1]
            merged[-1] = (a, max(n, start + length - a))
        else:
            merged.append((start, length))
    return merged


def _digest(fd: int, body: bytes, size: int, raw: list[tuple[int, int]]) -> bytes:
    """BLAKE2b-256 of `body`, then of the bytes [0, size) of `fd` outside the `raw` ranges."""
    h = hashlib.blake2b(body, digest_size=_DIGEST_BYTES)
    at = 0
    for start, length in [*raw, (size, 0)]:
        while at < start:
            n = min(start - at, _READ_BYTES)
            data = os.pread(fd, n, at)
            if len(data) != n:
                raise ValueError("short read")
            h.update(data)
            at += n
        at = max(at, start + length)
    return h.digest()


def seal(path: str | os.PathLike[str]) -> bool:
    """Seal a closed, validated Recording `path` (module docstring); whether it could.

    Only for a file that has just passed every check of
    :func:`~imucalib.io.opening.open_recording` and is not open anywhere. A file system without
    extended attributes (or too small a room for this one), or an HDF5 library that cannot list
    the chunks (``H5Dchunk_iter``, HDF5 1.14), leaves the file unsealed: it is then probed when
    opened, as before seals.

    Raises
    ------
    OSError
        When the file cannot be read.
    """
    p = Path(path)
    try:
        raw = _raw_ranges(p)
    except (*H5PY_ERRORS, AttributeError, NotImplementedError):  # an HDF5 without chunk_iter
        return False
    fd = os.open(p, os.O_RDONLY)
    try:
        size = os.fstat(fd).st_size
        body = json.dumps({"version": 1, "size": size, "raw": raw},
                          separators=(",", ":")).encode()
        value = body + _digest(fd, body, size, raw)
    finally:
        os.close(fd)
    try:
        os.setxattr(p, ATTRIBUTE, value)
    except (OSError, AttributeError):  # no extended attributes here (or not on this system)
        return False
    return True


def _parse(body: bytes, size: int) -> list[tuple[int, int]] | None:
    """Return the seal body's raw ranges, or None when it describes no valid seal of `size`."""
    doc = json.loads(body)
    if not isinstance(doc, dict) or doc.get("version") != 1 or doc.get("size") != size:
        return None
    raw = doc.get("raw")
    if not isinstance(raw, list):
        return None
    ranges: list[tuple[int, int]] = []
    at = 0
    for item in raw:
        if (not isinstance(item, list) or len(item) != 2
                or not all(isinstance(v, int) and not isinstance(v, bool) for v in item)):
            return None
        start, length = item
        if start < at or length <= 0 or start + length > size:
            return None
        ranges.append((start, length))
        at = start + length
    return ranges


def is_sealed(path: str | os.PathLike[str]) -> bool:
    """Whether `path` carries a seal whose digest matches its bytes (module docstring).

    Plain reads only (the attribute, then every byte outside the raw data); never raises: a
    failure to read or parse is "not sealed", and the file is then probed.
    """
    try:
        value = os.getxattr(Path(path), ATTRIBUTE)
        fd = os.open(Path(path), os.O_RDONLY)
    except (OSError, AttributeError):
        return False
    try:
        body, digest = value[:-_DIGEST_BYTES], value[-_DIGEST_BYTES:]
        size = os.fstat(fd).st_size
        raw = _parse(body, size) if len(value) > _DIGEST_BYTES else None
        return raw is not None and hmac.compare_digest(digest, _digest(fd, body, size, raw))
    except (OSError, ValueError, RecursionError):
        return False
    finally:
        os.close(fd)
