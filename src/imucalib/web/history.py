"""A unit's history, its drift, and the records' state (docs/web.md, "History and records").

``GET /units/{serial}``
    Every calibration of the unit over time (amended versions too), when it is due, and the
    drift of one parameter (``?parameter=NAME``): a figure and its values in display units.
``GET /units/{serial}/drift.svg?parameter=NAME``
    The drift figure (``imucalib records drift --figure``'s, as SVG): each calibration's value
    with ±2σ bars against its date.
``GET /records``
    Whether the records verify (``imucalib records verify`` without re-hashing the recordings),
    the units with their due dates (Eq. (R.4) of docs/records.md) and the equipment due.

Everything here only reads the records.
"""

from __future__ import annotations

import tempfile
import threading
from datetime import UTC, datetime
from pathlib import Path
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Request
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from imucalib.errors import CalibrationError
from imucalib.records.access import LoginSession
from imucalib.web.auth import require
from imucalib.web.context import context_of
from imucalib.web.render import WebError, render

__all__ = ["drift_svg", "router"]

router = APIRouter()
#: matplotlib's figures are drawn one at a time.
_DRAW = threading.Lock()


def drift_svg(serial: str, parameter: str, rows: list[Any]) -> bytes:
    """Return the drift figure of `rows` (:class:`~imucalib.records.views.DriftPoint`) as SVG."""
    from imucalib.report.console import display_unit
    from imucalib.report.drift_figure import save_drift_figure

    shown, scale = display_unit(parameter, rows[0].unit if rows else "")
    with _DRAW, tempfile.TemporaryDirectory() as tmp:
        path = save_drift_figure(Path(tmp) / "drift.svg", [r.calibrated_utc for r in rows],
                                 [r.value / scale for r in rows],
                                 [r.std / scale for r in rows],
                                 title=f"{serial} {parameter}", unit=shown)
        return path.read_bytes()


def _parameters(history: list[Any]) -> list[str]:
    names: list[str] = []
    for entry in history:
        if entry.current:
            names += [p.name for p in entry.parameters if p.name not in names]
    return names


def _drift_rows(rows: list[Any], parameter: str) -> list[dict[str, Any]]:
    from imucalib.report.console import display_parameter

    out = []
    for r in rows:
        value, std, unit = display_parameter(parameter, r.value, r.std, r.unit)
        out.append({"when": r.calibrated_utc, "value": value, "std": std, "unit": unit,
                    "result_id": r.result_id})
    return out


@router.get("/units/{serial}")
async def unit_page(request: Request, serial: str,
                    login: Annotated[LoginSession, Depends(require("view"))],
                    parameter: str = "") -> Response:
    """Show a unit's calibrations, its due date and the drift of one parameter."""
    web = context_of(request)

    def gather() -> dict[str, Any]:
        history = web.records.history(serial)
        due = next((u for u in web.records.unit_status() if u.serial == serial), None)
        names = _parameters(history)
        chosen = parameter if parameter in names else (names[0] if names else "")
        drift = _drift_rows(web.records.drift(serial, chosen), chosen) if chosen else []
        releases = {e.result_id: web.records.release_status(e.result_id) for e in history}
        return {"history": history, "due": due, "names": names, "chosen": chosen,
                "drift": drift, "releases": releases}

    try:
        values = await run_in_threadpool(gather)
    except CalibrationError as exc:
        raise WebError(404, str(exc)) from exc
    return render(request, "unit.html", serial=serial,
                  today=datetime.now(UTC).date(), **values)


@router.get("/units/{serial}/drift.svg")
async def drift_figure(request: Request, serial: str,
                       login: Annotated[LoginSession, Depends(require("view"))],
                       parameter: str = "") -> Response:
    """Send the drift figure of one parameter of the unit (SVG)."""
    web = context_of(request)

    def draw() -> bytes:
        chosen = parameter or next(iter(_parameters(web.records.history(serial))), "")
        if not chosen:
            raise WebError(404, f"unit {serial} has no calibrated parameter to draw")
        return drift_svg(serial, chosen, web.records.drift(serial, chosen))

    try:
        svg = await run_in_threadpool(draw)
    except CalibrationError as exc:
        raise WebError(404, str(exc)) from exc
    return Response(svg, media_type="image/svg+xml")


@router.get("/records")
async def records_page(request: Request,
                       login: Annotated[LoginSession, Depends(require("view"))]) -> Response:
    """Show whether the records verify, the units' due dates and the equipment due."""
    web = context_of(request)

    def gather() -> dict[str, Any]:
        report = web.records.verify_report(recordings=False)
        return {"problems": list(report.problems), "notes": list(report.notes),
                "units": web.records.unit_status(),
                "equipment_due": web.records.due_equipment()}

    values = await run_in_threadpool(gather)
    return render(request, "records.html", today=datetime.now(UTC).date(), **values)
