"""``/ws/runs/{id}``: a run's live events to its page (docs/web.md, "Live view").

The socket only sends: the supervisor's events (:mod:`imucalib.web.events`), a ``snapshot``
first, as JSON text frames. Commands go as POSTs with the CSRF token
(:mod:`imucalib.web.pages`), so the socket needs no token of its own; it needs the session
cookie and an ``Origin`` of this site (a page of another site cannot open it), and it closes
when the session ends. A closed or lost socket changes nothing of the run.

Close codes: 4401 no session (or it ended), 4403 another origin, 4404 unknown run, 4503 no
supervisor.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import queue
import time
from typing import Any, Final
from urllib.parse import urlsplit

from fastapi import APIRouter, WebSocket, WebSocketDisconnect
from starlette.concurrency import run_in_threadpool

from imucalib.errors import CalibrationError
from imucalib.web.auth import COOKIE
from imucalib.web.context import context_of

__all__ = ["router"]

#: How often the session is checked again while the socket is open. [s]
RECHECK_S: Final = 30.0
#: How long one wait for an event lasts before the socket checks it is still wanted. [s]
WAIT_S: Final = 0.5
router = APIRouter()


def same_origin(websocket: WebSocket) -> bool:
    """Return whether the socket's ``Origin`` is this site (its ``Host``)."""
    origin = websocket.headers.get("origin", "")
    host = websocket.headers.get("host", "")
    return bool(origin) and bool(host) and urlsplit(origin).netloc == host


async def _pump(websocket: WebSocket, events: queue.Queue[dict[str, Any]], token: str) -> None:
    web = context_of(websocket)
    checked = time.monotonic()
    while True:
        try:
            event = await run_in_threadpool(events.get, True, WAIT_S)
        except queue.Empty:
            event = None
        if event is not None:
            await websocket.send_text(json.dumps(event, default=str))
            if event.get("type") == "end":
                return
        if time.monotonic() - checked > RECHECK_S:
            checked = time.monotonic()
            if await run_in_threadpool(web.records.web_session, token) is None:
                await websocket.close(code=4401, reason="the session ended")
                return


async def _drain(websocket: WebSocket) -> None:
    """Read (and ignore) what the page sends, until it goes."""
    try:
        while True:
            await websocket.receive_text()
    except (WebSocketDisconnect, RuntimeError):
        return


@router.websocket("/ws/runs/{run_id}")
async def run_events(websocket: WebSocket, run_id: str) -> None:
    """Send the run's events until the run ends or the page goes."""
    web = context_of(websocket)
    await websocket.accept()             # then closed with a code the page can read, if refused
    token = websocket.cookies.get(COOKIE, "")
    login = await run_in_threadpool(web.records.web_session, token) if token else None
    if login is None:
        await websocket.close(code=4401, reason="log in first")
        return
    if not same_origin(websocket):
        await websocket.close(code=4403, reason="another site's page")
        return
    from imucalib.web.run_errors import UnknownRunError

    try:
        supervisor = web.runs()
        events = await run_in_threadpool(supervisor.subscribe, run_id)
    except UnknownRunError:
        await websocket.close(code=4404, reason="no such run")
        return
    except CalibrationError as exc:
        await websocket.close(code=4503, reason=str(exc)[:120])
        return
    pump = asyncio.create_task(_pump(websocket, events, token))
    drain = asyncio.create_task(_drain(websocket))
    try:
        done, _pending = await asyncio.wait({pump, drain}, return_when=asyncio.FIRST_COMPLETED)
    finally:                    # no await here: a cancelled handler still lets go of the queue
        for task in (pump, drain):
            task.cancel()
        supervisor.unsubscribe(run_id, events)
    if pump in done and not pump.cancelled() and pump.exception() is None:
        with contextlib.suppress(RuntimeError):
            await websocket.close()
