"""The audit trail of the web page: who did what (docs/web.md, "The audit trail").

Every action is an ``audit_events`` row of the records database: chained by hash and signed by
the station key like every record (:mod:`imucalib.records.access`), so an edited, deleted or
forged row is named by ``imucalib records verify``. Logins, logouts and lock changes are
written with the action they record (one transaction); :func:`record` writes the others.

:data:`router`: ``GET /audit`` (reviewers and admins), newest first, with the chain's status.
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Depends, Request
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from imucalib.records.access import LoginSession
from imucalib.web.auth import require
from imucalib.web.context import context_of
from imucalib.web.render import render

__all__ = ["chain_problems", "record", "router"]

router = APIRouter()


async def record(request: Request, login: LoginSession, action: str, *, run_ref: str = "",
                 details: dict[str, Any] | None = None) -> int:
    """Append an audit row naming `login`'s user; return its sequence number."""
    web = context_of(request)
    return await run_in_threadpool(lambda: web.records.audit(
        login.user.name, action, station=web.station, run_ref=run_ref, details=details))


def chain_problems(problems: list[Any]) -> list[Any]:
    """Return the problems of a verify report that concern the audit trail or the logins."""
    return [p for p in problems
            if p.table in ("audit_events", "user_credentials", "users", "user_events",
                           "signing_keys")]


@router.get("/audit")
async def audit_page(request: Request,
                     login: Annotated[LoginSession, Depends(require("audit"))],
                     run: str | None = None, actor: str | None = None,
                     limit: int = 200) -> Response:
    """List the newest audit rows (optionally of one run or one user) and the chain's status."""
    web = context_of(request)
    limit = max(1, min(limit, 5000))
    rows = await run_in_threadpool(lambda: web.records.audit_log(limit=limit, run_ref=run,
                                                                 actor=actor))
    report = await run_in_threadpool(lambda: web.records.verify_report(recordings=False))
    return render(request, "audit.html", rows=rows, problems=chain_problems(
        list(report.problems)), run=run or "", actor=actor or "", limit=limit)
