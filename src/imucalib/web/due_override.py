"""Overdue station equipment at the start of a run from the page, and its override.

``imucalib run`` refuses a station whose equipment is overdue for calibration unless
``--override-due REASON`` is given (:func:`imucalib.records.run_entry.check_due`, docs/records.md).
The page does the same before it starts a run: an operator sees the refusal in one line; an
engineer may start anyway by giving a reason, which the worker passes to the same check and
which is recorded with the run (its recording's ``override_due`` and the records' run
environment) and in the ``start`` audit row naming the engineer (docs/web.md, "Overdue
equipment"). ISO/IEC 17025:2017, 6.4.13 asks that the use of equipment whose calibration status
is not current be recorded and justified; the reason is that justification.
"""

from __future__ import annotations

from datetime import date
from pathlib import Path
from typing import Any

__all__ = ["due_station_name", "overdue_equipment", "overdue_line"]


def due_station_name(station_spec: str) -> str:
    """Return the station name whose equipment a run on `station_spec` uses.

    ``"sim"`` for the twin, else the station file's stem, as the worker checks it
    (:mod:`imucalib.web.run_worker`).
    """
    return "sim" if station_spec == "sim" else Path(station_spec).stem


def overdue_equipment(equipment: list[Any], station_name: str, today: date) -> list[Any]:
    """Return the current equipment of `station_name` whose certificate is due before `today`.

    The rule of :func:`imucalib.records.run_entry.check_due`: due strictly before today.
    """
    return [e for e in equipment if e.station == station_name and e.due_on is not None
            and e.due_on < today]


def overdue_line(station_name: str, overdue: list[Any], *, may_override: bool) -> str:
    """Return the one line that refuses a start on `overdue` equipment, saying what to do."""
    names = "; ".join(f"{e.kind} {e.model} {e.serial} (equipment {e.equipment_id}, due "
                      f"{e.due_on})" for e in overdue)
    then = ("give the reason to use it anyway in “Override overdue equipment” (recorded with "
            "the run and in the audit trail)" if may_override else
            "only an engineer may start a run on it, giving a reason")
    return (f"station {station_name!r} has equipment overdue for calibration: {names}; record "
            f"its new certificate (`imucalib records recertify`), or {then}")
