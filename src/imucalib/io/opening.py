"""Open a Recording: check its layout and time bases, first in a time-limited probe.

Contents
--------
:func:`open_recording`
    Open a Recording for reading (a context manager, :class:`~imucalib.io.reader.Recording`),
    including one a crashed writer left open.
:func:`open_damaged`
    Open one even if its layout or time bases are damaged (for recovery, private to
    :mod:`imucalib.io.recover`).

Opening validates the file (:mod:`imucalib.io._validate`; ``docs/recording-format.md``,
"Validation when a file is opened"): the layout, the commit counts, the committed rows of the
steps and log, and every stream's committed time base. The layout is first read in a forked
child process with a time limit (:mod:`imucalib.io._probe`; ``docs/recording-format.md``,
"Hangs and crashes inside HDF5"), because damaged HDF5 metadata can make the HDF5 library hang
or crash; a file whose seal holds (:mod:`imucalib.io._seal`: its metadata byte for byte what
such a probe read soundly when it was compacted or recovered) is checked in this process. The
time columns the check reads whole are kept for the reader's first read of them. Every
problem becomes a :class:`~imucalib.errors.RecordingError` with one line naming the file, what
was found and what was expected. What the opened file reads, and how, is
:mod:`imucalib.io.reader`'s.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from pathlib import Path

import h5py
import numpy as np
from numpy.typing import NDArray

from imucalib.errors import RecordingCorruptError, RecordingError, RecordingOpenForWriteError
from imucalib.io._open import open_h5
from imucalib.io._probe import run_probe
from imucalib.io._schema import FORMAT_VERSION
from imucalib.io._seal import is_sealed
from imucalib.io._validate import (
    H5PY_ERRORS,
    Layout,
    check_layout,
    check_root,
    check_time_bases,
    from_h5py,
    h5call,
    touch_all,
)
from imucalib.io.compression import register_plugin_filters
from imucalib.io.reader import Recording

__all__ = ["open_damaged", "open_recording", "reopening"]

#: The time columns the time-base check reads whole (those that fit its block) are kept for
#: the reader's first read of them, up to this many bytes a file (docs/recording-format.md,
#: "Cost of opening"): the field calibration, P3 and the tumble read a stream whole.
KEEP_TIME_BYTES = 4 << 20

#: Inside :func:`reopening`: the files validated (probe, layout, time bases) and found sound in
#: this scope, by their identity (:func:`_identity`), with the layout found.
_SCOPE: ContextVar[dict[tuple[object, ...], Layout] | None] = ContextVar("_SCOPE", default=None)


@contextlib.contextmanager
def reopening() -> Iterator[None]:
    """Within this block, opening again a file already opened and validated skips the checks.

    For code that opens the same recording several times in one task (a P2 batch opens each
    file to list its units, then to analyse them): the second open of a file whose identity
    (path, inode, size, modification and change times) is unchanged reuses the layout the first
    found valid instead of probing and checking it again. Scoped, not process-wide: a file
    rewritten in place within the timestamps' granularity would otherwise look unchanged.
    """
    token = _SCOPE.set({} if _SCOPE.get() is None else _SCOPE.get())
    try:
        yield
    finally:
        _SCOPE.reset(token)


def _identity(p: Path) -> tuple[object, ...] | None:
    """Return what changes when a file is written or replaced: path, inode, size, times."""
    try:
        st = p.stat()
        return (str(p.resolve()), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns,
                st.st_ctime_ns)
    except OSError:
        return None


def _remembered(key: tuple[object, ...] | None) -> Layout | None:
    scope = _SCOPE.get()
    return None if scope is None or key is None else scope.get(key)


def _remember(key: tuple[object, ...] | None, p: Path, layout: Layout) -> None:
    """Keep `layout` in the scope if the file still has identity `key` after the checks."""
    scope = _SCOPE.get()
    if scope is not None and key is not None and _identity(p) == key:
        scope[key] = layout


def open_recording(path: str | os.PathLike[str], *, strict: bool = False, probe: bool = True,
                   probe_timeout_s: float | None = None) -> Recording:
    """Open a Recording for reading, after checking its layout and time bases.

    A file left open by a crashed (or still running) writer is opened in SWMR-read mode and
    ``recording.was_open_for_write`` is set; it then shows every row flushed before the crash.

    Opening validates the file (see ``docs/recording-format.md``): root attributes, groups,
    commit counts, stream columns, the committed rows of the steps and log, and every stream's
    committed ``time_s`` (finite, never decreasing, in ``[0, 1e9]`` s). Any problem raises a
    typed error naming the file, what was found and what was expected.

    Parameters
    ----------
    path : str or Path
        The ``.h5`` file.
    strict : bool
        Refuse a file a writer left open instead of reading it.
    probe : bool
        Read the file's metadata first in a forked child process that is killed after
        `probe_timeout_s` (damaged HDF5 metadata can make the HDF5 library hang or crash; the
        probe turns that into :class:`RecordingCorruptError`). It costs about 20 ms
        (docs/recording-format.md, "Cost of opening"); a sealed file needs none, its checks
        running in this process (:mod:`imucalib.io._seal`).
    probe_timeout_s : float, optional
        Time limit of the probe [s]; default :data:`imucalib.io._probe.PROBE_TIMEOUT_S` (10 s).

    Returns
    -------
    Recording
        Use it as a context manager, or call :meth:`Recording.close`.

    Raises
    ------
    RecordingError
        If the file does not exist.
    RecordingFormatError
        A foreign HDF5 file (the message names what it holds) or a newer ``format_version``.
    RecordingCorruptError
        A truncated, garbage or damaged file; the message says what is wrong and, where it
        helps, suggests ``imucalib recover``.
    RecordingOpenForWriteError
        With ``strict=True``, for a file a writer left open.
    """
    rec, _ = _open(Path(path), strict=strict, probe=probe, probe_timeout_s=probe_timeout_s,
                   lenient=False)
    return rec


def open_damaged(path: Path, *, probe: bool = True, probe_timeout_s: float | None = None
                 ) -> tuple[Recording, RecordingCorruptError | None]:
    """Open a Recording even if its layout or time bases are damaged (for recovery; private).

    Returns the Recording (its cached layout is empty when damaged, so that it reads the file
    as it is) and the damage found, if any. Foreign, newer, unopenable files and files that
    make HDF5 hang or crash still raise.
    """
    return _open(path, strict=False, probe=probe, probe_timeout_s=probe_timeout_s, lenient=True)


def _checked_layout(p: Path, f: h5py.File, lenient: bool
                    ) -> Layout | RecordingCorruptError:
    try:
        return check_layout(p, f)
    except RecordingCorruptError as exc:
        if not lenient:
            raise
        return exc


def _probe_work(p: Path, lenient: bool) -> Callable[[Callable[[str], None]],
                                                   Layout | RecordingCorruptError]:
    """Make the work of a probe's child: the layout check, with `lenient` (recovery) a walk.

    The reader reads nothing the layout check and the root attributes do not cover; recovery
    also copies every dataset's attributes, so it walks the whole file first.
    """
    def work(progress: Callable[[str], None]) -> Layout | RecordingCorruptError:
        f, _ = _open_h5(p)
        progress("the root attributes")
        _root_version(p, f, lenient)  # a foreign file goes no further
        if lenient:
            touch_all(f, progress)
        else:
            h5call(p, "the root attributes", lambda: dict(f.attrs.items()))
        progress("the layout (groups, commit counts, stream columns, steps, log, truth)")
        return _checked_layout(p, f, lenient)
    return work


def _sealed_work(p: Path, f: h5py.File) -> Callable[[Callable[[str], None]], Layout]:
    """Make the checks of a sealed file, run in this process on its open file `f`.

    The checks of :func:`_probe_work` less what a probe reads only to show that HDF5 can (the
    root attributes, the steps' and log's fields no check looks into): the seal shows it, the
    bytes HDF5 parses being those a probe read soundly (:mod:`imucalib.io._seal`).
    """
    def work(progress: Callable[[str], None]) -> Layout:
        progress("the layout (groups, commit counts, stream columns, steps, log, truth)")
        return check_layout(p, f, sealed=True)
    return work


def _root_version(p: Path, f: h5py.File, lenient: bool) -> int:
    """Return the format version; with `lenient`, a damaged one counts as the current one."""
    try:
        return check_root(p, f)
    except RecordingCorruptError:
        if not lenient:
            raise
        return FORMAT_VERSION


def _open_h5(p: Path) -> tuple[h5py.File, bool]:
    try:
        return open_h5(p)
    except H5PY_ERRORS as exc:
        if isinstance(exc, RecordingError) or not from_h5py(exc):
            raise
        raise RecordingCorruptError(f"{p} cannot be opened by HDF5 ({exc}); it is damaged"
                                    ) from exc


def _open(p: Path, *, strict: bool, probe: bool, probe_timeout_s: float | None, lenient: bool
          ) -> tuple[Recording, RecordingCorruptError | None]:
    key = None if lenient or _SCOPE.get() is None else _identity(p)
    known = _remembered(key)
    if known is not None:  # validated before by this process, and unchanged since
        f, was_open = _open_h5(p)
        if not was_open:
            try:
                register_plugin_filters(f)
                return Recording(f, p, known.format_version, was_open_for_write=False,
                                 layout=known), None
            except BaseException:
                f.close()
                raise
        f.close()
    sealed = probe and not lenient and is_sealed(p)
    found = (run_probe(p, _probe_work(p, lenient), timeout_s=probe_timeout_s)
             if probe and not sealed else None)
    f, was_open = _open_h5(p)
    try:
        register_plugin_filters(f)  # imports hdf5plugin only for a file that needs it (Blosc)
        if strict and was_open:
            raise RecordingOpenForWriteError(
                f"{p} is still marked open for writing (its writer crashed, was killed while "
                f"closing, or is still running); `imucalib run --resume {p}` finishes a station "
                f"run (it recovers and closes the file first), `imucalib recover {p}` copies "
                "what was flushed into a cleanly closed file, or open it with strict=False to "
                "read it in SWMR mode")
        if sealed:  # its metadata is byte for byte what a probe read soundly when it was
            # written (imucalib.io._seal): the checks run here on this file, without the fork
            found = run_probe(p, _sealed_work(p, f), fork=False)
        if found is None:
            found = _checked_layout(p, f, lenient)
        damage = found if isinstance(found, RecordingCorruptError) else None
        layout = None if isinstance(found, RecordingCorruptError) else found
        times: dict[str, NDArray[np.float64]] = {}
        if layout is not None:
            try:
                # a file being written grows: only a closed one's time columns are kept
                times = check_time_bases(p, f, layout.streams,
                                         keep_bytes=0 if was_open else KEEP_TIME_BYTES)
            except RecordingCorruptError as exc:
                if not lenient:
                    raise
                damage, layout = exc, None
        version = (layout.format_version if layout is not None
                   else _root_version(p, f, lenient))
        rec = Recording(f, p, version, was_open_for_write=was_open, layout=layout,
                        times=times)
        if layout is not None and not was_open and damage is None:
            _remember(key, p, layout)
    except BaseException:
        f.close()
        raise
    return rec, damage
