"""``imucalib records …``: the calibration records database (docs/records.md).

``list``, ``runs``, ``show``, ``history``, ``drift``, ``due``, ``review``, ``amend``, ``verify``,
``rekey``, ``backup``, ``restore``, ``add-equipment``, ``recertify`` and ``equipment``; every
command
takes ``--db URL`` (default ``$IMUCALIB_DB``, else ``records.db`` in the user's data directory)
and the listing ones ``--json``. ``imucalib calibrate`` records by default through
:func:`imucalib.records.calibrations.record_calibration`.
"""

from __future__ import annotations

import json
from datetime import date
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from imucalib.cli._app import app, console, fail, typer_app
from imucalib.errors import CalibrationError, InvalidInputError

if TYPE_CHECKING:
    from imucalib.records.api import Records

__all__ = ["records_app"]

records_app = typer_app(help="The calibration records: history, drift, due dates, reviews, "
                             "amendments, tamper evidence, backups (docs/records.md).",
                        no_args_is_help=True)
app.add_typer(records_app, name="records")

Db = Annotated[str | None, typer.Option(
    "--db", help="Database URL or SQLite file (default: $IMUCALIB_DB, else records.db in the "
                 "user's data directory).")]
Json = Annotated[bool, typer.Option("--json", help="Print JSON instead of a table.")]


def _open(db: str | None) -> Records:
    from imucalib.records import open_records

    return open_records(db)


def _jsonable(value: Any) -> Any:
    from dataclasses import asdict, is_dataclass

    if is_dataclass(value) and not isinstance(value, type):
        return _jsonable(asdict(value))
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, date):
        return value.isoformat()
    return value


def _print(rows: list[Any], as_json: bool, title: str, columns: list[str]) -> None:
    data = [_jsonable(r) for r in rows]
    if as_json:
        console.print_json(json.dumps(data))
        return
    table = Table(*columns, title=title)
    for row in data:
        table.add_row(*("" if row.get(c) is None else str(row.get(c)) for c in columns))
    console.print(table)


@records_app.command("list")
def list_units(db: Db = None, as_json: Json = False) -> None:
    """List the units and when each is due (the last calibration of each)."""
    try:
        with _open(db) as records:
            rows = records.unit_status()
    except CalibrationError as exc:
        raise fail(exc) from exc
    _print(rows, as_json, "units", ["serial", "model", "last_calibrated", "due_on",
                                    "result_id"])


@records_app.command()
def history(serial: Annotated[str, typer.Argument(help="The unit's serial number.")],
            db: Db = None, as_json: Json = False) -> None:
    """Every result of a unit, amendments beside what they replaced."""
    try:
        with _open(db) as records:
            rows = records.history(serial)
    except CalibrationError as exc:
        raise fail(exc) from exc
    _print(rows, as_json, f"history of {serial}",
           ["result_id", "version", "procedure", "calibrated_utc", "passed", "replaces",
            "replaced_by", "amendment_reason"])


@records_app.command()
def runs(plan: Annotated[str, typer.Argument(help="A plan's name or hash.")], db: Db = None,
         as_json: Json = False) -> None:
    """Every run of a plan, oldest first."""
    try:
        with _open(db) as records:
            rows = records.runs_of_plan(plan)
    except CalibrationError as exc:
        raise fail(exc) from exc
    _print(rows, as_json, f"runs of {plan}", ["run_id", "plan_name", "procedure", "operator",
                                               "started_utc", "recording_path"])


@records_app.command()
def show(result_id: Annotated[int, typer.Argument(help="Result id.")], db: Db = None,
         as_json: Annotated[bool, typer.Option(
             "--json", help="Print JSON: result, run, equipment, reviews, release and the "
                            "stored result document.")] = False) -> None:
    """Print one result, its run, its reviews and whether it is released.

    The run: plan, operator, station, the equipment used with its certificates, start and end.
    """
    try:
        with _open(db) as records:
            entry = records.result(result_id)
            run = records.run(entry.run_id)
            known = {e.equipment_id: e for e in records.equipment(current_only=False)}
            release = records.release_status(result_id)
            doc = records.result_document(result_id) if as_json else {}
            unverified = records.reviews_unverified()
    except CalibrationError as exc:
        raise fail(exc) from exc
    equipment = [known[i] for i in run.equipment_ids if i in known]
    if as_json:
        console.print_json(json.dumps(_jsonable({
            "result": entry, "run": run, "equipment": equipment,
            "reviews": [] if unverified else entry.reviews,
            "release": None if unverified else release, "reviews_unverified": unverified,
            "document": doc}), default=str))
        return
    _show_text(entry, run, equipment, None if unverified else release, unverified)


def _utc_text(value: Any) -> str:
    return "—" if value is None else f"{value:%Y-%m-%d %H:%M:%S} UTC"


def _show_text(entry: Any, run: Any, equipment: list[Any], release: Any,
               unverified: str = "") -> None:
    from imucalib.report.console import display_parameter

    verdict = {True: "PASS", False: "FAIL", None: "no decision"}[entry.passed]
    state = ("current" if entry.current else f"amended by result {entry.replaced_by}")
    lines = [f"result {entry.result_id}: unit {entry.serial}, procedure {entry.procedure}, "
             f"version {entry.version} ({state}), {verdict}; calibrated "
             f"{_utc_text(entry.calibrated_utc)}, recorded {_utc_text(entry.created_utc)}"]
    if entry.replaces is not None:
        lines.append(f"  replaces result {entry.replaces}: {entry.amendment_reason}")
    lines += [f"run {run.run_id}: plan {run.plan_name or '—'}"
              f"{f' ({run.plan_hash[:12]}…)' if run.plan_hash else ''}, procedure "
              f"{run.procedure or '—'}, operator {run.operator or '—'}, station "
              f"{run.station or '—'}, imucalib {run.software_version or '—'}"
              f"{', unplanned' if getattr(run, 'unplanned', False) else ''}",
              f"  started {_utc_text(run.started_utc)}, ended {_utc_text(run.ended_utc)}",
              f"  recording {run.recording_path or '—'}"
              f"{f' (sha256 {run.recording_sha256[:16]}…)' if run.recording_sha256 else ''}"]
    if run.environment:
        lines.append(f"  environment {json.dumps(run.environment, sort_keys=True)}")
    for line in lines:
        console.print(line, highlight=False, soft_wrap=True)
    params = Table("parameter", "value", "std", "unit", title="parameters (σ as reported)")
    for p in entry.parameters:
        params.add_row(p.name, *display_parameter(p.name, p.value, p.std, p.unit))
    console.print(params)
    if equipment:
        table = Table("id", "kind", "model", "serial", "certificate", "calibrated_on", "due_on",
                      title=f"equipment of run {run.run_id}")
        for e in equipment:
            table.add_row(str(e.equipment_id), e.kind, e.model, e.serial, e.certificate,
                          str(e.calibrated_on or "—"), str(e.due_on or "—"))
        console.print(table)
    else:
        console.print(f"equipment of run {run.run_id}: none recorded", highlight=False)
    if unverified:
        console.print(f"reviews of result {entry.result_id}: not shown, {unverified}",
                      highlight=False, soft_wrap=True)
        return
    if entry.reviews:
        table = Table("review", "reviewer", "reviewed_utc", "decision", "comment",
                      title=f"reviews of result {entry.result_id}")
        for r in entry.reviews:
            table.add_row(str(r.review_id), r.reviewer, _utc_text(r.reviewed_utc), r.decision,
                          r.comment)
        console.print(table)
    else:
        console.print(f"reviews of result {entry.result_id}: none", highlight=False)
    console.print(release.text(), highlight=False, soft_wrap=True)


@records_app.command()
def drift(serial: Annotated[str, typer.Argument(help="The unit's serial number.")],
          parameter: Annotated[str, typer.Argument(help="A parameter, e.g. accel_bias_x.")],
          db: Db = None, as_json: Json = False,
          figure: Annotated[Path | None, typer.Option(
              "--figure", help="Also draw the values with their 2σ bars (PNG).")] = None) -> None:
    """One parameter of a unit across its calibrations (in its display unit; --json: SI)."""
    from imucalib.report.console import display_parameter, display_unit

    try:
        with _open(db) as records:
            rows = records.drift(serial, parameter)
        si_unit = rows[0].unit if rows else ""
        shown_unit, scale = display_unit(parameter, si_unit)
        if figure is not None:
            from imucalib.report.drift_figure import save_drift_figure

            save_drift_figure(figure, [r.calibrated_utc for r in rows],
                              [r.value / scale for r in rows], [r.std / scale for r in rows],
                              title=f"{serial} {parameter}", unit=shown_unit)
    except CalibrationError as exc:
        raise fail(exc) from exc
    if as_json:
        _print(rows, as_json, f"{parameter} of {serial}",
               ["calibrated_utc", "value", "std", "unit", "result_id"])
        return
    table = Table("calibrated_utc", "value", "std", "unit", "result_id",
                  title=f"{parameter} of {serial}")
    for r in rows:
        value, std, unit = display_parameter(parameter, r.value, r.std, r.unit)
        table.add_row(str(_jsonable(r).get("calibrated_utc") or ""), value, std, unit,
                      str(r.result_id))
    console.print(table)


@records_app.command()
def due(db: Db = None, as_json: Json = False,
        as_of: Annotated[str | None, typer.Option(help="Date (YYYY-MM-DD; default today).")]
        = None,
        equipment: Annotated[bool, typer.Option(help="Equipment due instead of units.")]
        = False) -> None:
    """Units (or equipment) due for calibration."""
    try:
        day = date.fromisoformat(as_of) if as_of else date.today()
    except ValueError:
        raise fail(InvalidInputError(f"--as-of wants YYYY-MM-DD; got {as_of!r}")) from None
    try:
        with _open(db) as records:
            if equipment:
                rows: list[Any] = records.due_equipment(day)
                cols = ["equipment_id", "station", "kind", "model", "serial", "certificate",
                        "due_on"]
            else:
                rows = records.due_units(day)
                cols = ["serial", "model", "last_calibrated", "due_on", "result_id"]
    except CalibrationError as exc:
        raise fail(exc) from exc
    _print(rows, as_json, f"{'equipment' if equipment else 'units'} due on {day}", cols)


@records_app.command("add-equipment")
def add_equipment(kind: Annotated[str, typer.Option(help="rate-table, chamber, centrifuge …")],
                  due_on: Annotated[str, typer.Option(help="Calibration due (YYYY-MM-DD).")],
                  station: Annotated[str, typer.Option(help="The station's name.")] = "sim",
                  model: Annotated[str, typer.Option()] = "",
                  serial: Annotated[str, typer.Option()] = "",
                  certificate: Annotated[str, typer.Option(help="Its certificate id.")] = "",
                  calibrated_on: Annotated[str | None, typer.Option(
                      help="Its last calibration (YYYY-MM-DD).")] = None,
                  db: Db = None) -> None:
    """Register a station's equipment with its own calibration certificate and due date."""
    try:
        try:
            due_day = date.fromisoformat(due_on)
            cal_day = date.fromisoformat(calibrated_on) if calibrated_on else None
        except ValueError:
            raise InvalidInputError(f"dates are YYYY-MM-DD; got {due_on!r}, "
                                    f"{calibrated_on!r}") from None
        with _open(db) as records:
            if station not in {e.station for e in records.equipment()}:
                try:
                    records.add_station(station)
                except CalibrationError:
                    pass                          # it exists without equipment yet
            eid = records.add_equipment(station, kind, model=model, serial=serial,
                                        certificate=certificate, calibrated_on=cal_day,
                                        due_on=due_day)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"equipment {eid}: {kind} {model} {serial} at {station}, due {due_day}",
                  highlight=False)


def _day(text: str, option: str) -> date:
    try:
        return date.fromisoformat(text)
    except ValueError:
        raise InvalidInputError(f"{option} wants a date YYYY-MM-DD; got {text!r}") from None


@records_app.command()
def recertify(equipment_id: Annotated[int, typer.Argument(
                  metavar="EQUIPMENT_ID", help="The equipment's id (`records equipment`).")],
              certificate: Annotated[str, typer.Option(help="The new certificate's number.")],
              calibrated_on: Annotated[str, typer.Option(
                  help="When it was calibrated (YYYY-MM-DD).")],
              due_on: Annotated[str, typer.Option(help="Its new due date (YYYY-MM-DD).")],
              db: Db = None) -> None:
    """Record a renewed certificate: a new row that replaces the old one, which is kept.

    The new certificate is what `run` checks and `records due --equipment` reads; `records
    equipment --all` shows the history.
    """
    try:
        cal_day = _day(calibrated_on, "--calibrated-on")
        due_day = _day(due_on, "--due-on")
        if not certificate.strip():
            raise InvalidInputError("--certificate must name the new certificate; got ''")
        if due_day <= cal_day:
            raise InvalidInputError(f"--due-on {due_day} must come after --calibrated-on "
                                    f"{cal_day}")
        with _open(db) as records:
            new_id = records.recertify_equipment(equipment_id, certificate.strip(), cal_day,
                                                 due_day)
            eq = next(e for e in records.equipment() if e.equipment_id == new_id)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"equipment {new_id} replaces equipment {equipment_id}: {eq.kind} {eq.model} "
                  f"{eq.serial} at {eq.station or '—'}, certificate {eq.certificate}, "
                  f"calibrated {cal_day}, due {due_day}", highlight=False, soft_wrap=True)


@records_app.command("equipment")
def list_equipment(db: Db = None, as_json: Json = False,
                   every: Annotated[bool, typer.Option(
                       "--all", help="Every certificate, replaced ones too (the history).")]
                   = False,
                   station: Annotated[str | None, typer.Option(
                       help="Only this station's equipment.")] = None) -> None:
    """List the registered equipment: each current certificate (--all: with its history)."""
    try:
        with _open(db) as records:
            rows = records.equipment(current_only=not every)
    except CalibrationError as exc:
        raise fail(exc) from exc
    if station is not None:
        rows = [e for e in rows if e.station == station]
    successor = {e.replaces: e.equipment_id for e in rows if e.replaces is not None}
    today = date.today()
    listed = [{**_jsonable(e),
               "status": (f"replaced by {successor[e.equipment_id]}"
                          if e.equipment_id in successor
                          else "overdue" if e.due_on is not None and e.due_on < today
                          else "no due date" if e.due_on is None else "current")}
              for e in rows]
    if as_json:
        console.print_json(json.dumps(listed))
        return
    table = Table(*(cols := ["equipment_id", "station", "kind", "model", "serial",
                             "certificate", "calibrated_on", "due_on", "replaces", "status"]),
                  title="equipment" + (" (every certificate)" if every else ""))
    for row in listed:
        table.add_row(*("" if row.get(c) is None else str(row[c]) for c in cols))
    console.print(table)


DECISIONS = ("approve", "reject")


@records_app.command()
def review(result_id: Annotated[int, typer.Argument(help="Result id.")],
           decision: Annotated[str | None, typer.Option(
               help="approve or reject (required: a review has no default).")] = None,
           comment: Annotated[str, typer.Option(
               help="What was checked, or why rejected (required to reject).")] = "",
           user: Annotated[str | None, typer.Option(
               "--user", help="The reviewer: a user's name or initials (default "
                              "$IMUCALIB_USER).")] = None,
           db: Db = None) -> None:
    """Record a review (approve or reject) of a result's current version.

    Once the database has users the reviewer must be an active reviewer or admin who is not
    the run's operator; an approval by such a reviewer releases the result (docs/records.md,
    "Users and roles").
    """
    from imucalib.records.users import USER_ENV, resolve_user

    if decision not in DECISIONS:
        got = "none given" if decision is None else f"got {decision!r}"
        raise fail(InvalidInputError(f"--decision must be approve or reject ({got}); a review "
                                     "has no default decision"))
    try:
        with _open(db) as records:
            who = resolve_user(records, user, action="review a result")
            if not who:
                raise InvalidInputError(f"name the reviewer: pass --user NAME or set {USER_ENV}")
            rid = records.review(result_id, who, decision == "approve", comment)
            status = records.release_status(result_id)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"review {rid}: result {result_id} "
                  f"{'approved' if decision == 'approve' else 'rejected'} by {who}; "
                  f"{status.text()}", highlight=False, soft_wrap=True)


@records_app.command()
def amend(result_id: Annotated[int, typer.Argument(help="The result replaced.")],
          new_result: Annotated[Path, typer.Argument(help="The new result JSON.")],
          reason: Annotated[str, typer.Option(help="Why (recorded).")],
          db: Db = None) -> None:
    """Record a new version of a result; the original stays, `history` shows both.

    The new result file (any procedure's, docs/procedures.md "The result file") keeps its
    decision: a FAIL stays a FAIL.
    """
    from imucalib.models.result_document import load_result

    try:
        result = load_result(new_result)
        with _open(db) as records:
            rid = records.amend(result_id, result, reason, passed=result.passed)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"result {rid} amends result {result_id} ({reason})", highlight=False)


@records_app.command()
def verify(db: Db = None, as_json: Annotated[bool, typer.Option(
               "--json", help="Print the problems as JSON (a list).")] = False,
           recordings: Annotated[bool, typer.Option(
               help="Also re-hash the recording files.")] = True,
           anchors: Annotated[Path | None, typer.Option(
               help="A heads.json kept elsewhere (every backup writes one): its chain heads "
                    "must still be there, which catches a deleted last row.")] = None,
           anchor_log: Annotated[Path | None, typer.Option(
               help="The anchor log to check (default: anchors.jsonl in the records' key "
                    "folder; a backup's signing/anchors.jsonl).")] = None) -> None:
    """Re-hash and check the signature of every record, the anchor log and every recording.

    Names every problem (exit 1 when any), says which key signed what, and notes rows made
    before signing (docs/records.md, "What verify checks").
    """
    from imucalib.records.views import ChainHead

    try:
        heads: list[ChainHead] = []
        if anchors is not None:
            try:
                heads = [ChainHead(str(h["table"]), int(h["seq"]), str(h["row_hash"]))
                         for h in json.loads(anchors.read_text(encoding="utf-8"))]
            except (OSError, ValueError, KeyError, TypeError, RecursionError) as exc:
                raise InvalidInputError(f"{anchors}: not a heads.json (a list of table, seq, "
                                        f"row_hash): {exc}") from exc
        with _open(db) as records:
            report = records.verify_report(recordings=recordings, anchors=heads,
                                           anchor_log=anchor_log)
            where = records.url
    except CalibrationError as exc:
        raise fail(exc) from exc
    problems = list(report.problems)
    if as_json:
        console.print_json(json.dumps(_jsonable(problems)))
        if problems:
            raise typer.Exit(code=1)
        return
    for k in report.keys:
        signed = ", ".join(f"{t} {n}" for t, n in sorted(k.rows.items())) or "nothing"
        console.print(f"key {k.key_id} ({k.fingerprint}, "
                      f"{'trusted' if k.trusted else 'NOT trusted'}"
                      f"{', ' + k.reason if k.reason else ''}): signed {signed}",
                      highlight=False, soft_wrap=True)
    for note in report.notes:
        console.print(f"note: {note}", highlight=False, soft_wrap=True)
    if problems:
        console.print(f"{len(problems)} problem(s) in {where}:", highlight=False,
                      soft_wrap=True)
        for p in problems:
            console.print(f"  {p} [{p.kind}]", highlight=False, soft_wrap=True, markup=False)
        raise typer.Exit(code=1)
    console.print(f"every record and recording in {where} is intact", highlight=False)


@records_app.command()
def rekey(reason: Annotated[str, typer.Option(help="Why the key is replaced (recorded).")],
          lost_key: Annotated[bool, typer.Option(
              "--lost-key", help="The key file is lost: register a new key without the old "
                                 "key's endorsement (docs/records.md, \"A lost key\").")]
          = False,
          db: Db = None) -> None:
    """Replace the station key: a new key file, registered in the records.

    The old key endorses the new one; the old key file is kept as
    station.key.<fingerprint>.retired.
    """
    try:
        with _open(db) as records:
            key_id = records.rekey(reason, lost=lost_key)
            folder = records.signing_folder
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"key {key_id} registered{' (lost key: not endorsed)' if lost_key else ''}; "
                  f"the key file is {folder / 'station.key'}", highlight=False, soft_wrap=True)


@records_app.command()
def backup(dests: Annotated[list[Path], typer.Argument(help="One or more backup folders.")],
           db: Db = None,
           recordings: Annotated[bool, typer.Option(
               help="Also copy the recordings the runs name.")] = True) -> None:
    """Back up the database (a consistent snapshot) and the recordings, verified."""
    from imucalib.records.backup import backup as do_backup
    from imucalib.records.signing import LOG_FILE, PUB_FILE

    try:
        import sqlalchemy as sa

        with _open(db) as records:
            url = records.engine.url
            with records.engine.connect() as conn:
                paths = conn.execute(sa.text("SELECT recording_path FROM runs")).scalars()
                files = sorted({Path(p) for p in paths if isinstance(p, str) and p}
                               ) if recordings else []
            heads = [_jsonable(h) for h in records.heads()]
            signing = records.signing_folder
        manifests = do_backup(url, dests, recordings=files, extra_files={
            f"signing/{LOG_FILE}": signing / LOG_FILE, f"signing/{PUB_FILE}": signing / PUB_FILE})
        for dest in dests:      # the chain heads, kept apart: `verify --anchors` reads them
            (Path(dest) / "heads.json").write_text(json.dumps(heads, indent=1) + "\n",
                                                   encoding="utf-8")
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(InvalidInputError(f"cannot write heads.json: {exc}")) from exc
    for dest, m in zip(dests, manifests, strict=True):
        console.print(f"backed up into {dest}: {sum(t.rows for t in m.tables)} rows, "
                      f"{len(m.recordings)} recording(s), verified", highlight=False)


def _restore_signing(source: Path, folder: Path) -> None:
    """Copy a backup's anchor log and station.pub into the restored records' key folder."""
    import shutil

    from imucalib.records.signing import LOG_FILE, PUB_FILE

    for name in (LOG_FILE, PUB_FILE):
        src, dst = source / "signing" / name, folder / name
        if src.is_file() and not dst.exists():
            try:
                folder.mkdir(parents=True, exist_ok=True, mode=0o700)
                shutil.copyfile(src, dst)
            except OSError as exc:
                raise InvalidInputError(f"cannot copy {src} to {dst}: {exc}") from exc


@records_app.command()
def restore(source: Annotated[Path, typer.Argument(help="A backup folder.")],
            db: Annotated[str, typer.Option("--db", help="An empty database to restore into.")],
            recordings_dir: Annotated[Path | None, typer.Option(
                help="Where to put the recordings.")] = None) -> None:
    """Rebuild a database from a backup after verifying it; then verify the chain."""
    from imucalib.records import open_records
    from imucalib.records.backup import restore as do_restore
    from imucalib.records.engine import resolve_url, upgrade

    try:
        summary = do_restore(source, resolve_url(db), create_schema=upgrade,
                             recordings_dir=recordings_dir)
        with open_records(db) as records:
            _restore_signing(source, records.signing_folder)
            problems = records.verify(recordings=recordings_dir is not None)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"restored {sum(summary.rows.values())} rows of {len(summary.rows)} tables "
                  f"and {len(summary.files)} recording(s) into {db}", highlight=False)
    if problems:
        _print(problems, False, "problems after restore", ["table", "key", "what"])
        raise typer.Exit(code=1)
    console.print("the restored records verify", highlight=False)
