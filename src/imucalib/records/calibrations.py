"""Record a procedure's result in the run that made its recording (docs/records.md).

What ``imucalib calibrate`` and the demo call after a calibration: one calibration is one run
record, from the plan to the certificate (docs/records.md, "One calibration, one run").

- The run is found by the recording's SHA-256 (:meth:`~imucalib.records.api.Records.
  run_of_recording`): a recording ``imucalib run`` recorded gets its result(s) attached to that
  run (its plan, operator, station, equipment, times), not a second run.
- A second analysis of the same recording in the same run is the next *version* of the unit's
  result (``replaces`` the current one) with who and why as its reason: the reason given, else
  an automatic one naming the analysis options.
- Data no run recorded (a log, a CSV, an imported file, a recording of ``run --no-record``) get
  a run opened here, marked in its ``environment_json``: ``"opened_by": "calibrate"`` and
  ``"unplanned": true`` when the data carry no plan (``plan_hash`` empty).

Contents
--------
:func:`record_calibration`, :func:`reanalysis_reason`, :data:`OPENED_BY_CALIBRATE`
"""

from __future__ import annotations

from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

from imucalib.models.procedure_result import ProcedureResult

if TYPE_CHECKING:
    from imucalib.records.api import Records

__all__ = ["OPENED_BY_CALIBRATE", "OPENED_BY_RUN", "reanalysis_reason", "record_calibration"]

#: ``environment_json["opened_by"]`` of a run ``imucalib run`` recorded.
OPENED_BY_RUN: Final = "run"
#: ``environment_json["opened_by"]`` of a run opened by ``calibrate`` (no run recorded the data).
OPENED_BY_CALIBRATE: Final = "calibrate"
#: The recording's metadata keys ``imucalib run`` writes for a run opened later by calibrate.
_RUN_KEYS: Final = ("run_operator", "override_due", "station_equipment_json")
#: The longest automatic reason (the options' text is cut beyond it).
_REASON_CHARS: Final = 400


def reanalysis_reason(operator: str, reason: str = "",
                      options: Mapping[str, Any] | None = None) -> str:
    """Return the reason a re-analysis is recorded with: who, and why (given, else the options).

    ``"re-analysis by ana: wrong lever arm"``; without a reason, ``"re-analysis by ana with
    options model='per-axis', workers=2"`` (``… with the default options`` when none was given).
    """
    who = f" by {operator}" if operator else ""
    if reason.strip():
        return f"re-analysis{who}: {reason.strip()}"
    given = {k: v for k, v in (options or {}).items() if v is not None}
    if not given:
        return f"re-analysis{who} with the default options"
    text = ", ".join(f"{k}={v!r}" for k, v in sorted(given.items()))
    if len(text) > _REASON_CHARS:
        text = text[:_REASON_CHARS - 1] + "…"
    return f"re-analysis{who} with options {text}"


def _parse_utc(text: Any) -> datetime | None:
    if not isinstance(text, str) or not text:
        return None
    try:
        when = datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        return None
    return when.replace(tzinfo=UTC) if when.tzinfo is None else when.astimezone(UTC)


def _opened_run(result: ProcedureResult, recording: Path | None, sha256: str,
                operator: str) -> dict[str, Any]:
    """Return :meth:`~imucalib.records.api.Records.record_run`'s arguments for new data.

    For data no run recorded: the plan, operator, start time, due override and equipment that
    the recording carries (what ``imucalib run`` writes into it), marked as opened here.
    """
    meta: Mapping[str, Any] = {}
    plan_name, plan_hash = "", ""
    if recording is not None and recording.suffix.lower() in (".h5", ".hdf5"):
        from imucalib.io.context import RecordingContext
        from imucalib.io.opening import open_recording

        with open_recording(recording) as rec:
            meta = dict(rec.metadata)
        context = RecordingContext.of(meta)
        plan_name, plan_hash = context.plan_name, context.plan_hash
    environment: dict[str, Any] = {
        "opened_by": OPENED_BY_CALIBRATE, "unplanned": not plan_hash,
        "note": ("no run was recorded for these data; calibrate opened this run"
                 + ("" if plan_hash else " (unplanned: the data carry no plan)"))}
    if operator:
        environment["analysed_by"] = operator
    source = meta.get("source") or ("" if recording is None
                                    or recording.suffix.lower() in (".h5", ".hdf5") else "log")
    if source:
        environment["source"] = str(source)
    for key in ("source_file", "source_sha256", *_RUN_KEYS):
        value = meta.get(key)
        if value not in (None, "", [], {}):
            environment[key.removesuffix("_json")] = value
    return {"plan_name": plan_name, "plan_hash": plan_hash, "procedure": str(result.procedure),
            "recording": recording, "recording_sha256": sha256 or None,
            "environment": environment,
            "operator": str(meta.get("run_operator") or operator),
            "started_utc": _parse_utc(meta.get("run_started_utc"))}


def _equipment_used(records: Records, described: Any) -> tuple[list[int], str | None]:
    """Return the ids (and station) of the equipment a recording says its run used.

    Only equipment registered in these records under that id with the same serial and
    certificate is linked (a recording made against another database links none).
    """
    if not isinstance(described, list):
        return [], None
    known = {e.equipment_id: e for e in records.equipment(current_only=False)}
    ids, station = [], None
    for item in described:
        if not isinstance(item, Mapping) or not isinstance(item.get("equipment_id"), int):
            continue
        eq = known.get(int(item["equipment_id"]))
        if eq is not None and eq.serial == item.get("serial") \
                and eq.certificate == item.get("certificate"):
            ids.append(eq.equipment_id)
            station = eq.station or station
    return ids, station if ids else None


def record_calibration(result: ProcedureResult, recording: Path | None, *, db: str | None,
                       operator: str = "", reason: str = "",
                       options: Mapping[str, Any] | None = None,
                       recording_sha256: str = "") -> str:
    """Record a procedure result in the run of its recording; return one line saying where.

    Each unit's result with reported parameters is recorded as its result document (the result
    contract; a batch, P2, records each unit that was calibrated); a result without parameters
    is only noted. The run is the one that recorded `recording` (same SHA-256), else a run
    opened here (module docstring); a unit that already has a result of this procedure in that
    run gets a new version of it, recorded with :func:`reanalysis_reason` (`operator`, `reason`,
    the analysis `options`). `recording_sha256`, when the caller has hashed the recording
    already (the pipeline's provenance), saves reading it a second time.
    """
    units = list(result.members) or [result]
    recordable = [u for u in units if not u.error and u.parameter_rows()]
    if not recordable:
        return f"not recorded: a {result.procedure} result has no calibrated parameters"
    from imucalib.errors import RecordsError
    from imucalib.io.hashing import file_sha256
    from imucalib.records.api import open_records

    sha = recording_sha256
    if not sha and recording is not None and recording.is_file():
        try:
            sha = file_sha256(recording)
        except OSError as exc:
            raise RecordsError(f"cannot hash the recording {recording}: {exc}") from exc
    records = open_records(db)
    try:
        found = records.run_of_recording(sha, recording) if sha else None
        if found is None:
            fields = _opened_run(result, recording, sha, operator)
            fields["equipment"], fields["station"] = _equipment_used(
                records, fields["environment"].get("station_equipment"))
            run_id = records.record_run(**fields)
        else:
            run_id = found.run_id
        why = reanalysis_reason(operator, reason, options)
        done = [records.record_analysis(run_id, unit, passed=unit.passed,
                                        serial=str(unit.unit), reason=why)
                for unit in recordable]
        ids = ", ".join(str(rid) if old is None else f"{rid} (re-analysis, replaces {old})"
                        for rid, old in done)
        if found is None:
            return f"recorded run {run_id}, result(s) {ids} in {records.url}"
        plan = f" of plan {found.plan_name}" if found.plan_name else ""
        return f"recorded result(s) {ids} in run {run_id}{plan} in {records.url}"
    finally:
        records.close()
