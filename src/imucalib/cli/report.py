"""``imucalib report RESULT|RECORDING`` or ``--run N``: the calibration report as PDF or HTML.

A recording of an array (P2) gives one report per unit and the array's summary report; a run
of the records database (``--run N``) is reported from its recording (its SHA-256 checked
against the records), each unit's report with that unit's reviews and records id
(docs/reporting.md, "The calibration report").

Every report is a certificate of one template (:mod:`imucalib.report.certificate`): the
laboratory from the laboratory configuration (``--config``, docs/configuration.md), the customer
(``--customer``), and, for a result of the records (``--result-id N`` or ``--run N``), the run's
operator, calibration date and equipment with its certificates and the result's release
(``Records.release_status``): a DRAFT until a reviewer has released it. A result file is
reported with the recording beside it when that is the one it was made from (its SHA-256), else
the run's recording from the records, so that its station (the twin: not traceable) is known.
The report id is the same in every path.
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


def _when(value: Any) -> str:
    from imucalib.report.certificate import when_text

    return when_text(value)


#: The keys of a run's environment (records) that are no condition of the run.
_RUN_KEYS = frozenset({"opened_by", "status", "override_due", "overdue_equipment", "unplanned",
                       "customer"})


def _records_facts(db: str | None, result_id: int, customer: str | None
                   ) -> tuple[dict[str, Any], Any, Any]:
    """Return what the records hold of result `result_id` for its certificate.

    (the :class:`~imucalib.report.certificate.CertificateFacts` fields: operator, calibration
    date, equipment with certificates and due dates, overrides, customer, release; the
    result's reviews; its run's view).
    """
    from imucalib.records import open_records
    from imucalib.report.certificate import EquipmentItem, Release

    with open_records(db) as records:
        entry = records.result(result_id)
        run = records.run(entry.run_id)
        kit = {e.equipment_id: e for e in records.equipment(current_only=False)}
        status = records.release_status(result_id)
        unverified = records.reviews_unverified()   # a review is shown once verified
    started = entry.calibrated_utc or run.started_utc
    items = []
    for eid in run.equipment_ids:
        e = kit.get(eid)
        if e is None:
            items.append(EquipmentItem(f"equipment {eid}", note="not in the records"))
            continue
        overdue = (e.due_on is not None and started is not None
                   and e.due_on < started.date())
        items.append(EquipmentItem(e.kind, e.model, e.serial, e.certificate,
                                   _when(e.due_on), "overdue at the run" if overdue else ""))
    env = run.environment or {}
    override = str(env.get("override_due") or "").strip()
    conditions = tuple((str(k).replace("_", " "), str(v)) for k, v in env.items()
                       if k not in _RUN_KEYS and isinstance(v, str | int | float) and v != "")
    facts = {
        "operator": run.operator, "calibration_date": _when(started),
        "equipment": tuple(items), "run_id": run.run_id, "records_result_id": result_id,
        "overrides": (f"equipment overdue for calibration used: {override}",) if override
        else (),
        "customer": customer or str(env.get("customer") or ""), "environment": conditions,
        "release": Release(released=status.released, reviewer=status.reviewer,
                           decision=status.decision or "",
                           reviewed_utc=_when(status.reviewed_utc), comment=status.comment,
                           reason=status.reason)}
    if unverified:
        facts["release"] = Release(released=False, reason=unverified)
        return facts, (), run
    return facts, entry.reviews, run


def _recording_of(result: Any, path: Path, run: Any) -> Path | None:
    """Return the recording `result` was made from: beside its file, else the run's (by hash)."""
    from imucalib.io.hashing import file_sha256

    prov = result.provenance
    candidates = []
    if prov is not None and prov.recording:
        candidates.append((path.parent / Path(prov.recording).name, prov.recording_sha256))
    if run is not None and run.recording_path:
        candidates.append((Path(run.recording_path), run.recording_sha256))
    for file, sha in candidates:
        if file.suffix.lower() in (".h5", ".hdf5") and file.is_file() and sha \
                and file_sha256(file) == sha:
            return file
    return None


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
    fmt: Annotated[str, typer.Option(
        "--format", help="pdf or html, or both (pdf,html: the same report in each, analysed "
                         "once).")] = "pdf",
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="The file to write (default: beside the input); for an array or "
                            "a run, the folder.")] = None,
    result_id: Annotated[int | None, typer.Option(
        help="The result's id in the records database: its reviews and authorisation go "
             "into the report (docs/records.md).")] = None,
    db: Annotated[str | None, typer.Option(
        "--db", help="Records database (with --result-id or --run).")] = None,
    imu: Annotated[str | None, typer.Option(help="IMU stream of a recording.")] = None,
    customer: Annotated[str | None, typer.Option(
        "--customer", help="The customer the certificate is issued to (default: the run's, "
                           "else not stated).")] = None,
    config: Annotated[Path | None, typer.Option(
        "--config", help="The laboratory configuration (default: $IMUCALIB_CONFIG, else "
                         "./imucalib.toml, else the user's; docs/configuration.md).")] = None,
) -> None:
    """Write the calibration certificate: U = 2u with its budget, decision, authorisation.

    Laboratory, customer, item, calibration and issue dates, equipment with certificates,
    traceability, operator and the authorising reviewer (a DRAFT until released).
    """
    from imucalib.config import use_config

    try:
        with use_config(config):
            written = _write_reports(path, run, fmt, out, result_id, db, imu, customer)
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(InvalidInputError(f"cannot write {out}: {exc.strerror or exc}")) from exc
    if not written:
        raise fail(InvalidInputError("no unit could be reported (none was calibrated)"))
    for file, rid, draft in written:
        console.print(f"wrote {file} (report {rid}{', DRAFT: not released' if draft else ''})",
                      highlight=False, soft_wrap=True)


def _write_reports(path: Path | None, run: int | None, fmt: str, out: Path | None,
                   result_id: int | None, db: str | None, imu: str | None,
                   customer: str | None) -> list[tuple[Path, str, bool]]:
    """Write the report(s) of `report` (its arguments); return (file, id, draft) of each."""
    from imucalib.exports.report import build_report, build_summary_report, laboratory_facts
    from imucalib.report.document import write_report

    formats = tuple(dict.fromkeys(f.strip() for f in fmt.split(",")))
    if not formats or any(f not in ("pdf", "html") for f in formats):
        raise InvalidInputError(f"--format must be pdf, html or pdf,html; got {fmt!r}")
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
        given: dict[str, Any] = {"customer": customer or ""}
        reviews: Any = None
        run_view: Any = None
        if rid is not None:
            given, reviews, run_view = _records_facts(db, rid, customer)
        unit_recording = recording if recording is not None else _recording_of(
            unit_result, path, run_view)
        document = build_report(unit_result, recording=unit_recording, review=reviews,
                                result_id=rid, facts=laboratory_facts(**given))
        for form in formats:
            name = (f"{file_stem(stem, unit_result.unit, unit_result.procedure)}.report.{form}"
                    if len(units) > 1 or run is not None else f"{stem}.report.{form}")
            target = (folder / name if folder is not None else
                      out.with_suffix(f".{form}") if out is not None and len(formats) > 1 else
                      out if out is not None else path.with_name(name))
            target.parent.mkdir(parents=True, exist_ok=True)
            written.append((write_report(document, target, form), document.report_id,
                            bool(document.watermark)))
        ids[str(unit_result.unit)] = document.report_id
    if len(units) > 1:
        document = build_summary_report(result, recordings=[path], report_ids=ids)
        for form in formats:
            target = ((folder or path.parent)
                      / f"{file_stem(stem, result.unit, result.procedure)}.summary.report.{form}")
            written.append((write_report(document, target, form), document.report_id, False))
    return written
