"""Run a piece of HDF5 reading in a forked child under a time limit (private).

Damaged HDF5 metadata can make the HDF5 library loop forever (a zeroed object in a global heap
collection, which carries no checksum, is one such case) or crash the process. Python cannot
interrupt a call inside the library, so :func:`run_probe` runs the reading in a forked child
process: the child reports where it is (``progress``) and finally its result, both through a
pipe; the parent waits at most `timeout_s` and kills the child if it has not finished. A child
that hangs becomes :class:`RecordingCorruptError` naming the time limit and what it was reading;
one that dies from a signal becomes :class:`RecordingCorruptError` naming the signal.

Where ``os.fork`` does not exist the work runs in the calling process, unprotected.
h5py's global lock is held across the fork, so that no other thread of the parent can be inside
HDF5 at that moment (the child would otherwise inherit a lock it can never take).
"""

from __future__ import annotations

import faulthandler
import gc
import os
import pickle
import select
import signal
import struct
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from h5py._objects import phil

from imucalib import errors
from imucalib.errors import RecordingCorruptError, RecordingError

__all__ = ["PROBE_TIMEOUT_S", "run_probe"]

_T = TypeVar("_T")

#: Default time limit of a probe [s] (read when a probe starts); valid files take milliseconds.
PROBE_TIMEOUT_S = 10.0

_HEADER = struct.Struct("<cI")  # frame: kind (b"P" progress, b"R" result), payload length


def _send(fd: int, kind: bytes, payload: bytes) -> None:
    data = _HEADER.pack(kind, len(payload)) + payload
    while data:
        data = data[os.write(fd, data):]


def _child(fd: int, work: Callable[[Callable[[str], None]], Any]) -> None:
    """Body of the child: never returns."""
    code = 0
    faulthandler.disable()  # a crash is reported by the parent, not dumped here
    gc.disable()  # free none of the parent's objects here (an HDF5 file could be flushed)
    try:
        try:
            result: tuple[Any, ...] = ("ok", work(lambda what: _send(fd, b"P", what.encode())))
        except RecordingError as exc:
            result = ("error", type(exc).__name__, str(exc))
        except BaseException as exc:  # a bug, not damage: the parent reruns the work itself
            result = ("bug", f"{type(exc).__name__}: {exc}")
        _send(fd, b"R", pickle.dumps(result))
    except BaseException:
        code = 1
    finally:
        os._exit(code)


def _frames(buf: bytearray) -> list[tuple[bytes, bytes]]:
    """Remove and return the complete frames at the start of `buf`."""
    out = []
    while len(buf) >= _HEADER.size:
        kind, n = _HEADER.unpack_from(buf)
        if len(buf) < _HEADER.size + n:
            break
        out.append((kind, bytes(buf[_HEADER.size:_HEADER.size + n])))
        del buf[:_HEADER.size + n]
    return out


def run_probe(path: Path, work: Callable[[Callable[[str], None]], _T], *,
              timeout_s: float | None = None, fork: bool = True) -> _T:
    """Return ``work(progress)`` computed in a forked child within `timeout_s` seconds.

    `timeout_s` defaults to :data:`PROBE_TIMEOUT_S`. With ``fork=False`` (a file whose seal
    says its metadata is what a probe read soundly before, :mod:`imucalib.io._seal`) the work
    runs in this process, as it does where ``os.fork`` does not exist.

    The result must pickle. A :class:`~imucalib.errors.RecordingError` raised by `work` is
    raised again here (same class and message); any other exception in the child makes the
    work run again in this process, so that a bug shows its own traceback.

    Raises
    ------
    RecordingCorruptError
        If the child has not finished within `timeout_s` (it is killed) or died from a signal.
    """
    if not fork or not hasattr(os, "fork"):
        return work(lambda what: None)
    timeout_s = PROBE_TIMEOUT_S if timeout_s is None else float(timeout_s)
    r, w = os.pipe()
    try:
        with phil:  # no other thread may hold HDF5 while we fork
            pid = os.fork()
            if pid == 0:
                os.close(r)
                _child(w, work)
    finally:
        os.close(w)
    buf = bytearray()
    reading = "the file's superblock"
    result: tuple[Any, ...] | None = None
    done = False
    try:
        deadline = time.monotonic() + timeout_s
        while not done:
            left = deadline - time.monotonic()
            if left <= 0:
                raise RecordingCorruptError(
                    f"{path} is damaged: HDF5 did not finish reading its metadata within "
                    f"{timeout_s:g} s (it was reading {reading}) and was stopped; damaged "
                    "metadata can make the HDF5 library loop forever. Neither imucalib nor "
                    "`imucalib recover` can read this file: restore it from a copy")
            if not select.select([r], [], [], left)[0]:
                continue
            chunk = os.read(r, 1 << 16)
            done = not chunk
            buf += chunk
            for kind, payload in _frames(buf):
                if kind == b"P":
                    reading = payload.decode(errors="replace")
                else:
                    result = pickle.loads(payload)  # our own child's bytes
    finally:
        os.close(r)
        if not done:
            os.kill(pid, signal.SIGKILL)
        _, status = os.waitpid(pid, 0)
    if result is None:
        how = (f"signal {signal.Signals(os.WTERMSIG(status)).name}" if os.WIFSIGNALED(status)
               else f"exit status {os.waitstatus_to_exitcode(status)}")
        raise RecordingCorruptError(
            f"{path} is damaged: the HDF5 library crashed ({how}) reading {reading}. Neither "
            "imucalib nor `imucalib recover` can read this file: restore it from a copy")
    if result[0] == "ok":
        return result[1]
    if result[0] == "error":
        cls = getattr(errors, result[1], RecordingCorruptError)
        if not (isinstance(cls, type) and issubclass(cls, RecordingError)):
            cls = RecordingCorruptError
        raise cls(result[2])
    return work(lambda what: None)
