"""The Recording (crash-safe HDF5 file of a station run): writer, reader, recovery.

Contents
--------
:class:`RecordingWriter`, :class:`StreamSpec`, :class:`ColumnSpec`
    Write a Recording (:mod:`imucalib.io.recording`, which documents the file format).
:func:`open_recording`
    Open one for reading, after checking its layout and time bases (:mod:`imucalib.io.opening`).
:class:`Recording`, :class:`StreamInfo`, :class:`StreamData`, :class:`StepRecord`,
:class:`LogEvent`
    Read it (:mod:`imucalib.io.reader`).
:class:`EventKind`
    The kinds of station event in a Recording's log: remount, swap, load
    (:mod:`imucalib.io.events`).
:func:`recover_recording`, :class:`RecoveryReport`, :func:`compact_recording`
    Copy what a crashed writer flushed into a cleanly closed file; rewrite a closed one with
    another compression (:mod:`imucalib.io.recover`).

A stream or a step of it is exported to CSV or MAT by :mod:`imucalib.exports.streams`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from imucalib._lazy import lazy_getattr

if TYPE_CHECKING:
    from imucalib.io.events import EventKind
    from imucalib.io.opening import open_recording
    from imucalib.io.reader import LogEvent, Recording, StepRecord, StreamData, StreamInfo
    from imucalib.io.recording import (
        FORMAT_NAME,
        FORMAT_VERSION,
        ColumnSpec,
        RecordingWriter,
        StreamSpec,
    )
    from imucalib.io.recover import (
        RecoveredStream,
        RecoveryReport,
        compact_recording,
        recover_recording,
    )

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "ColumnSpec",
    "EventKind",
    "LogEvent",
    "Recording",
    "RecordingWriter",
    "RecoveredStream",
    "RecoveryReport",
    "StepRecord",
    "StreamData",
    "StreamInfo",
    "StreamSpec",
    "compact_recording",
    "open_recording",
    "recover_recording",
]

#: Module of each public name, imported on first access (PEP 562): importing one module of this
#: package (the file hash, the step file) imports neither h5py nor the reader.
__getattr__ = lazy_getattr(__name__, {
    "EventKind": "imucalib.io.events",
    "open_recording": "imucalib.io.opening",
    **dict.fromkeys(("LogEvent", "Recording", "StepRecord", "StreamData", "StreamInfo"),
                    "imucalib.io.reader"),
    **dict.fromkeys(("FORMAT_NAME", "FORMAT_VERSION", "ColumnSpec", "RecordingWriter",
                     "StreamSpec"), "imucalib.io.recording"),
    **dict.fromkeys(("RecoveredStream", "RecoveryReport", "compact_recording",
                     "recover_recording"), "imucalib.io.recover"),
})
