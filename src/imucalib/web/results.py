"""A run's results: the calibration, its report and exports, and its review (docs/web.md).

``GET /runs/{id}/results``
    What the run produced (the report once its recording is calibrated).
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Request
from starlette.responses import Response

from imucalib.records.access import LoginSession
from imucalib.web.auth import require
from imucalib.web.pages import supervised
from imucalib.web.render import render

__all__ = ["router"]

router = APIRouter()


@router.get("/runs/{run_id}/results")
async def results_page(request: Request, run_id: str,
                       login: Annotated[LoginSession, Depends(require("view"))]) -> Response:
    """Show what the run produced (the report once its recording is calibrated)."""
    view = await supervised(request, lambda s: s.view(run_id))
    return render(request, "results.html", run=view)
