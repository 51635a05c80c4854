"""The records' read side: stored rows as the views a user sees, and the due rules.

Every function takes an open :class:`~sqlalchemy.orm.Session` (the snapshot of one read
transaction, :meth:`imucalib.records.api.Records._run`) and returns plain views
(:mod:`imucalib.records.views`); nothing here writes. A stored value not of its column's type,
or a row naming another that is not there, is refused with a message that asks for
``imucalib records verify``.

Due rules (docs/records.md, "Due rules")
----------------------------------------
(R.4) a unit's due date = the date of its last calibration + its interval (its own
      ``recal_interval_days``, else the `interval_days` asked for); the last calibration is the
      latest calibration date (:func:`calibration_date`: its run's ``started_utc``, else its
      ``ended_utc``, else the ``created_utc`` of the result's first version, so that an
      amendment or a re-analysis keeps it) among its current results whose decision is not a
      fail; a unit with none is due now;
(R.5) a piece of equipment is due when its current certificate's ``due_on`` ≤ the date asked
      (a missing ``due_on`` is due).

Contents
--------
:func:`find_unit`, :func:`calibration_date`, :func:`history_entries`, :func:`unit_history`,
:func:`drift_points`, :func:`unit_status`, :func:`equipment_views`, :func:`run_view`,
:func:`runs_of_plan`, :func:`run_of_recording`, :func:`result_document`; the shared
:func:`to_utc` and :func:`dangling`.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from datetime import UTC, datetime, timedelta
from typing import Any

from sqlalchemy import or_, select
from sqlalchemy.orm import Session

from imucalib.errors import RecordsError
from imucalib.records import chain
from imucalib.records.schema import Equipment, Result, ResultParameter, Review, Run, Station, Unit
from imucalib.records.views import (
    DriftPoint,
    DueUnit,
    EquipmentView,
    HistoryEntry,
    ParameterRow,
    ReviewView,
    RunView,
)

__all__ = ["calibration_date", "dangling", "drift_points", "equipment_views", "find_unit",
           "history_entries", "result_document", "run_of_recording", "run_view",
           "runs_of_plan", "to_utc", "unit_history", "unit_status"]


def to_utc(value: datetime | None) -> datetime | None:
    """Return a stored time as an aware UTC datetime (a naive one is UTC); None stays None."""
    if value is None:
        return None
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


def _as_utc(value: datetime) -> datetime:
    out = to_utc(value)
    assert out is not None
    return out


def dangling(table: str, row_id: int, column: str, value: Any) -> RecordsError:
    """Make the error for a row that names another row that is not there."""
    return RecordsError(f"the records database has a problem: {table} row {row_id} names "
                        f"{column} {value!r}, which is not there (a dangling reference); run "
                        "`imucalib records verify`")


def _number(value: Any) -> float:
    """Return a stored number as a float; anything else (text in a float column) is refused."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"a parameter value or σ is not a number ({value!r})")
    return float(value)


def find_unit(session: Session, serial: str) -> Unit:
    """Return the unit `serial` (RecordsError naming known serials if there is none)."""
    unit = session.scalars(select(Unit).where(Unit.serial == serial)).first()
    if unit is None:
        known = session.scalars(select(Unit.serial).order_by(Unit.seq).limit(10)).all()
        raise RecordsError(f"no unit with serial {serial!r} in the records; known serials: "
                           f"{', '.join(known) or 'none'}")
    return unit


def _first_version(session: Session, res: Result) -> Result:
    """Return the first version (version 1) of `res`, following ``replaces_id`` back."""
    first, seen = res, {res.id}
    while first.replaces_id is not None and first.replaces_id not in seen:
        earlier = session.get(Result, first.replaces_id)
        if earlier is None:
            break
        seen.add(earlier.id)
        first = earlier
    return first


def calibration_date(session: Session, run: Run, res: Result) -> datetime:
    """Return a result's calibration date (UTC): its run's, which no new version changes.

    The run's ``started_utc``, else its ``ended_utc``, else (a run with no times: one opened by
    ``calibrate`` for a recording no run recorded) the ``created_utc`` of the result's first
    version. An amendment or a re-analysis (version n + 1, in the same run) therefore keeps the
    date of the calibration it corrects, and the due date (R.4) with it.
    """
    return (to_utc(run.started_utc) or to_utc(run.ended_utc)
            or _as_utc(_first_version(session, res).created_utc))


def result_document(session: Session, result_id: int) -> dict[str, Any]:
    """Return the stored document of a result (RecordsError if unknown)."""
    row = session.get(Result, result_id)
    if row is None:
        raise RecordsError(f"no result with id {result_id} in the records")
    return dict(json.loads(row.document_json))


def history_entries(session: Session, results: Iterable[Result]) -> list[HistoryEntry]:
    """Return `results` as history entries: parameters, reviews, versions, calibration date."""
    out = []
    for res in results:
        run = session.get(Run, res.run_id)
        if run is None:
            raise dangling("results", res.id, "run", res.run_id)
        unit = session.get(Unit, res.unit_id)
        if unit is None:
            raise dangling("results", res.id, "unit", res.unit_id)
        successor = session.scalars(select(Result.id)
                                    .where(Result.replaces_id == res.id)).first()
        params = session.scalars(select(ResultParameter)
                                 .where(ResultParameter.result_id == res.id)
                                 .order_by(ResultParameter.id)).all()
        reviews = session.scalars(select(Review).where(Review.result_id == res.id)
                                  .order_by(Review.seq)).all()
        out.append(HistoryEntry(
            result_id=res.id, run_id=res.run_id, serial=unit.serial,
            procedure=res.procedure, model=res.model, version=res.version,
            calibrated_utc=calibration_date(session, run, res),
            created_utc=_as_utc(res.created_utc), passed=res.passed,
            replaces=res.replaces_id, replaced_by=successor,
            amendment_reason=res.amendment_reason,
            parameters=tuple(ParameterRow(str(p.name), _number(p.value), _number(p.std),
                                          str(p.unit)) for p in params),
            reviews=tuple(ReviewView(r.id, r.result_id, r.reviewer,
                                     _as_utc(r.reviewed_utc), r.approved, r.comment)
                          for r in reviews),
            plan_name=run.plan_name, plan_hash=run.plan_hash))
    return out


def unit_history(session: Session, serial: str) -> list[HistoryEntry]:
    """Return every result of unit `serial` in recording order, amended ones included."""
    unit = find_unit(session, serial)
    rows = session.scalars(select(Result).where(Result.unit_id == unit.id)
                           .order_by(Result.seq)).all()
    return history_entries(session, rows)


def drift_points(serial: str, parameter: str, history: Sequence[HistoryEntry]
                 ) -> list[DriftPoint]:
    """Return `parameter` across the current entries of a unit's `history`, oldest first.

    Raises
    ------
    RecordsError
        A parameter none of the unit's current results carries.
    """
    entries = [e for e in history if e.current]
    points = []
    for e in entries:
        try:
            p = e.parameter(parameter)
        except KeyError:
            continue
        assert e.calibrated_utc is not None
        points.append(DriftPoint(e.calibrated_utc, p.value, p.std, p.unit, e.result_id))
    if entries and not points:
        names = sorted({p.name for e in entries for p in e.parameters})
        raise RecordsError(f"no result of unit {serial!r} carries parameter {parameter!r}; "
                           f"they carry {', '.join(names[:12])}"
                           f"{' …' if len(names) > 12 else ''}")
    return sorted(points, key=lambda d: (d.calibrated_utc, d.result_id))


def unit_status(session: Session, interval_days: int) -> list[DueUnit]:
    """Return every unit with its last good calibration and when it is due, Eq. (R.4)."""
    due = []
    replaced = set(session.scalars(select(Result.replaces_id).where(
        Result.replaces_id.is_not(None))))
    for unit in session.scalars(select(Unit).order_by(Unit.seq)).all():
        interval = unit.recal_interval_days or interval_days
        rows = session.scalars(
            select(Result).where(Result.unit_id == unit.id,
                                 or_(Result.passed.is_(None), Result.passed.is_(True)))
        ).all()
        best: tuple[datetime, int] | None = None
        for res in rows:
            if res.id in replaced:
                continue
            run = session.get(Run, res.run_id)
            if run is None:
                raise dangling("results", res.id, "run", res.run_id)
            when = calibration_date(session, run, res)
            if best is None or when > best[0]:
                best = (when, res.id)
        if best is None:
            due.append(DueUnit(unit.serial, unit.model, None, None, interval, None))
            continue
        last = best[0].date()
        due.append(DueUnit(unit.serial, unit.model, last,
                           last + timedelta(days=interval), interval, best[1]))
    return due


def equipment_views(session: Session, *, current_only: bool) -> list[EquipmentView]:
    """Return the equipment (only current certificates with `current_only`), in order."""
    replaced = set(session.scalars(select(Equipment.replaces_id).where(
        Equipment.replaces_id.is_not(None))))
    out = []
    for eq in session.scalars(select(Equipment).order_by(Equipment.seq)):
        if current_only and eq.id in replaced:
            continue
        station = session.get(Station, eq.station_id) if eq.station_id else None
        out.append(EquipmentView(eq.id, station.name if station else "", eq.kind,
                                 eq.model, eq.serial, eq.certificate, eq.calibrated_on,
                                 eq.due_on, eq.replaces_id))
    return out


def run_view(session: Session, run: Run) -> RunView:
    """Return a run with its station, equipment and results."""
    station = session.get(Station, run.station_id) if run.station_id else None
    eq = chain.children_of(session, run)["equipment"]
    results = session.scalars(select(Result.id).where(Result.run_id == run.id)
                              .order_by(Result.seq)).all()
    return RunView(run.id, run.plan_name, run.plan_hash, run.procedure, run.recording_path,
                   run.recording_sha256, dict(json.loads(run.environment_json)),
                   run.operator, run.software_version, station.name if station else "",
                   tuple(eq), to_utc(run.started_utc), to_utc(run.ended_utc), tuple(results))


def runs_of_plan(session: Session, plan: str) -> list[RunView]:
    """Return every run whose plan hash or plan name is `plan`, oldest first."""
    runs = session.scalars(select(Run).where(or_(Run.plan_hash == plan, Run.plan_name == plan))
                           .order_by(Run.seq)).all()
    return [run_view(session, r) for r in runs]


def run_of_recording(session: Session, sha256: str, path: str) -> RunView | None:
    """Return the run that recorded the bytes `sha256` (that at `path` first), or None."""
    rows = session.scalars(select(Run).where(Run.recording_sha256 == sha256)
                           .order_by(Run.seq)).all()
    if not rows:
        return None
    same = [r for r in rows if path and r.recording_path == path]
    return run_view(session, (same or list(rows))[0])
