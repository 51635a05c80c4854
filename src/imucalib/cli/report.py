"""``imucalib report RESULT|RECORDING``: the calibration report (certificate) as PDF or HTML."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from imucalib.cli._app import app, console, fail
from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["report"]


@app.command()
def report(
    path: Annotated[Path, typer.Argument(
        metavar="RESULT|RECORDING",
        help="A result (.result.json), or a recording (.h5) whose procedure is run again "
             "(the full report: checks, decision, figures).")],
    fmt: Annotated[str, typer.Option("--format", help="pdf or html.")] = "pdf",
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="The file to write (default: beside the input).")] = None,
    result_id: Annotated[int | None, typer.Option(
        help="The result's id in the records database: its reviews and authorisation go "
             "into the report (docs/records.md).")] = None,
    db: Annotated[str | None, typer.Option(
        "--db", help="Records database (with --result-id).")] = None,
    imu: Annotated[str | None, typer.Option(help="IMU stream of a recording.")] = None,
) -> None:
    """Write the calibration report: six sections, U = 2u, decision rule, review status."""
    from imucalib.report.document import build_report

    try:
        if fmt not in ("pdf", "html"):
            raise InvalidInputError(f"--format must be pdf or html; got {fmt!r}")
        recording = None
        result: Any
        if path.suffix.lower() in (".h5", ".hdf5"):
            from imucalib.io.reader import open_recording
            from imucalib.procedures import registry

            with open_recording(path) as rec:
                name = registry.identify(rec)
            result = registry.get(name).analyze(path, unit=imu)
            recording = path
        else:
            from types import SimpleNamespace

            from imucalib.models.result import CalibrationResult

            cal = CalibrationResult.load(path)
            result = SimpleNamespace(result=cal, procedure=cal.procedure, unit=cal.sensor_id,
                                     passed=None)
        reviews: Any = None
        if result_id is not None:
            from imucalib.records import open_records

            with open_records(db) as records:
                reviews = records.result(result_id).reviews
        document = build_report(result, recording=recording, review=reviews,
                                result_id=result_id)
        target = out or path.with_name(path.name.split(".")[0] + f".report.{fmt}")
        if fmt == "pdf":
            from imucalib.report.pdf import write_report_pdf

            written = write_report_pdf(document, target)
        else:
            from imucalib.report.html import write_report_html

            written = write_report_html(document, target)
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(InvalidInputError(f"cannot write {out}: {exc.strerror or exc}")) from exc
    console.print(f"wrote {written} (report {document.report_id})", highlight=False,
                  soft_wrap=True)
