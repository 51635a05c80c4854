"""The one calibration pipeline: data → procedure → result → output files → records.

``imucalib calibrate``, ``imucalib allan``, the demo and a user's own script call
:func:`calibrate`; none writes the flow again (docs/architecture.md, "The flow"):

1. which procedure: the one named, else the recording's (its step roles, else its stored
   plan: :func:`~imucalib.procedures.registry.identify`);
2. the analysis: the procedure's ``analyze`` for one recording or log, ``analyze_many`` for
   several recordings analysed as one (a P2 production lot), with the options it takes;
3. the output files: the formats the procedure lists (or those asked for), named
   ``<name>.<unit>.<procedure><suffix>`` (:func:`~imucalib.exports.outputs.write_outputs`);
4. the records: the result, in the run that recorded the data (found by the recording's
   SHA-256; a re-analysis is the result's next version; data no run recorded get a run of
   their own), unless ``record=False``
   (:func:`~imucalib.records.calibrations.record_calibration`, docs/records.md).

The terminal is not part of it: a caller prints the result with the procedure's
``render_console`` hook.

Contents
--------
:class:`Calibration`, :func:`calibrate`, :func:`procedure_of`
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imucalib.errors import CalibrationError, InvalidInputError
from imucalib.models.result import Provenance

if TYPE_CHECKING:
    from imucalib.procedures.common.procedure import Procedure, ProcedureResult

__all__ = ["Calibration", "calibrate", "procedure_of", "provenance_of"]

#: Suffixes of a Recording (every other file is a log that a procedure reads itself).
RECORDING_SUFFIXES = (".h5", ".hdf5")


@dataclass(frozen=True)
class Calibration:
    """What :func:`calibrate` did.

    Attributes
    ----------
    procedure : Procedure
        The procedure that analysed the data (its hooks print and report the result).
    result : ProcedureResult
        The result.
    written : tuple of Path
        The output files, in the order written.
    record : str or None
        The records' line (where the result was recorded, or why it was not); None when
        recording was not asked for or failed.
    record_error : CalibrationError or None
        Why the records refused the result (the files are written all the same: a caller shows
        the result, then the error).
    """

    procedure: Procedure
    result: ProcedureResult
    written: tuple[Path, ...]
    record: str | None
    record_error: CalibrationError | None = None


def procedure_of(data: str | os.PathLike[str], name: str | None = None) -> Procedure:
    """Return the procedure that analyses `data`: the one named, else the recording's.

    Raises
    ------
    ConfigurationError
        An unknown name, or a recording that says no procedure.
    InvalidInputError
        A log (not a Recording) without a named procedure, or for one that reads Recordings
        only.
    """
    from imucalib.io.opening import open_recording
    from imucalib.procedures import registry

    path = Path(data)
    if name is None:
        if path.suffix.lower() not in RECORDING_SUFFIXES:
            raise InvalidInputError(f"{path} is not a Recording: name the procedure that reads "
                                    "such a log (`imucalib calibrate field DATA`), or import it "
                                    "with a step file first (docs/import.md)")
        with open_recording(path) as rec:
            name = registry.identify(rec)
    procedure = registry.get(name)
    if path.suffix.lower() not in RECORDING_SUFFIXES and \
            "import_spec" not in procedure.analysis_options:
        raise InvalidInputError(f"procedure {name} analyses a Recording of its plan; {path} is "
                                "a log (a CSV goes through --steps, docs/import.md)")
    return procedure


def provenance_of(path: Path) -> Provenance:
    """Return where a result of `path` comes from: the file, its SHA-256, its plan's hash.

    For a result that carries no provenance of its own (a calibration carries its own); the
    plan hash is the recording's (:class:`~imucalib.io.context.RecordingContext`), empty for a
    log that is no Recording.
    """
    from datetime import UTC, datetime

    from imucalib import __version__
    from imucalib.io.hashing import file_sha256

    plan_hash = ""
    if path.suffix.lower() in (".h5", ".hdf5"):
        from imucalib.io.context import RecordingContext
        from imucalib.io.opening import open_recording

        with open_recording(path) as rec:
            plan_hash = RecordingContext.of(rec.metadata).plan_hash
    return Provenance(plan_hash=plan_hash, recording=path.name,
                      recording_sha256=file_sha256(path) if path.is_file() else "",
                      software_version=__version__,
                      created_utc=datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"))


def calibrate(data: str | os.PathLike[str], *, procedure: str | None = None,
              options: Mapping[str, Any] | None = None, unit: str | None = None,
              more: Sequence[str | os.PathLike[str]] = (),
              out: str | os.PathLike[str] | None = None, name: str | None = None,
              formats: Sequence[str] | Callable[[ProcedureResult], Sequence[str]] | None = None,
              record: bool = True, db: str | None = None, operator: str = "",
              progress: Callable[[float], None] | None = None, reason: str = "") -> Calibration:
    """Analyse `data` with its procedure, write the output files and record the result.

    Parameters
    ----------
    data : str or Path
        A Recording, or a log that the named `procedure` reads itself (the field calibration's
        CSV, with ``options["import_spec"]``).
    procedure : str, optional
        The procedure's registry name; default: the recording's.
    options : mapping, optional
        The analysis options (keys of the procedure's ``analysis_options``).
    unit : str, optional
        The IMU (its stream); default: the only one (a P2 lot: every unit).
    more : sequence of path
        Further recordings analysed with `data` as one (``analyze_many``: a P2 lot).
    out : str or Path, optional
        The folder of the output files; default: `data`'s.
    name : str, optional
        The files' name stem; default: `data`'s stem.
    formats : sequence of str, or callable, optional
        The output formats, or a function of the result that returns them (a format that only
        some results can give); default: the procedure's ``outputs``.
    record : bool
        Record the result and its run in the records database.
    db : str, optional
        The records database (default: ``$IMUCALIB_DB``, else the user's data directory).
    operator : str
        Who calibrated, for the records.
    progress : callable, optional
        Given the fraction of the analysis done (the procedure's measure).
    reason : str
        Why the data are analysed again, when the records already hold this procedure's result
        of the same recording (the new result is its next version, docs/records.md "One
        calibration, one run"); default: an automatic reason naming the options.

    Raises
    ------
    CalibrationError
        What the procedure or the outputs refuse (one line each; a folder that cannot be
        written is an :class:`~imucalib.errors.InvalidInputError`); the records' refusal is
        returned as :attr:`Calibration.record_error`.
    """
    from imucalib.exports.outputs import write_outputs

    path = Path(data)
    proc = procedure_of(path, procedure)
    if more:
        result = proc.analyze_many([path, *(Path(m) for m in more)],
                                   units=[unit] if unit else None, options=options,
                                   progress=progress)
    else:
        result = proc.analyze(path, unit=unit, options=options, progress=progress)
    folder = Path(out) if out is not None else path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
        chosen = formats(result) if callable(formats) else formats
        provenance = None if result.calibration is not None else provenance_of(path)
        written = write_outputs(result, folder, chosen, name=name or path.stem,
                                provenance=provenance, recording=path)
    except OSError as exc:
        raise InvalidInputError(f"cannot write the outputs into {folder}: "
                                f"{exc.strerror or exc}") from exc
    line, error = None, None
    if record:
        from imucalib.records.calibrations import record_calibration

        try:
            line = record_calibration(
                result, path, db=db, operator=operator, reason=reason, options=options,
                recording_sha256=provenance.recording_sha256 if provenance else "")
        except CalibrationError as exc:
            error = exc
    return Calibration(procedure=proc, result=result, written=tuple(written), record=line,
                       record_error=error)
