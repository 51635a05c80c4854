"""The laboratory's overview: every station's state from the shared records database.

``GET /lab``
    Every station the records database knows (docs/web.md, "Lab overview"): who holds it,
    since when and who asked for it; its latest runs (from its page and as recorded) with their
    operator, status and serials; its equipment due. Any logged-in role may read it; it
    changes nothing (:mod:`imucalib.web.lab_state`).
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Request
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from imucalib.errors import CalibrationError
from imucalib.records.access import LoginSession
from imucalib.web.auth import require
from imucalib.web.context import context_of
from imucalib.web.render import WebError, render

__all__ = ["router"]

router = APIRouter()


@router.get("/lab")
async def lab_page(request: Request,
                   login: Annotated[LoginSession, Depends(require("view"))]) -> Response:
    """Show every station's lock, latest runs and due equipment."""
    from imucalib.web.lab_state import SOON_DAYS, lab_overview

    web = context_of(request)
    try:
        stations = await run_in_threadpool(lab_overview, web.records)
    except CalibrationError as exc:
        raise WebError(503, f"the records database cannot be read: {exc}") from exc
    return render(request, "lab.html", stations=stations, soon_days=SOON_DAYS,
                  this_station=web.station)
