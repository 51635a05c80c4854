"""``imucalib report RESULT|RECORDING`` or ``--run N``: the calibration report as PDF or HTML.

A recording of an array (P2) gives one report per unit and the array's summary report; a run
of the records database (``--run N``) is reported from its recording (its SHA-256 checked
against the records), each unit's report with that unit's reviews and records id
(docs/reporting.md, "The calibration report").
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from imucalib.cli._app import app, console, fail
from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["report"]


def _analyse(path: Path, imu: str | None) -> Any:
    from imucalib.io.opening import open_recording
    from imucalib.procedures import registry

    with open_recording(path) as rec:
        name = registry.identify(rec)
    return registry.get(name).analyze(path, unit=imu)


def _from_result_file(path: Path) -> Any:
    from imucalib.models.result_document import load_result

    return load_result(path)


def _run_recording(run_id: int, db: str | None) -> tuple[Path, dict[str, Any]]:
    """Return the run's recording (its hash checked) and its current results by unit."""
    from imucalib.io.hashing import file_sha256
    from imucalib.records import open_records

    with open_records(db) as records:
        view = records.run(run_id)
        entries = [records.result(i) for i in view.result_ids]
    path = Path(view.recording_path)
    if not view.recording_path or not path.is_file():
        raise InvalidInputError(f"run {run_id}'s recording {view.recording_path!r} is not there: "
                                "the report is made from the recording")
    if view.recording_sha256 and file_sha256(path) != view.recording_sha256:
        raise InvalidInputError(f"run {run_id}'s recording {path} has changed since it was "
                                f"recorded: SHA-256 expected {view.recording_sha256}, found "
                                f"{file_sha256(path)}")
    by_unit = {e.serial: e for e in entries if e.current}
    return path, by_unit


@app.command()
def report(
    path: Annotated[Path | None, typer.Argument(
        metavar="RESULT|RECORDING",
        help="A result (.result.json), or a recording (.h5) whose procedure is run again "
             "(the full report: checks, decision, figures; an array: one report per unit and "
             "a summary).")] = None,
    run: Annotated[int | None, typer.Option(
        "--run", help="A run of the records database: its recording is analysed again (its "
                      "SHA-256 checked) and each unit's report carries its records id and "
                      "reviews.")] = None,
    fmt: Annotated[str, typer.Option("--format", help="pdf or html.")] = "pdf",
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="The file to write (default: beside the input); for an array or "
                            "a run, the folder.")] = None,
    result_id: Annotated[int | None, typer.Option(
        help="The result's id in the records database: its reviews and authorisation go "
             "into the report (docs/records.md).")] = None,
    db: Annotated[str | None, typer.Option(
        "--db", help="Records database (with --result-id or --run).")] = None,
    imu: Annotated[str | None, typer.Option(help="IMU stream of a recording.")] = None,
) -> None:
    """Write the calibration report: six sections, U = 2u, decision rule, review status."""
    from imucalib.exports.report import build_report, build_summary_report
    from imucalib.report.document import write_report

    try:
        if fmt not in ("pdf", "html"):
            raise InvalidInputError(f"--format must be pdf or html; got {fmt!r}")
        if (path is None) == (run is None):
            raise InvalidInputError("give a RESULT or RECORDING, or --run N (one of them); got "
                                    + ("both" if path is not None else "neither"))
        entries: dict[str, Any] = {}
        if run is not None:
            path, entries = _run_recording(run, db)
        assert path is not None
        recording = None
        result: Any
        if path.suffix.lower() in (".h5", ".hdf5"):
            result = _analyse(path, imu)
            recording = path
        else:
            result = _from_result_file(path)
        from imucalib.exports.outputs import file_stem

        units = list(result.members) or [result]
        folder = out if out is not None and (len(units) > 1 or run is not None) else None
        stem = path.name.split(".")[0]
        written = []
        ids: dict[str, str] = {}
        for unit_result in units:
            if unit_result.error:
                console.print(f"unit {unit_result.unit}: not calibrated, no report "
                              f"({unit_result.error})", highlight=False, soft_wrap=True)
                continue
            entry = entries.get(str(unit_result.unit))
            rid = result_id if entry is None else entry.result_id
            reviews: Any = None if entry is None else entry.reviews
            if reviews is None and rid is not None:
                from imucalib.records import open_records

                with open_records(db) as records:
                    reviews = records.result(rid).reviews
            document = build_report(unit_result, recording=recording, review=reviews,
                                    result_id=rid)
            name = (f"{file_stem(stem, unit_result.unit, unit_result.procedure)}.report.{fmt}"
                    if len(units) > 1 or run is not None else f"{stem}.report.{fmt}")
            target = (folder / name if folder is not None else
                      out if out is not None else path.with_name(name))
            target.parent.mkdir(parents=True, exist_ok=True)
            written.append((write_report(document, target, fmt), document.report_id))
            ids[str(unit_result.unit)] = document.report_id
        if len(units) > 1:
            document = build_summary_report(result, recordings=[path], report_ids=ids)
            target = ((folder or path.parent)
                      / f"{file_stem(stem, result.unit, result.procedure)}.summary.report.{fmt}")
            written.append((write_report(document, target, fmt), document.report_id))
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(InvalidInputError(f"cannot write {out}: {exc.strerror or exc}")) from exc
    if not written:
        raise fail(InvalidInputError("no unit could be reported (none was calibrated)"))
    for file, rid in written:
        console.print(f"wrote {file} (report {rid})", highlight=False, soft_wrap=True)
