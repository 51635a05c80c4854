"""The exception and warning hierarchy of imucalib.

Every error raised on bad input names what was expected and what was received. Library code never
prints; the command line renders these.

Hierarchy
---------
- :class:`CalibrationError` (base of everything imucalib raises)
  - :class:`InvalidInputError` (also a ``ValueError``): malformed arrays, NaN, bad shapes, bad plans
    - :class:`UnitError`: unknown or mismatched units
    - :class:`ConfigurationError`: a model, scenario or station description that cannot be used
    - :class:`LimitExceededError`: a command or parameter outside a device or plan limit
  - :class:`InsufficientExcitationError`: a rank-deficient design; names the unobservable parameters
  - :class:`ConvergenceError`: an iterative solver that stopped before converging
  - :class:`RecordingError`: a recording that cannot be written or read
    - :class:`MissingSegmentError`: a segment the analysis needs is missing or unusable
    - :class:`SaturationError`: samples the analysis needs reached the sensor's range
    - :class:`RecordingFormatError`: not an imucalib recording, or a newer format version
    - :class:`RecordingCorruptError`: truncated or damaged file
    - :class:`RecordingOpenForWriteError`: a file a crashed writer left open
      (use ``imucalib recover``)
    - :class:`StorageFullError`: no room left to write (the file is closed cleanly)
    - :class:`RecordingWriteError`: HDF5 failed to write a file (the file is given up unclosed)
  - :class:`DeviceError`: equipment faults
    - :class:`DeviceTimeoutError` (also a ``TimeoutError``)
  - :class:`GuardTripError`: a guard stopped a step
  - :class:`RecordsError`: the calibration records database (unreachable, a newer schema,
    an unknown serial or record)
- :class:`CalibrationWarning` (a ``UserWarning``)
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = [
    "CalibrationError",
    "CalibrationWarning",
    "ConfigurationError",
    "ConvergenceError",
    "DeviceError",
    "DeviceTimeoutError",
    "GuardTripError",
    "InsufficientExcitationError",
    "InvalidInputError",
    "LimitExceededError",
    "MissingSegmentError",
    "RecordingCorruptError",
    "RecordingError",
    "RecordingFormatError",
    "RecordingOpenForWriteError",
    "RecordingWriteError",
    "RecordsError",
    "SaturationError",
    "StorageFullError",
    "UnitError",
]


class CalibrationError(Exception):
    """Base class of every exception imucalib raises."""


class InvalidInputError(CalibrationError, ValueError):
    """Input that does not meet the documented contract (shape, finiteness, range, type)."""


class UnitError(InvalidInputError):
    """An unknown unit, or data in units other than those a function or result expects."""


class ConfigurationError(InvalidInputError):
    """A model, scenario, plan or station description that is inconsistent or incomplete."""


class LimitExceededError(InvalidInputError):
    """A command or parameter outside a device's or plan's limit."""


class InsufficientExcitationError(CalibrationError):
    """A design that cannot identify some parameters.

    Parameters
    ----------
    unobservable : sequence of str
        Names of the parameters (or parameter combinations) that the data cannot determine.
    message : str, optional
        Extra context; a default naming the parameters is built when omitted.
    """

    def __init__(self, unobservable: Sequence[str], message: str | None = None) -> None:
        self.unobservable = tuple(unobservable)
        text = message or (
            "the design does not excite these parameters: " + ", ".join(self.unobservable)
        )
        super().__init__(text)


class ConvergenceError(CalibrationError):
    """An iterative solver (nonlinear least squares, …) stopped before meeting its tolerances."""


class RecordingError(CalibrationError):
    """A recording that cannot be written or read."""


class MissingSegmentError(RecordingError):
    """A segment an analysis needs is missing or unusable.

    An orientation, a turning direction or a temperature point that is not there, or one that
    cannot be used (dropouts, too few revolutions).
    """


class SaturationError(RecordingError):
    """Recorded samples an analysis needs reached the sensor's range (flagged saturated).

    A mean over clipped samples is wrong by an unknown amount; the analysis refuses it and
    names the unit and the step.
    """


class RecordingFormatError(RecordingError):
    """A file that is not an imucalib recording, or one of an unsupported format version."""


class RecordingCorruptError(RecordingError):
    """A recording that is truncated or damaged beyond what ``imucalib recover`` can mend."""


class RecordingOpenForWriteError(RecordingError):
    """A recording still marked open by a crashed writer; ``imucalib recover FILE`` fixes it."""


class StorageFullError(RecordingError):
    """Too little room left on the disk (or under the file-size limit) to write a Recording.

    Raised before the write that would not fit, so the file stays consistent and closes
    cleanly with everything written so far; ``imucalib run --resume FILE`` continues once
    space is freed.
    """


class RecordingWriteError(RecordingError):
    """HDF5 failed to write, flush or close a file (ENOSPC or EIO behind the free-space checks).

    The file was given up unclosed, as a killed writer leaves it (``imucalib run --resume
    FILE`` or ``imucalib recover FILE`` finish a Recording; a temporary copy is removed), and
    the process must end with :func:`os._exit` after reporting it
    (:func:`imucalib.io.recording.abandoned_files`; ``docs/reliability.md``).
    """


class DeviceError(CalibrationError):
    """A fault reported by, or detected on, a piece of equipment."""


class DeviceTimeoutError(DeviceError, TimeoutError):
    """A device that did not answer within its time-out."""


class GuardTripError(CalibrationError):
    """A guard stopped a step (table drift, rate error, saturation, counter gap, …)."""


class RecordsError(CalibrationError):
    """The calibration records database cannot do what was asked (docs/records.md).

    An unreachable database URL, a schema newer than this software, an unknown serial number or
    record id, an amendment of a result that was already amended.
    """


class CalibrationWarning(UserWarning):
    """Something the user should know that does not stop the computation."""
