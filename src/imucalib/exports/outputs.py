"""Write every output file of a procedure result: :func:`write_outputs`.

A result (:class:`~imucalib.procedures.common.procedure.ProcedureResult`) is written into one
folder as ``<name>.<unit>.<procedure><suffix>``, one file (or folder) per output format, by
default the formats its procedure lists in ``outputs``, in that order. The formats
(:data:`OUTPUT_FORMATS`):

=================  =============================  ================================================
format             file                           content
=================  =============================  ================================================
``result-json``    ``….result.json``              the result document (format version 4,
                                                  :mod:`imucalib.models.result_document`): every
                                                  reported parameter with σ and σ before Birge
                                                  scaling, covariance, fit quality, decision,
                                                  provenance, the triad model where there is one;
                                                  ``apply``, ``export``, ``report``, ``combine``
                                                  and the records read it
``report-json``    ``….report.json``              the whole result, procedure-specific: checks,
                                                  decision, per repetition (``result.to_dict()``)
``parameters-csv`` ``….parameters.csv``           one row per reported parameter: value,
                                                  standard uncertainty (Birge-scaled where a fit
                                                  is a misfit), SI unit, σ before that scaling
``c-runtime``      ``….c/``                       the calibration as C99 for firmware:
                                                  ``imucal_params.h`` and the runtime library
                                                  (:mod:`imucalib.exports.c_runtime`,
                                                  docs/c-runtime.md); in no default list
``mat``            ``….intrinsics.mat``           the calibration as a MATLAB v5 struct ``imucal``
                                                  (:mod:`imucalib.exports.intrinsics`,
                                                  docs/exports.md); in no default list
``mat73``          ``….intrinsics73.mat``         the same as MATLAB v7.3 (HDF5)
``ros-yaml``       ``….ros.yaml``                 a ROS-style parameter YAML, one namespace per
                                                  triad
``kalibr-imu``     ``….kalibr-imu.yaml``          Kalibr ``scale-misalignment`` intrinsics (``M``,
                                                  ``A``, ``C_gyro_i``)
``openvins-imu``   ``….openvins-imu.yaml``        OpenVINS ``kalibr_imu_chain.yaml`` intrinsics
                                                  (``Tw``, ``R_IMUtoGYRO``, ``Ta``,
                                                  ``R_IMUtoACC``, ``Tg``)
``report-pdf``     ``….report.pdf``               the calibration report (certificate):
                                                  docs/reporting.md, "The calibration report"
``report-html``    ``….report.html``              the same report as one self-contained page
=================  =============================  ================================================

A procedure adds formats of its own (``output_writers``: Allan's noise YAML, tables and
figures, P1's residual figure, P2's temperature figure; docs/exports.md lists them all).

A batch (a result with ``members``, one per unit: P2's array or lot) is written unit by unit,
each unit's files named after it (a unit that could not be calibrated gets its
``report.json`` only, which holds the error), then the batch's own files (its procedure's
``batch_outputs``: P2's summary JSON, CSV and lot figure) and, with
``report-pdf``/``report-html``, the summary report ``.summary.report.pdf``/``.html``
(:func:`~imucalib.exports.report.build_summary_report`: its procedure's ``summary_report``)
beside each unit's own report (:func:`~imucalib.exports.report.build_report`).

Contents
--------
:func:`write_outputs`, :func:`file_stem`, :data:`OUTPUT_FORMATS`, :data:`TEMPERATURE_FORMATS`
"""

from __future__ import annotations

import csv
import json
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol

from imucalib.errors import InvalidInputError
from imucalib.models.procedure_result import ProcedureResult
from imucalib.models.result import CalibrationResult, Provenance

__all__ = ["OUTPUT_FORMATS", "TEMPERATURE_FORMATS", "file_stem", "formats_of", "write_outputs"]

_Writer = Callable[[Any, Path, str], list[Path]]


def _calibration(result: ProcedureResult, fmt: str) -> CalibrationResult:
    cal = result.calibration
    if cal is None:
        raise InvalidInputError(f"output {fmt!r} needs a whole triad model; this "
                                f"{result.procedure} result holds none")
    return cal


def _result_json(result: ProcedureResult, folder: Path, stem: str, *,
                 provenance: Provenance | None = None) -> list[Path]:
    from imucalib.models.result_document import result_document

    path = folder / f"{stem}.result.json"
    text = json.dumps(result_document(result, provenance=provenance), indent=1,
                      allow_nan=False)
    path.write_text(text + "\n", encoding="utf-8")
    return [path]


def _report_json(result: ProcedureResult, folder: Path, stem: str) -> list[Path]:
    path = folder / f"{stem}.report.json"
    path.write_text(json.dumps(result.to_dict(), indent=1, allow_nan=True) + "\n",
                    encoding="utf-8")
    return [path]


def _parameters_csv(result: ProcedureResult, folder: Path, stem: str) -> list[Path]:
    rows = result.parameter_rows()
    if not rows:
        raise InvalidInputError(f"output 'parameters-csv' needs reported parameters; a "
                                f"{result.procedure} result has none")
    path = folder / f"{stem}.parameters.csv"
    with open(path, "w", encoding="utf-8", newline="") as fh:
        out = csv.writer(fh, lineterminator="\n")
        out.writerow(["parameter", "value", "std_uncertainty", "unit", "std_noise"])
        # repr of a Python float: the shortest text that reads back to the same bits (a numpy
        # scalar's repr would write "np.float64(…)")
        out.writerows((r.name, repr(float(r.value)), repr(float(r.std)), r.unit,
                       repr(float(r.std_noise))) for r in rows)
    return [path]


def _c_runtime(result: Any, folder: Path, stem: str) -> list[Path]:
    from imucalib.exports.c_runtime import write_c_runtime

    return write_c_runtime(_calibration(result, "c-runtime"), folder / f"{stem}.c")


#: The formats that take a temperature (their tools hold constant intrinsics; docs/exports.md).
TEMPERATURE_FORMATS = ("kalibr-imu", "openvins-imu")


class _IntrinsicsWriter(Protocol):
    def __call__(self, result: Any, folder: Path, stem: str, *,
                 temperature_degc: float | None = None,
                 drop_terms: bool = False) -> list[Path]: ...


def _intrinsics(fmt: str, suffix: str) -> _IntrinsicsWriter:
    def writer(result: Any, folder: Path, stem: str, *,
               temperature_degc: float | None = None, drop_terms: bool = False) -> list[Path]:
        from imucalib.exports import intrinsics

        cal, path = _calibration(result, fmt), folder / f"{stem}{suffix}"
        if fmt == "kalibr-imu":
            return [intrinsics.write_kalibr_intrinsics(
                cal, path, temperature_degc=temperature_degc, drop_terms=drop_terms)]
        if fmt == "openvins-imu":
            return [intrinsics.write_openvins_intrinsics(
                cal, path, temperature_degc=temperature_degc, drop_terms=drop_terms)]
        write = {"mat": intrinsics.write_mat, "mat73": intrinsics.write_mat73,
                 "ros-yaml": intrinsics.write_ros_yaml}[fmt]
        return [write(cal, path)]

    return writer


def _write_document(document: Any, fmt: str, path_stem: Path) -> Path:
    """Write a report as ``<path_stem>.pdf`` or ``.html`` (`fmt` "report-pdf"/"report-html")."""
    from imucalib.report.document import write_report

    ext = fmt.removeprefix("report-")
    return write_report(document, path_stem.with_name(f"{path_stem.name}.{ext}"), ext)


#: The result exports of :mod:`imucalib.exports.intrinsics`, by format.
_INTRINSICS: dict[str, _IntrinsicsWriter] = {
    fmt: _intrinsics(fmt, suffix) for fmt, suffix in (
        ("mat", ".intrinsics.mat"), ("mat73", ".intrinsics73.mat"), ("ros-yaml", ".ros.yaml"),
        ("kalibr-imu", ".kalibr-imu.yaml"), ("openvins-imu", ".openvins-imu.yaml"))}


def _report(fmt: str) -> _Writer:
    def writer(result: Any, folder: Path, stem: str, *,
               provenance: Provenance | None = None,
               recording: Path | None = None) -> list[Path]:
        from imucalib.exports.report import build_report

        prov = provenance or (result.calibration.provenance
                              if result.calibration is not None else None)
        name = Path(prov.recording).name if prov is not None and prov.recording else ""
        if recording is not None and recording.suffix.lower() not in (".h5", ".hdf5"):
            recording = None  # a user's CSV log is no Recording: not read again
        if (recording is None and name and Path(name).suffix.lower() in (".h5", ".hdf5")
                and (folder / name).is_file()):  # written beside the recording (the demo)
            recording = folder / name
        document = build_report(result, recording=recording)
        return [_write_document(document, fmt, folder / f"{stem}.report")]

    return writer


def file_stem(name: str, unit: Any, procedure: str) -> str:
    """Return ``<name>.<unit>.<procedure>``: the unit as a file-name part ("SN/42" → "SN_42")."""
    return f"{name}.{_safe(unit)}.{procedure}"


def _safe(unit: Any) -> str:
    """Return a unit's name as a file-name part ('SN/42' → 'SN_42': not a folder)."""
    return "".join("_" if c in "/\\\0" else c for c in str(unit))


def _write_batch(batch: ProcedureResult, writers: Mapping[str, _Writer], out: Path,
                 chosen: Sequence[str], name: str) -> list[Path]:
    """Write every member's files, then the batch's own and its summary report."""
    from imucalib.procedures import registry

    written: list[Path] = []
    for unit_result in batch.members:
        stem = file_stem(name, unit_result.unit, batch.procedure)
        formats = chosen if unit_result.error == "" else ("report-json",)
        for fmt in formats:
            written += writers[fmt](unit_result, out, stem)
    stem = file_stem(name, batch.unit, batch.procedure)
    written += registry.get(batch.procedure).batch_outputs(batch, out, stem)
    reports = [f for f in chosen if f in ("report-pdf", "report-html")]
    if reports:
        from imucalib.exports.report import build_summary_report

        document = build_summary_report(batch)
        written += [_write_document(document, f, out / f"{stem}.summary.report")
                    for f in reports]
    return written


#: The formats every result has: format → writer(result, folder, stem) returning the paths
#: written; a procedure adds its own (``output_writers``).
OUTPUT_FORMATS: dict[str, _Writer] = {
    "result-json": _result_json,
    "report-json": _report_json,
    "parameters-csv": _parameters_csv,
    "c-runtime": _c_runtime,
    "mat": _INTRINSICS["mat"],
    "mat73": _INTRINSICS["mat73"],
    "ros-yaml": _INTRINSICS["ros-yaml"],
    "kalibr-imu": _INTRINSICS["kalibr-imu"],
    "openvins-imu": _INTRINSICS["openvins-imu"],
    "report-pdf": _report("report-pdf"),
    "report-html": _report("report-html"),
}

#: The writers that take the result's provenance.
_PROVENANCED: dict[str, Callable[..., list[Path]]] = {
    "result-json": _result_json, "report-pdf": OUTPUT_FORMATS["report-pdf"],
    "report-html": OUTPUT_FORMATS["report-html"]}


def formats_of(procedure: str) -> dict[str, _Writer]:
    """Return every output format a result of `procedure` can be written in.

    The shared :data:`OUTPUT_FORMATS` and the procedure's own (``output_writers``; none for a
    procedure not installed here).
    """
    from imucalib.errors import ConfigurationError
    from imucalib.procedures import registry

    try:
        own = registry.get(procedure).output_writers()
    except ConfigurationError:  # a result file of a procedure not installed here
        own = {}
    return {**OUTPUT_FORMATS, **own}


def write_outputs(result: ProcedureResult, folder: str | os.PathLike[str],
                  formats: Sequence[str] | None = None, *, name: str,
                  temperature_degc: float | None = None,
                  drop_terms: bool = False,
                  provenance: Provenance | None = None,
                  recording: str | os.PathLike[str] | None = None) -> list[Path]:
    """Name and write the output files of a procedure result (module docstring).

    Parameters
    ----------
    result : ProcedureResult
        What a procedure's ``analyze`` returned, or a result read back from its file
        (:func:`~imucalib.models.result_document.load_result`).
    folder : path
        Where to write (created when missing).
    formats : sequence of str, optional
        Formats of :func:`formats_of` the result's procedure; default: the procedure's
        ``outputs``.
    name : str
        First part of every file name, usually the recording's stem.
    temperature_degc : float, optional
        For :data:`TEMPERATURE_FORMATS` only (``kalibr-imu``, ``openvins-imu``): the temperature
        at which a result's temperature models (Eq. (T1)) are evaluated; such a result is
        refused without it (:func:`imucalib.exports.intrinsics.at_temperature`). [°C]
    drop_terms : bool
        For :data:`TEMPERATURE_FORMATS` only: write a result whose K2 or K3 their tools' models
        lack without them, the file stating the error left (Eq. (X6) of
        :mod:`imucalib.exports.intrinsics`); refused otherwise.
    provenance : Provenance, optional
        Where the result came from (the recording, its SHA-256, the plan hash), for the result
        document and the report; default: its calibration's.
    recording : path, optional
        The Recording analysed, for the report (its environment, the run's facts, the station:
        a twin's result is not traceable); default: the one of the provenance's name in
        `folder`, if it is there.

    Returns
    -------
    list of Path
        The files (and figure files) written, in the order of `formats`.

    Raises
    ------
    InvalidInputError
        An unknown format, or one the result cannot give (a noise table of a calibration), or
        a temperature with a format outside :data:`TEMPERATURE_FORMATS`.
    ConfigurationError
        Default formats for a result whose procedure is not installed here.
    """
    from imucalib.procedures import registry

    writers = formats_of(result.procedure)
    chosen = tuple(registry.get(result.procedure).outputs if formats is None else formats)
    unknown = [f for f in chosen if f not in writers]
    if unknown:
        raise InvalidInputError(f"unknown output format(s) {unknown} for a {result.procedure} "
                                f"result; known: {', '.join(writers)}")
    if temperature_degc is not None:
        other = [f for f in chosen if f not in TEMPERATURE_FORMATS]
        if other:
            raise InvalidInputError(
                f"a temperature applies to the formats {', '.join(TEMPERATURE_FORMATS)} only "
                f"(their tools hold constant intrinsics); not to {', '.join(other)}, which "
                "carry the temperature models themselves or none")
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    if result.members:
        if temperature_degc is not None:
            raise InvalidInputError("a temperature is for one result, not a batch")
        return _write_batch(result, writers, out, chosen, name)
    stem = file_stem(name, result.unit, result.procedure)
    written: list[Path] = []
    for fmt in chosen:
        if fmt in TEMPERATURE_FORMATS:
            written += _INTRINSICS[fmt](result, out, stem, temperature_degc=temperature_degc,
                                        drop_terms=drop_terms)
        elif fmt in ("report-pdf", "report-html"):
            written += _PROVENANCED[fmt](result, out, stem, provenance=provenance,
                                         recording=None if recording is None else Path(recording))
        elif fmt == "result-json":
            written += _PROVENANCED[fmt](result, out, stem, provenance=provenance)
        else:
            written += writers[fmt](result, out, stem)
    return written
