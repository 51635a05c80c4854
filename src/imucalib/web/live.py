"""``/ws/runs/{id}``: a run's live events to its page (docs/web.md, "Live view").

The socket only sends: the supervisor's events (:mod:`imucalib.web.events`), a ``snapshot``
first, as JSON text frames. The snapshot carries the run's ``history`` besides its view: the
window means so far and the temperature trace (``window`` and ``trace`` events of the run's
``events.jsonl``, the latest :data:`HISTORY_WINDOWS` and at most :data:`HISTORY_TRACE` points),
so that a page opened late, or reconnected, draws what it missed. Commands go as POSTs with
the CSRF token (:mod:`imucalib.web.pages`), so the socket needs no token of its own; it needs
the session cookie and an ``Origin`` of this site (a page of another site cannot open it), and
it closes when the session ends. A closed or lost socket changes nothing of the run.

Close codes: 4401 no session (or it ended), 4403 another origin, 4404 unknown run, 4503 no
supervisor.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import queue
import time
from collections import deque
from pathlib import Path
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
#: Window-mean events a snapshot carries at most (the latest).
HISTORY_WINDOWS: Final = 1000
#: Temperature-trace points a snapshot carries at most (the whole trace, thinned evenly).
HISTORY_TRACE: Final = 600
router = APIRouter()


def run_history(events_path: Path) -> dict[str, Any]:
    """Return a run's ``window`` events and its ``trace`` thinned to :data:`HISTORY_TRACE`.

    Read line by line; the memory is bounded by what is kept, not by the file.
    """
    windows: deque[dict[str, Any]] = deque(maxlen=HISTORY_WINDOWS)
    trace: list[dict[str, Any]] = []
    stride, seen = 1, 0
    try:
        with events_path.open("rb") as f:
            for line in f:
                if b'"window"' not in line and b'"trace"' not in line:
                    continue
                try:
                    event = json.loads(line)
                except ValueError:
                    continue          # the last line, half written
                kind = event.get("type") if isinstance(event, dict) else None
                if kind == "window":
                    windows.append(event)
                elif kind == "trace":
                    if seen % stride == 0:
                        trace.append(event)
                    seen += 1
                    if len(trace) >= 2 * HISTORY_TRACE:  # thin evenly: every other point
                        trace, stride = trace[::2], stride * 2
    except OSError:
        pass
    return {"windows": list(windows), "trace": trace, "trace_stride": stride}


def same_origin(websocket: WebSocket) -> bool:
    """Return whether the socket's ``Origin`` is this site (its ``Host``)."""
    origin = websocket.headers.get("origin", "")
    host = websocket.headers.get("host", "")
    return bool(origin) and bool(host) and urlsplit(origin).netloc == host


async def _next(events: queue.Queue[dict[str, Any]]) -> dict[str, Any] | None:
    """Return the next event within :data:`WAIT_S` (None): on the loop, else in a thread."""
    wait = getattr(events, "next_event", None)
    if wait is not None:                       # a SubscriberQueue: no thread per page
        event: dict[str, Any] | None = await wait(WAIT_S)
        return event
    try:                                       # a plain queue (a test's stand-in supervisor)
        return await run_in_threadpool(events.get, True, WAIT_S)
    except queue.Empty:
        return None


async def _pump(websocket: WebSocket, events: queue.Queue[dict[str, Any]], token: str) -> None:
    web = context_of(websocket)
    checked = time.monotonic()
    while True:
        event = await _next(events)
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
    try:
        first = events.get_nowait()          # the snapshot: sent with the run's history
        folder = Path(getattr(supervisor, "runs_dir", web.runs_dir)) / run_id
        first["history"] = await run_in_threadpool(run_history, folder / "events.jsonl")
        await websocket.send_text(json.dumps(first, default=str))
    except queue.Empty:
        pass
    except (WebSocketDisconnect, RuntimeError):
        supervisor.unsubscribe(run_id, events)
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
