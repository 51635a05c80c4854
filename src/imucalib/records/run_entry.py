"""What a station run puts in the records and in its recording: equipment, due dates, operator.

Shared by ``imucalib run`` and the web page's run worker (:mod:`imucalib.web.run_worker`), so
that a run from either is checked and recorded alike (docs/records.md, "One calibration, one
run"; docs/web-runs.md).

Contents
--------
:func:`check_due`, :func:`run_metadata`, :func:`run_environment`, :func:`equipment_row`,
:func:`records_exist`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from imucalib.errors import ConfigurationError

__all__ = ["check_due", "equipment_row", "records_exist", "run_environment", "run_metadata"]


def equipment_row(e: Any) -> dict[str, Any]:
    """Return one piece of equipment as the run's environment and its recording describe it."""
    return {"equipment_id": e.equipment_id, "kind": e.kind, "model": e.model,
            "serial": e.serial, "certificate": e.certificate,
            "calibrated_on": e.calibrated_on.isoformat() if e.calibrated_on else None,
            "due_on": e.due_on.isoformat() if e.due_on else None}


def run_environment(status: str, overdue: list[Any], override: str | None,
                    customer: str | None = None) -> dict[str, Any]:
    """Return the run's ``environment_json``: its status, the customer and any due override."""
    env: dict[str, Any] = {"opened_by": "run", "status": status,
                           "override_due": (override or "").strip() if overdue else ""}
    if customer and customer.strip():
        env["customer"] = customer.strip()
    if overdue:
        env["overdue_equipment"] = [equipment_row(e) for e in overdue]
    return env


def run_metadata(who: str, equipment: list[Any], overdue: list[Any],
                 override: str | None, customer: str | None = None) -> dict[str, str]:
    """Return what the recording keeps of the run for the records.

    ``calibrate`` of a recording no run recorded (``run --no-record``) opens its run from these
    (docs/records.md, "One calibration, one run").
    """
    meta = {"run_operator": who}
    if customer and customer.strip():
        meta["customer"] = customer.strip()
    if equipment:
        meta["station_equipment_json"] = json.dumps([equipment_row(e) for e in equipment])
    if overdue:
        meta["override_due"] = (override or "").strip()
    return meta


def check_due(db: str | None, station_name: str, override: str | None, *,
              create: bool = True) -> tuple[list[Any], list[Any]]:
    """Return the station's current equipment and the overdue part of it.

    Overdue equipment is refused unless `override` gives a reason (the caller warns that it
    runs with it). With ``create=False`` (``run --no-record``) the check is made all the same,
    but a records database that does not exist yet (an SQLite file not there: nothing is
    registered) is not created.

    Raises
    ------
    ConfigurationError
        Overdue equipment and no `override`, naming each piece and how to recertify it.
    """
    from datetime import date

    from imucalib.records import open_records

    if not create and not records_exist(db):
        return [], []
    with open_records(db) as records:
        mine = [e for e in records.equipment() if e.station == station_name]
    overdue = [e for e in mine if e.due_on is not None and e.due_on < date.today()]
    if overdue and not (override or "").strip():
        names = "; ".join(f"{e.kind} {e.model} {e.serial} (equipment {e.equipment_id}, "
                          f"certificate {e.certificate or '?'}, due {e.due_on})"
                          for e in overdue)
        raise ConfigurationError(f"station {station_name!r} has equipment overdue for "
                                 f"calibration: {names}; once recalibrated, record its new "
                                 "certificate (`imucalib records recertify EQUIPMENT_ID "
                                 "--certificate NUM --calibrated-on DATE --due-on DATE`), or "
                                 "pass --override-due REASON (recorded with the run)")
    return mine, overdue


def records_exist(db: str | None) -> bool:
    """Return False only for an SQLite records file that is not there (nothing registered)."""
    from sqlalchemy.engine import make_url
    from sqlalchemy.exc import ArgumentError

    from imucalib.records.engine import resolve_url

    try:
        url = make_url(resolve_url(db))
    except ArgumentError:
        return True                    # open_records names what is wrong with it
    if url.get_backend_name() != "sqlite" or url.database in (None, "", ":memory:"):
        return True
    return Path(url.database).exists()
