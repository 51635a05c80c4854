"""The station's pages and a run's commands (docs/web.md, "Pages").

``GET /``
    The station: who holds the lock (and who asked for it), the current run, recent runs.
``GET /runs/{id}``
    A run: its steps and progress, the prompt dialog, the abort button, live values (the page's
    script subscribes to ``/ws/runs/{id}``, :mod:`imucalib.web.live`).
``POST /runs/{id}/answer``, ``POST /runs/{id}/abort``, ``POST /runs/{id}/resume``
    The commands: each carries the run id (its path) and the step (and prompt) the page showed,
    so a stale page never acts on a newer state (409); each is audited.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Any, TypeVar

from fastapi import APIRouter, Depends, Form, Request
from fastapi.responses import JSONResponse, RedirectResponse
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from imucalib.errors import CalibrationError
from imucalib.records.access import LoginSession
from imucalib.web.audit import record
from imucalib.web.auth import require
from imucalib.web.context import SupervisorUnavailableError, context_of
from imucalib.web.lock import require_lock
from imucalib.web.render import WebError, render, wants_json

__all__ = ["router", "supervised"]

_T = TypeVar("_T")
#: Runs listed on the station page.
RECENT = 20
router = APIRouter()


async def supervised(request: Request, work: Callable[[Any], _T]) -> _T:
    """Run `work(supervisor)` in a thread; turn the supervisor's errors into answers.

    An unknown run is 404; a stale command or one the run's state refuses is 409; another
    refusal 400; no supervisor 503.
    """
    from imucalib.web.run_errors import RunStateError, StaleCommandError, UnknownRunError

    web = context_of(request)
    try:
        supervisor = web.runs()
        return await run_in_threadpool(work, supervisor)
    except SupervisorUnavailableError as exc:
        raise WebError(503, str(exc)) from exc
    except UnknownRunError as exc:
        raise WebError(404, str(exc)) from exc
    except (StaleCommandError, RunStateError) as exc:
        raise WebError(409, str(exc)) from exc
    except CalibrationError as exc:
        raise WebError(400, str(exc)) from exc


@router.get("/")
async def station_page(request: Request,
                       login: Annotated[LoginSession, Depends(require("view"))]) -> Response:
    """Show the station: its lock, the current run, recent runs."""
    web = context_of(request)
    lock = await run_in_threadpool(web.records.station_lock, web.station)
    runs: list[Any] = []
    problem = ""
    try:
        runs = await supervised(request, lambda s: list(s.runs()))
    except WebError as exc:
        problem = exc.message
    runs.sort(key=lambda r: str(r.started_utc), reverse=True)
    live = [r for r in runs if r.status in ("starting", "running", "waiting", "aborting")]
    return render(request, "station.html", lock=lock, current=live[0] if live else None,
                  runs=runs[:RECENT], problem=problem)


@router.get("/runs/{run_id}")
async def run_page(request: Request, run_id: str,
                   login: Annotated[LoginSession, Depends(require("view"))]) -> Response:
    """Show a run (the live values come over the WebSocket)."""
    view = await supervised(request, lambda s: s.view(run_id))
    return render(request, "run.html", run=view, view_json=view.to_dict())


def _done(request: Request, run_id: str, what: str) -> Response:
    if wants_json(request):
        return JSONResponse({"ok": True, "run_id": run_id, "done": what})
    return RedirectResponse(f"/runs/{run_id}", status_code=303)


@router.post("/runs/{run_id}/answer")
async def answer(request: Request, run_id: str,
                 login: Annotated[LoginSession, Depends(require("run"))],
                 prompt_id: Annotated[int, Form()], step_index: Annotated[int, Form()],
                 confirmed: Annotated[bool, Form()], note: Annotated[str, Form()] = ""
                 ) -> Response:
    """Confirm or refuse the prompt the page showed (a refusal is a safe stop)."""
    await require_lock(request, login)
    who = login.user.name
    await supervised(request, lambda s: s.answer(run_id, prompt_id, step_index, confirmed,
                                                 who, note))
    await record(request, login, "prompt_answer", run_ref=run_id,
                 details={"prompt_id": prompt_id, "step_index": step_index,
                          "confirmed": confirmed, "note": note})
    return _done(request, run_id, "answer")


@router.post("/runs/{run_id}/abort")
async def abort(request: Request, run_id: str,
                login: Annotated[LoginSession, Depends(require("abort"))],
                step_index: Annotated[int | None, Form()] = None) -> Response:
    """Stop the run safely (table to rest, chamber safe, centrifuge braked)."""
    who = login.user.name
    await supervised(request, lambda s: s.abort(run_id, step_index, who))
    await record(request, login, "abort", run_ref=run_id, details={"step_index": step_index})
    return _done(request, run_id, "abort")


@router.post("/runs/{run_id}/resume")
async def resume(request: Request, run_id: str,
                 login: Annotated[LoginSession, Depends(require("run"))]) -> Response:
    """Resume a stopped or interrupted run from its recording."""
    await require_lock(request, login)
    who = login.user.name
    await supervised(request, lambda s: s.resume(run_id, who))
    await record(request, login, "resume", run_ref=run_id)
    return _done(request, run_id, "resume")
