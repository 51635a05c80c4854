"""A run's results: the calibration, its report and exports, and its review (docs/web.md).

``GET /runs/{id}/results``
    What the run produced: the calibration's tables (the console's: parameters in display
    units with GUM rounding, fit quality, checks, decision), the files as downloads, the
    records' results with their release status and the review forms; while a job runs the
    page reloads itself every few seconds.
``POST /runs/{id}/calibrate``
    Calibrate the run's recording now (operator, engineer; audited ``calibrate``): the
    pipeline of ``imucalib calibrate`` in a process of its own
    (:mod:`imucalib.web.calibrate_job`). A run that finishes is calibrated by itself
    (:mod:`imucalib.web.auto_calibrate`, this router's lifespan).
``POST /runs/{id}/review``
    Approve or reject one of the run's results with a comment (reviewer, admin; audited
    ``approve`` or ``reject``): the records' review control decides (rule (U.3): not the run's
    operator; a rejection says why); then the certificate is written again with the review.
``GET /runs/{id}/files/{name}``
    A file of the run's results folder (only a file the results page lists: no other path).
"""

from __future__ import annotations

import mimetypes
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Form, Request
from fastapi.responses import FileResponse, JSONResponse, RedirectResponse
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from imucalib.errors import CalibrationError, InvalidInputError
from imucalib.records.access import LoginSession
from imucalib.web.audit import record
from imucalib.web.auth import require
from imucalib.web.auto_calibrate import lifespan
from imucalib.web.calibrate_job import (
    DownloadError,
    JobBusyError,
    ResultsFolder,
    download_path,
    start_job,
)
from imucalib.web.context import context_of
from imucalib.web.pages import supervised
from imucalib.web.render import WebError, render, wants_json
from imucalib.web.run_view import LIVE_STATUSES, RunView

__all__ = ["records_results", "router"]

#: Seconds between the page's reloads while a job runs, and while the run itself runs.
REFRESH_S = 2
REFRESH_LIVE_S = 10
router = APIRouter(lifespan=lifespan)


def _records_run(view: RunView, summary: dict[str, Any] | None) -> int | None:
    if summary and summary.get("records_run_id"):
        return int(summary["records_run_id"])
    return view.records_run_id


def records_results(records: Any, records_run: int | None) -> list[dict[str, Any]]:
    """Return the current results of records run `records_run` with their release status."""
    if records_run is None:
        return []
    try:
        run = records.run(records_run)
    except CalibrationError:
        return []
    out = []
    for rid in run.result_ids:
        entry = records.result(rid)
        if not entry.current:
            continue
        out.append({"entry": entry, "release": records.release_status(rid),
                    "operator": run.operator})
    return out


async def _view(request: Request, run_id: str) -> tuple[RunView, ResultsFolder]:
    view = await supervised(request, lambda s: s.view(run_id))
    try:
        return view, ResultsFolder.of(context_of(request).runs_dir, run_id)
    except DownloadError as exc:
        raise WebError(404, str(exc)) from exc


@router.get("/runs/{run_id}/results")
async def results_page(request: Request, run_id: str,
                       login: Annotated[LoginSession, Depends(require("view"))]) -> Response:
    """Show what the run produced (module docstring)."""
    view, results = await _view(request, run_id)
    web = context_of(request)

    def gather() -> dict[str, Any]:
        summary = results.summary()
        runs = _records_run(view, summary)
        return {"calibration": results.state("calibrate"),
                "certificate": results.state("certificate"), "summary": summary,
                "downloads": results.downloads(), "console": results.console_text(),
                "records_run": runs, "results": records_results(web.records, runs)}

    values = await run_in_threadpool(gather)
    live = view.status in LIVE_STATUSES
    # a finished run not calibrated yet: the watcher starts its calibration within a second
    # (auto_calibrate.PERIOD_S), so the page reloads until it shows that job
    pending = view.status == "finished" and values["calibration"].status == "none"
    working = (values["calibration"].running or values["certificate"].running or pending)
    response = render(request, "results.html", run=view, live=live, **values)
    if working or live:   # no script: the browser reloads the page while something is at work
        response.headers["Refresh"] = str(REFRESH_S if working else REFRESH_LIVE_S)
    return response


def _done(request: Request, run_id: str, what: str, **extra: Any) -> Response:
    if wants_json(request):
        return JSONResponse({"ok": True, "run_id": run_id, "done": what, **extra})
    return RedirectResponse(f"/runs/{run_id}/results", status_code=303)


@router.post("/runs/{run_id}/calibrate")
async def calibrate(request: Request, run_id: str,
                    login: Annotated[LoginSession, Depends(require("run"))],
                    reason: Annotated[str, Form()] = "") -> Response:
    """Calibrate the run's recording now, in a process of its own (audited).

    A run that already has a result is calibrated again only with a `reason`: the new result's
    amendment reason in the records, the audit row's, and the page's.
    """
    view, results = await _view(request, run_id)
    if view.status in LIVE_STATUSES:
        raise WebError(409, f"run {run_id} is {view.status}: it is calibrated once it has "
                            "ended")
    web = context_of(request)
    who = login.user.name
    why = " ".join(reason.split())[:500]
    again = await run_in_threadpool(lambda: results.summary() is not None
                                    or results.state("calibrate").status == "done")
    if again and not why:
        raise WebError(422, f"run {run_id} is already calibrated: calibrating it again needs "
                            "a reason (recorded with the new result and in the audit trail); "
                            "got none")
    try:
        await run_in_threadpool(lambda: start_job(results, "calibrate", who=who,
                                                  db=web.records_url,
                                                  recording=view.recording_path,
                                                  reason=why if again else ""))
    except JobBusyError as exc:
        raise WebError(409, str(exc)) from exc
    except CalibrationError as exc:
        raise WebError(409, str(exc)) from exc
    details: dict[str, Any] = {"automatic": False}
    if again:
        details.update(again=True, reason=why)
    await record(request, login, "calibrate", run_ref=run_id, details=details)
    return _done(request, run_id, "calibrate")


@router.post("/runs/{run_id}/review")
async def review(request: Request, run_id: str,
                 login: Annotated[LoginSession, Depends(require("review"))],
                 result_id: Annotated[int, Form()], decision: Annotated[str, Form()],
                 comment: Annotated[str, Form()] = "") -> Response:
    """Approve or reject one of the run's results (the records' control decides; audited)."""
    view, results = await _view(request, run_id)
    if decision not in ("approve", "reject"):
        raise WebError(400, f"the decision must be approve or reject; got {decision!r}")
    web = context_of(request)
    records_run = _records_run(view, await run_in_threadpool(results.summary))
    who = login.user.name

    def work() -> int:
        entry = web.records.result(result_id)
        if records_run is None or entry.run_id != records_run:
            raise InvalidInputError(f"result {result_id} is not a result of run {run_id}")
        return int(web.records.review(result_id, who, decision == "approve", comment.strip()))

    try:
        review_id = await run_in_threadpool(work)
    except InvalidInputError as exc:
        raise WebError(400, str(exc)) from exc
    except CalibrationError as exc:
        raise WebError(409, str(exc)) from exc
    await record(request, login, decision, run_ref=run_id,
                 details={"result_id": result_id, "review_id": review_id,
                          "comment": comment.strip()})
    try:   # the certificate shows the review: written again (a running job keeps its own)
        await run_in_threadpool(lambda: start_job(results, "certificate", who=who,
                                                  db=web.records_url,
                                                  records_run=records_run))
    except CalibrationError:
        pass
    return _done(request, run_id, decision, review_id=review_id)


@router.get("/runs/{run_id}/files/{name:path}")
async def download(request: Request, run_id: str, name: str,
                   login: Annotated[LoginSession, Depends(require("view"))]) -> Response:
    """Send one file of the run's results (only one the results page lists)."""
    _, results = await _view(request, run_id)
    try:
        path = await run_in_threadpool(download_path, results, name)
    except DownloadError as exc:
        raise WebError(404, str(exc)) from exc
    kind = mimetypes.guess_type(path.name)[0] or "application/octet-stream"
    return FileResponse(path, media_type=kind, filename=path.name)
