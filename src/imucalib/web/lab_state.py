"""Every station's state, read from the records database the lab's servers share.

:func:`lab_overview` reads, in one snapshot of the records database (docs/records.md):

- the stations: those with a lock row (``station_locks``), those recorded (``stations``,
  ``equipment``) and those named by the audit trail (a web server's ``--station``);
- each station's lock: holder, since when, who asked for it;
- its latest runs: the runs started from a station's page (``start`` audit rows: who, when,
  the plan, the serials; the last command sent to the run) and the runs recorded for the
  station (``runs``: operator, status, serials of their results), newest first; a page's run
  that reached the records (its recording is in the run's folder) shows its recorded status;
- its equipment whose certificate is due (Eq. (R.5) of docs/records.md) or due within
  :data:`SOON_DAYS`.

Read-only (:meth:`~imucalib.records.api.Records.read_snapshot`): it writes nothing (docs/web.md,
"Lab overview").
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from datetime import UTC, date, datetime, timedelta
from typing import TYPE_CHECKING, Any, Final

from sqlalchemy import select

from imucalib.records.schema import (
    AuditEvent,
    Equipment,
    Result,
    Run,
    Station,
    StationLock,
    Unit,
)

if TYPE_CHECKING:
    from sqlalchemy.orm import Session

    from imucalib.records.api import Records

__all__ = ["SOON_DAYS", "EquipmentDue", "LabRun", "StationState", "lab_overview"]

#: Equipment due within this many days is shown as due soon. [days]
SOON_DAYS: Final = 30
#: The commands of a page's run, the last of which is shown.
_COMMANDS: Final = ("prompt_answer", "abort", "resume")
#: Audit rows looked at for the page's runs (the newest).
_AUDIT_SCAN: Final = 5000


@dataclass(frozen=True)
class LabRun:
    """One run of a station: from its page (``source="page"``) or recorded (``"records"``)."""

    source: str
    started_utc: datetime | None
    plan: str
    operator: str
    status: str
    serials: tuple[str, ...] = ()
    run_ref: str = ""
    records_run_id: int | None = None
    last_command: str = ""


@dataclass(frozen=True)
class EquipmentDue:
    """A piece of equipment due (``overdue``: the due date has passed or is unknown)."""

    kind: str
    model: str
    serial: str
    due_on: date | None
    overdue: bool


@dataclass
class StationState:
    """A station's lock, latest runs and due equipment."""

    name: str
    holder: str = ""
    since_utc: datetime | None = None
    requested_by: str = ""
    requested_utc: datetime | None = None
    runs: list[LabRun] = field(default_factory=list)
    due: list[EquipmentDue] = field(default_factory=list)


def _utc(value: datetime | None) -> datetime | None:
    if value is None:
        return None
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


def _details(text: str) -> dict[str, Any]:
    try:
        value = json.loads(text or "{}")
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}


def _records_run(session: Session, run: Run, names: dict[int, str]) -> LabRun:
    units = session.scalars(select(Result.unit_id).where(Result.run_id == run.id)).all()
    env = _details(run.environment_json)
    return LabRun("records", _utc(run.started_utc), run.plan_name, run.operator,
                  str(env.get("status", "")),
                  tuple(sorted({names[u] for u in units if u in names})),
                  records_run_id=int(run.id))


def _read(session: Session, per_station: int, today: date) -> list[StationState]:
    states: dict[str, StationState] = {}

    def state(name: str) -> StationState:
        return states.setdefault(name, StationState(name))

    for lock in session.scalars(select(StationLock)):
        s = state(lock.station)
        s.holder, s.since_utc = lock.holder, _utc(lock.since_utc)
        s.requested_by, s.requested_utc = lock.requested_by, _utc(lock.requested_utc)
    stations = {int(st.id): st.name for st in session.scalars(select(Station))}
    for name in stations.values():
        state(name)
    units = {int(u.id): u.serial for u in session.scalars(select(Unit))}
    # the page's runs: "start" rows, newest first, with the last command of each
    rows = session.scalars(select(AuditEvent).where(AuditEvent.station != "")
                           .order_by(AuditEvent.seq.desc()).limit(_AUDIT_SCAN)).all()
    last_command: dict[str, str] = {}
    for row in rows:
        state(row.station)
        if row.action in _COMMANDS and row.run_ref and row.run_ref not in last_command:
            last_command[row.run_ref] = f"{row.action} by {row.actor}"
    for row in rows:
        s = state(row.station)
        if row.action != "start" or len([r for r in s.runs if r.source == "page"]) >= per_station:
            continue
        d = _details(row.details_json)
        recorded = session.scalars(select(Run).where(Run.recording_path.contains(
            f"{row.run_ref}/")).order_by(Run.seq.desc()).limit(1)).first() if row.run_ref else None
        status = str(_details(recorded.environment_json).get("status", "")) if recorded else ""
        s.runs.append(LabRun("page", _utc(row.created_utc), str(d.get("plan", "")), row.actor,
                             status or "started",
                             tuple(str(x) for x in d.get("serials") or ()),
                             run_ref=row.run_ref,
                             records_run_id=int(recorded.id) if recorded else None,
                             last_command=last_command.get(row.run_ref, "")))
    shown = {r.records_run_id for s in states.values() for r in s.runs}
    for station_id, name in stations.items():
        recorded_runs = session.scalars(select(Run).where(Run.station_id == station_id)
                                        .order_by(Run.seq.desc()).limit(per_station)).all()
        state(name).runs += [_records_run(session, r, units) for r in recorded_runs
                             if int(r.id) not in shown]
    replaced = set(session.scalars(select(Equipment.replaces_id)
                                   .where(Equipment.replaces_id.is_not(None))))
    soon = today + timedelta(days=SOON_DAYS)
    for eq in session.scalars(select(Equipment).order_by(Equipment.seq)):
        if eq.id in replaced or eq.station_id is None or eq.station_id not in stations:
            continue
        if eq.due_on is None or eq.due_on <= soon:
            state(stations[eq.station_id]).due.append(EquipmentDue(
                eq.kind, eq.model, eq.serial, eq.due_on,
                eq.due_on is None or eq.due_on <= today))
    for s in states.values():
        s.runs.sort(key=lambda r: r.started_utc or datetime.min.replace(tzinfo=UTC),
                    reverse=True)
        del s.runs[2 * per_station:]
    return sorted(states.values(), key=lambda s: s.name)


def lab_overview(records: Records, *, per_station: int = 5,
                 today: date | None = None) -> list[StationState]:
    """Return every station's state (module docstring), the stations by name.

    Parameters
    ----------
    records : Records
        The records database the lab's servers share.
    per_station : int
        Runs of each kind shown per station (the newest).
    today : date, optional
        The day equipment due dates are compared with (default: today, UTC).
    """
    day = today or datetime.now(UTC).date()
    return records.read_snapshot(lambda s: _read(s, per_station, day))
