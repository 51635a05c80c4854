"""Write every output file of a procedure result: :func:`write_outputs`.

A result (:class:`~imucalib.procedures.common.procedure.ProcedureResult`) is written into one
folder as ``<name>.<unit>.<procedure><suffix>``, one file (or folder) per output format, by
default the formats its procedure lists in ``outputs``, in that order. The formats
(:data:`OUTPUT_FORMATS`):

=================  =============================  ================================================
format             file                           content
=================  =============================  ================================================
``result-json``    ``….result.json``              the calibration result
                                                  (:class:`~imucalib.models.result.CalibrationResult`),
                                                  which ``imucalib apply`` reads
``report-json``    ``….report.json``              the whole result: checks, decision, per
                                                  repetition (``result.to_dict()``)
``parameters-csv`` ``….parameters.csv``           one row per parameter: value, standard
                                                  uncertainty (Birge-scaled where a fit is a
                                                  misfit), SI unit (a result with
                                                  ``parameter_rows()``, P3, gives its own)
``noise-json``     ``….json``                     the versioned noise characterisation
``kalibr-yaml``    ``…[.k].kalibr.yaml``          Kalibr ``imu.yaml``, per static record k
``openvins-yaml``  ``…[.k].openvins.yaml``        OpenVINS ``kalibr_imu_chain.yaml``, per record
``noise-table``    ``…[.k].table.md``             the datasheet-style noise table, per record
``figures``        ``….figures/``                 Allan deviation figures (PNG)
``residuals-png``  ``….residuals.png``            residual mean per window and axis with ±2σ
                                                  bars, χ²/ν (a calibration)
``temperature-png`` ``….temperature.png``         P2: every parameter against temperature with
                                                  its model and 2σ band
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

A batch (a result with ``results``, one per unit: P2's array or lot) is
written unit by unit, each unit's files named after it (a unit that could not be calibrated
gets its ``report.json`` only, which holds the error), then the batch's own files:
``<name>.<array|lot>.p2.summary.json`` and ``.summary.csv`` (one row per unit: pass/fail, the
compensated errors, the parameters furthest from the lot, the error), for two or more
calibrated units ``.lot.png`` (every parameter's spread across the units), and with
``report-pdf``/``report-html`` the summary report ``.summary.report.pdf``/``.html``
(:func:`~imucalib.exports.report.build_summary_report`: its procedure's ``summary_report``)
beside each unit's own report (:func:`~imucalib.exports.report.build_report`).

The record index ``.k`` appears only when the characterisation holds more than one record.

Contents
--------
:func:`write_outputs`, :func:`file_stem`, :data:`OUTPUT_FORMATS`, :data:`TEMPERATURE_FORMATS`
"""

from __future__ import annotations

import csv
import json
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol

from imucalib.errors import InvalidInputError
from imucalib.procedures.common.procedure import ProcedureResult

__all__ = ["OUTPUT_FORMATS", "TEMPERATURE_FORMATS", "file_stem", "write_outputs"]

_Writer = Callable[[Any, Path, str], list[Path]]


def _calibration(result: Any, fmt: str) -> Any:
    from imucalib.models.result import CalibrationResult

    cal = getattr(result, "result", None)
    if not isinstance(cal, CalibrationResult):
        raise InvalidInputError(f"output {fmt!r} needs a calibration result; a "
                                f"{result.procedure} result holds none")
    return cal


def _noise(result: Any, fmt: str) -> Any:
    from imucalib.procedures.allan.analysis import NoiseCharacterization

    if not isinstance(result, NoiseCharacterization):
        raise InvalidInputError(f"output {fmt!r} needs a noise characterisation; got a "
                                f"{result.procedure} result")
    return result


def _result_json(result: Any, folder: Path, stem: str) -> list[Path]:
    path = folder / f"{stem}.result.json"
    path.write_text(_calibration(result, "result-json").to_json() + "\n", encoding="utf-8")
    return [path]


def _report_json(result: Any, folder: Path, stem: str) -> list[Path]:
    path = folder / f"{stem}.report.json"
    path.write_text(json.dumps(result.to_dict(), indent=1, allow_nan=True) + "\n",
                    encoding="utf-8")
    return [path]


def _parameters_csv(result: Any, folder: Path, stem: str) -> list[Path]:
    rows_of = getattr(result, "parameter_rows", None)
    if callable(rows_of):  # a result that is not a triad calibration (P3)
        rows = [(n, repr(v), repr(s), u) for n, v, s, u in rows_of()]
    else:
        cal = _calibration(result, "parameters-csv")
        std = cal.std(scaled=True)  # as reported: Birge-scaled where a fit is a misfit
        rows = [(n, repr(cal.value(n)), repr(std[n]), cal.units.get(n, ""))
                for n in cal.param_names]
    path = folder / f"{stem}.parameters.csv"
    with open(path, "w", encoding="utf-8", newline="") as fh:
        out = csv.writer(fh, lineterminator="\n")
        out.writerow(["parameter", "value", "std_uncertainty", "unit"])
        out.writerows(rows)
    return [path]


def _noise_json(result: Any, folder: Path, stem: str) -> list[Path]:
    return [_noise(result, "noise-json").save(folder / f"{stem}.json")]


def _per_record(fmt: str, write: Callable[[Path, Any], Path], suffix: str) -> _Writer:
    def writer(result: Any, folder: Path, stem: str) -> list[Path]:
        segments = _noise(result, fmt).segments
        written = []
        for i, seg in enumerate(segments):
            index = "" if len(segments) == 1 else f".{i}"
            written.append(write(folder / f"{stem}{index}{suffix}", seg))
        return written

    return writer


def _kalibr(path: Path, seg: Any) -> Path:
    from imucalib.exports.noise import write_kalibr_yaml

    return write_kalibr_yaml(path, seg.noise_parameters())


def _openvins(path: Path, seg: Any) -> Path:
    from imucalib.exports.noise import write_openvins_yaml

    return write_openvins_yaml(path, seg.noise_parameters())


def _table(path: Path, seg: Any) -> Path:
    from imucalib.exports.noise import format_noise_table

    path.write_text(format_noise_table(seg.fits(), fmt="markdown") + "\n", encoding="utf-8")
    return path


def _figures(result: Any, folder: Path, stem: str) -> list[Path]:
    from imucalib.procedures.allan.figures import save_allan_figures

    return list(save_allan_figures(_noise(result, "figures"), folder / f"{stem}.figures"))


def _residuals_png(result: Any, folder: Path, stem: str) -> list[Path]:
    from imucalib.report.residual_figure import save_residual_figure

    _calibration(result, "residuals-png")
    return [save_residual_figure(result, folder / f"{stem}.residuals.png")]


def _temperature_png(result: Any, folder: Path, stem: str) -> list[Path]:
    from imucalib.procedures.p2.figures import save_temperature_figure

    if not getattr(result, "models", None):
        raise InvalidInputError(f"output 'temperature-png' needs temperature models; a "
                                f"{result.procedure} result holds none")
    return [save_temperature_figure(result, folder / f"{stem}.temperature.png")]


def _c_runtime(result: Any, folder: Path, stem: str) -> list[Path]:
    from imucalib.exports.c_runtime import write_c_runtime

    return write_c_runtime(_calibration(result, "c-runtime"), folder / f"{stem}.c")


#: The formats that take a temperature (their tools hold constant intrinsics; docs/exports.md).
TEMPERATURE_FORMATS = ("kalibr-imu", "openvins-imu")


class _IntrinsicsWriter(Protocol):
    def __call__(self, result: Any, folder: Path, stem: str, *,
                 temperature_degc: float | None = None) -> list[Path]: ...


def _intrinsics(fmt: str, suffix: str) -> _IntrinsicsWriter:
    def writer(result: Any, folder: Path, stem: str, *,
               temperature_degc: float | None = None) -> list[Path]:
        from imucalib.exports import intrinsics

        cal, path = _calibration(result, fmt), folder / f"{stem}{suffix}"
        if fmt == "kalibr-imu":
            return [intrinsics.write_kalibr_intrinsics(cal, path,
                                                       temperature_degc=temperature_degc)]
        if fmt == "openvins-imu":
            return [intrinsics.write_openvins_intrinsics(cal, path,
                                                         temperature_degc=temperature_degc)]
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
    def writer(result: Any, folder: Path, stem: str) -> list[Path]:
        from imucalib.exports.report import build_report

        recording = None
        name = _recording_name(result)
        if (name and Path(name).suffix.lower() in (".h5", ".hdf5")
                and (folder / name).is_file()):  # written beside the recording (the demo)
            recording = folder / name  # (a user's CSV log is no Recording: not read again)
        document = build_report(result, recording=recording)
        return [_write_document(document, fmt, folder / f"{stem}.report")]

    return writer


def _recording_name(result: Any) -> str:
    cal = getattr(result, "result", None)
    prov = getattr(cal, "provenance", None) or getattr(result, "provenance", None)
    name = getattr(prov, "recording", "") or ""
    return Path(str(name)).name if name else ""


def file_stem(name: str, unit: Any, procedure: str) -> str:
    """Return ``<name>.<unit>.<procedure>``: the unit as a file-name part ("SN/42" → "SN_42")."""
    return f"{name}.{_safe(unit)}.{procedure}"


def _safe(unit: Any) -> str:
    """Return a unit's name as a file-name part ('SN/42' → 'SN_42': not a folder)."""
    return "".join("_" if c in "/\\\0" else c for c in str(unit))


def _write_batch(batch: Any, out: Path, chosen: Sequence[str], name: str) -> list[Path]:
    """Write every unit's files, then the batch's summary (module docstring)."""
    from imucalib.procedures.p2.batch import summary_rows

    written: list[Path] = []
    for unit_result in batch.results:
        stem = file_stem(name, unit_result.unit, batch.procedure)
        formats = chosen if unit_result.error == "" else ("report-json",)
        for fmt in formats:
            written += OUTPUT_FORMATS[fmt](unit_result, out, stem)
    stem = file_stem(name, batch.unit, batch.procedure)
    rows = summary_rows(batch)
    summary = out / f"{stem}.summary.json"
    summary.write_text(json.dumps({"procedure": batch.procedure, "passed": batch.passed,
                                   "recordings": list(batch.recordings), "units": rows},
                                  indent=1, allow_nan=True) + "\n", encoding="utf-8")
    table = out / f"{stem}.summary.csv"
    with open(table, "w", encoding="utf-8", newline="") as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(["unit", "passed", "accel_error_mps2", "gyro_error_rps",
                         "worst_parameters", "error"])
        for row in rows:
            writer.writerow([row["unit"], row["passed"], row["accel_error_mps2"],
                             row["gyro_error_rps"], "; ".join(row["worst_parameters"]),
                             row["error"]])
    written += [summary, table]
    if sum(r.result is not None for r in batch.results) >= 2:
        from imucalib.procedures.p2.figures import save_lot_figure

        written.append(save_lot_figure(batch, out / f"{stem}.lot.png"))
    reports = [f for f in chosen if f in ("report-pdf", "report-html")]
    if reports:
        from imucalib.exports.report import build_summary_report

        document = build_summary_report(batch)
        written += [_write_document(document, f, out / f"{stem}.summary.report")
                    for f in reports]
    return written


#: Output format → writer(result, folder, stem) returning the paths written.
OUTPUT_FORMATS: dict[str, _Writer] = {
    "result-json": _result_json,
    "report-json": _report_json,
    "parameters-csv": _parameters_csv,
    "noise-json": _noise_json,
    "kalibr-yaml": _per_record("kalibr-yaml", _kalibr, ".kalibr.yaml"),
    "openvins-yaml": _per_record("openvins-yaml", _openvins, ".openvins.yaml"),
    "noise-table": _per_record("noise-table", _table, ".table.md"),
    "figures": _figures,
    "residuals-png": _residuals_png,
    "temperature-png": _temperature_png,
    "c-runtime": _c_runtime,
    "mat": _INTRINSICS["mat"],
    "mat73": _INTRINSICS["mat73"],
    "ros-yaml": _INTRINSICS["ros-yaml"],
    "kalibr-imu": _INTRINSICS["kalibr-imu"],
    "openvins-imu": _INTRINSICS["openvins-imu"],
    "report-pdf": _report("report-pdf"),
    "report-html": _report("report-html"),
}


def write_outputs(result: ProcedureResult, folder: str | os.PathLike[str],
                  formats: Sequence[str] | None = None, *, name: str,
                  temperature_degc: float | None = None) -> list[Path]:
    """Name and write the output files of a procedure result (module docstring).

    Parameters
    ----------
    result : ProcedureResult
        What a procedure's ``analyze`` returned.
    folder : path
        Where to write (created when missing).
    formats : sequence of str, optional
        Formats of :data:`OUTPUT_FORMATS`; default: the procedure's ``outputs``.
    name : str
        First part of every file name, usually the recording's stem.
    temperature_degc : float, optional
        For :data:`TEMPERATURE_FORMATS` only (``kalibr-imu``, ``openvins-imu``): the temperature
        at which a result's temperature models (Eq. (T1)) are evaluated; such a result is
        refused without it (:func:`imucalib.exports.intrinsics.at_temperature`). [°C]

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
        The result names an unregistered procedure.
    """
    from imucalib.procedures import registry

    procedure = registry.get(result.procedure)
    chosen = tuple(procedure.outputs if formats is None else formats)
    unknown = [f for f in chosen if f not in OUTPUT_FORMATS]
    if unknown:
        raise InvalidInputError(f"unknown output format(s) {unknown}; known: "
                                f"{', '.join(OUTPUT_FORMATS)}")
    if temperature_degc is not None:
        other = [f for f in chosen if f not in TEMPERATURE_FORMATS]
        if other:
            raise InvalidInputError(
                f"a temperature applies to the formats {', '.join(TEMPERATURE_FORMATS)} only "
                f"(their tools hold constant intrinsics); not to {', '.join(other)}, which "
                "carry the temperature models themselves or none")
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    if hasattr(result, "results"):
        if temperature_degc is not None:
            raise InvalidInputError("a temperature is for one result, not a batch")
        return _write_batch(result, out, chosen, name)
    stem = file_stem(name, result.unit, result.procedure)
    written: list[Path] = []
    for fmt in chosen:
        if temperature_degc is not None:  # only TEMPERATURE_FORMATS here (checked above)
            written += _INTRINSICS[fmt](result, out, stem, temperature_degc=temperature_degc)
        else:
            written += OUTPUT_FORMATS[fmt](result, out, stem)
    return written
