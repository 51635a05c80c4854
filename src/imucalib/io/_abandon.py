"""Give up an HDF5 file after a failed write, so that the process can stop without crashing.

After HDF5 fails to write a file (the disk filled up behind imucalib's free-space checks, the
file system answered EIO), the library can neither flush nor close that file: every later call
that touches it, including the close HDF5 starts when Python frees the last h5py object of the
file, writes again, fails again, and may leave HDF5's caches in a state where the process
crashes (segmentation fault) a moment later. Such a file is therefore *abandoned*:

1. every h5py object that could still reach it is kept alive in :data:`_KEEP_ALIVE` (the
   writer that holds its datasets, the h5py file, and the exception, whose traceback holds the
   temporary objects of the frames the failure went through), so that Python never frees them;
2. no HDF5 call touches the file again;
3. the process ends with :func:`os._exit` after printing its one-line message (the command line
   does it when :func:`abandoned_files` is not empty), skipping the interpreter's and HDF5's
   teardown.

The file is left as a killed writer leaves it: a Recording keeps everything committed before
the failure (``imucalib run --resume FILE`` or ``imucalib recover FILE`` finish it); a
temporary copy (recovery's, compaction's) is removed from its folder.

Contents
--------
:data:`WRITE_ERRORS`
    The exceptions h5py raises when HDF5 fails to write, flush or close a file.
:func:`abandon`, :func:`abandon_copy`
    Abandon a file (a temporary copy: and remove it); return the error to raise, or its text.
:func:`abandoned_files`
    The files this process abandoned.
:func:`watch_freed_objects`, :func:`freed_object_failure`
    Note the writes HDF5 fails while Python frees an h5py object (no caller sees them), so that
    the next flush or close of the file gives it up instead of calling HDF5 (which may crash).
:func:`failure_text`
    HDF5's error message as one line, led by the operating system's reason.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Any, Final

from imucalib.errors import RecordingWriteError

__all__ = [
    "WRITE_ERRORS",
    "abandon",
    "abandon_copy",
    "abandoned_files",
    "failure_text",
    "freed_object_failure",
    "watch_freed_objects",
]

#: What h5py raises when HDF5 fails to write, flush or close a file (``OSError`` for most
#: calls, ``RuntimeError`` for flushes, closes and reference-count decrements).
WRITE_ERRORS: Final = (OSError, RuntimeError)

_ABANDONED: list[Path] = []
_KEEP_ALIVE: list[object] = []  # never freed: freeing them would make HDF5 write again
_ERRNO_TEXT = re.compile(r"error message = '([^']*)'")
_WRITE_FAILED = "file write failed"  # in HDF5's message of every failed write
_FREED_FAILURES: list[BaseException] = []  # failed writes raised while h5py freed an object


def failure_text(exc: BaseException) -> str:
    """Return HDF5's message of a failed call as one line, the system's reason first.

    HDF5 describes a failed write over two lines (``... file write failed: time = <date>``,
    a line break, then ``, filename = ..., errno = 28, error message = 'No space left on
    device', ...``); this returns ``"No space left on device (HDF5: <what HDF5 was
    doing>)"``, or the message with its white space collapsed when it names no system error.
    """
    text = " ".join(str(exc).split()) or type(exc).__name__
    reason = _ERRNO_TEXT.search(text)
    if reason is None:
        return text
    doing = text.split(" (", 1)[0]
    return f"{reason.group(1)} (HDF5: {doing})"


def abandoned_files() -> tuple[Path, ...]:
    """Files this process gave up after HDF5 failed to write them, in order.

    A program that sees any here must end with :func:`os._exit` after printing its message;
    the command line does (``imucalib.cli.main``).
    """
    return tuple(_ABANDONED)


def watch_freed_objects() -> None:
    """Note the writes HDF5 fails while Python frees an h5py object (once per process).

    Freeing the last h5py object of a dataset closes it in HDF5, which may write; a failure
    there cannot reach the caller (Python reports it to :data:`sys.unraisablehook`), and the
    next flush of the file may then crash inside HDF5. The hook installed here notes such a
    failure for :func:`freed_object_failure` and passes it on to the previous hook.
    """
    if getattr(sys.unraisablehook, "imucalib_watch", False):
        return  # installed, and not replaced since
    previous = sys.unraisablehook

    def hook(unraisable: Any) -> None:
        if _WRITE_FAILED in str(unraisable.exc_value):
            _FREED_FAILURES.append(unraisable.exc_value)
        previous(unraisable)

    hook.imucalib_watch = True  # type: ignore[attr-defined]
    sys.unraisablehook = hook


def freed_object_failure(path: Path) -> BaseException | None:
    """Return the first failed write to `path` noted while h5py freed an object, if any."""
    name = f"filename = '{path}'"
    return next((exc for exc in _FREED_FAILURES if name in str(exc)), None)


def _mute_teardown(path: Path) -> None:
    """Drop the errors HDF5 raises if Python frees an object of an abandoned file anyway.

    They repeat the failed write (reported once already), printed by Python as "Exception
    ignored in ... __dealloc__" with a traceback; every other unraisable exception still reaches
    the previous hook.
    """
    previous = sys.unraisablehook
    name = str(path)

    def hook(unraisable: Any) -> None:
        if name in str(unraisable.exc_value) or _WRITE_FAILED in str(unraisable.exc_value):
            return
        previous(unraisable)

    sys.unraisablehook = hook


def abandon(path: Path, message: str, exc: BaseException | None,
            *objects: object) -> RecordingWriteError:
    """Abandon `path` after HDF5 failed on it, and return the error to raise.

    Parameters
    ----------
    path : Path
        The file HDF5 failed to write.
    message : str
        The one-line message of the returned error (what failed, what is left, what to do).
    exc : BaseException, optional
        The h5py exception; kept alive with its traceback (the frames hold h5py objects).
    *objects : object
        Everything else that holds h5py objects of the file (the writer, the h5py file).

    Returns
    -------
    RecordingWriteError
        To be raised (``raise abandon(...) from exc``).
    """
    _KEEP_ALIVE.extend(objects)
    if exc is not None:
        _KEEP_ALIVE.append(exc)
    if path not in _ABANDONED:
        _ABANDONED.append(path)
        _mute_teardown(path)
    return RecordingWriteError(" ".join(message.split()))


def abandon_copy(tmp: Path, what: str, exc: BaseException, *objects: object) -> str:
    """Abandon a temporary copy (recovery's, compaction's) after a failed write, and remove it.

    Returns the failure as one line (:func:`failure_text`), for the caller's message; the
    caller raises a :class:`~imucalib.errors.RecordingWriteError` of its own.
    """
    abandon(tmp, what, exc, *objects)
    try:
        tmp.unlink(missing_ok=True)
    except OSError:
        pass  # the file system failed: the copy's name is a temporary one, which no reader opens
    return failure_text(exc)
