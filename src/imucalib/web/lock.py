"""The station lock on the page: one operator holds the station at a time (docs/web.md).

The lock is kept in the records database (:mod:`imucalib.records.station_lock`), so every page
— and a lab overview of several stations sharing one database — shows who holds it. Starting a
run, answering its prompts and resuming need the lock; aborting does not (any operator or
engineer may stop the station).

:data:`router`: ``POST /lock/take``, ``POST /lock/release``, ``POST /lock/request``; each
audited (``lock``, ``unlock``, ``lock_request``).
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Request
from fastapi.responses import RedirectResponse
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from imucalib.errors import RecordsError
from imucalib.records.access import LoginSession
from imucalib.web.auth import article, can, require
from imucalib.web.context import context_of
from imucalib.web.render import WebError

__all__ = ["require_lock", "router"]

router = APIRouter()


async def require_lock(request: Request, login: LoginSession) -> None:
    """Refuse (409) unless `login`'s user holds this station's lock."""
    web = context_of(request)
    held = await run_in_threadpool(web.records.station_lock, web.station)
    if held.holder != login.user.name:
        who = f"held by {held.holder}" if held.holder else "free"
        raise WebError(409, f"take the station's lock first: station {web.station!r} is {who}")


async def _change(request: Request, work: str, login: LoginSession) -> Response:
    web = context_of(request)
    name = login.user.name
    try:
        if work == "take":
            await run_in_threadpool(web.records.take_station, web.station, name)
        elif work == "request":
            await run_in_threadpool(web.records.request_station, web.station, name)
        else:
            force = can(login, "force_unlock")
            await run_in_threadpool(lambda: web.records.release_station(web.station, name,
                                                                        force=force))
    except RecordsError as exc:
        raise WebError(409, str(exc)) from exc
    return RedirectResponse("/", status_code=303)


@router.post("/lock/take")
async def take(request: Request,
               login: Annotated[LoginSession, Depends(require("lock"))]) -> Response:
    """Take the station (refused while another user holds it)."""
    return await _change(request, "take", login)


@router.post("/lock/request")
async def ask(request: Request,
              login: Annotated[LoginSession, Depends(require("lock"))]) -> Response:
    """Ask the holder for the station (shown to everyone)."""
    return await _change(request, "request", login)


@router.post("/lock/release")
async def release(request: Request,
                  login: Annotated[LoginSession, Depends(require("view"))]) -> Response:
    """Release the station: its holder, or an admin for a holder who left."""
    if not (can(login, "lock") or can(login, "force_unlock")):
        raise WebError(403, f"{login.user.name} is {article(login.user.role)}: only the holder "
                            "(an operator or engineer) or an admin releases the station")
    return await _change(request, "release", login)
