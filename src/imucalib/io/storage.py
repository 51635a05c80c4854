"""Room left for a file to grow: free space on its filesystem and the process's file-size limit.

Contents
--------
:func:`room_bytes`
    Bytes a file may still grow by before a write fails.
:func:`format_bytes`
    A byte count for messages ("412 MB", "1.3 GB").
:data:`DEFAULT_RESERVE_BYTES`
    Room a Recording keeps free so that it can always close cleanly.

Why this exists: HDF5 cannot recover from a failed write. Once a write has failed for lack of
space, closing the file fails too and the library may crash the process at exit, so the writer
checks the room *before* each block write and refuses a write that would leave less than a
reserve (``docs/reliability.md``). Two limits apply to a write: the free space of the
filesystem available to unprivileged users (``statvfs`` ``f_bavail``), and the soft
``RLIMIT_FSIZE`` of the process (a write past it fails with ``EFBIG``).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["DEFAULT_RESERVE_BYTES", "format_bytes", "room_bytes"]

#: Room a Recording keeps free so that its last flush and close always succeed [bytes].
DEFAULT_RESERVE_BYTES = 4 << 20


def _fsize_limit() -> int | None:
    """Return the soft RLIMIT_FSIZE of this process, or None when unlimited (or unknown)."""
    try:
        import resource
    except ImportError:  # not on POSIX
        return None
    soft, _ = resource.getrlimit(resource.RLIMIT_FSIZE)
    return None if soft == resource.RLIM_INFINITY or soft < 0 else int(soft)


def room_bytes(path: str | os.PathLike[str], *, file_size_bytes: int | None = None) -> int:
    """Return how many bytes the file at `path` can still grow by. [bytes]

    Parameters
    ----------
    path : str or Path
        The file (it may not exist yet; its folder must).
    file_size_bytes : int, optional
        The size the file already takes or has reserved, when larger than what the filesystem
        reports (HDF5 allocates space before it writes it: its end of allocation). [bytes]

    Returns
    -------
    int
        ``min(free space for unprivileged users − (file_size_bytes − size on disk),
        RLIMIT_FSIZE − file_size_bytes)``, never negative.
    """
    p = Path(path)
    folder = p.parent if str(p.parent) else Path(".")
    st = os.statvfs(folder)
    try:
        on_disk = p.stat().st_size
    except FileNotFoundError:
        on_disk = 0
    size = max(on_disk, file_size_bytes or 0)
    room = int(st.f_bavail) * int(st.f_frsize) - (size - on_disk)
    limit = _fsize_limit()
    if limit is not None:
        room = min(room, limit - size)
    return max(room, 0)


def format_bytes(n: float) -> str:
    """Format a byte count with a decimal prefix, e.g. ``"412 MB"``."""
    n = float(n)
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if abs(n) >= scale:
            value = n / scale
            return f"{value:.3g} {unit}" if value < 100 else f"{value:.0f} {unit}"
    return f"{n:.0f} B"
