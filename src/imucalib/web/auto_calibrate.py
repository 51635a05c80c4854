"""The calibrate step at the end of a run: a watcher in the server (docs/web.md).

While the server runs (its lifespan), :func:`lifespan` looks every :data:`PERIOD_S` seconds at
the supervisor's runs: a run that ``finished`` and has never been calibrated gets its
calibration started (:func:`~imucalib.web.calibrate_job.start_job`: a process of its own, never
the server's), on behalf of the run's operator, and an audit row ``calibrate`` with
``"automatic": true``; and a certificate a review asked for while the last one was being
written, when that job ended before it could take the ask. A run that stopped or failed is
not calibrated by itself (its recording is incomplete); the results page's button calibrates
it on demand.

It looks only at a supervisor the server already made (a page made it), and only at the
station's own :class:`~imucalib.web.supervisor.RunSupervisor`: a test's stand-in is left alone.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator
from typing import Any, Final

from starlette.concurrency import run_in_threadpool

from imucalib.errors import CalibrationError

__all__ = ["PERIOD_S", "calibrate_finished", "lifespan"]

#: How often the watcher looks at the runs. [s]
PERIOD_S: Final = 1.0
_log = logging.getLogger(__name__)


def calibrate_finished(web: Any) -> list[str]:
    """Start the calibration of every finished, never-calibrated run; return their ids.

    Parameters
    ----------
    web : WebContext
        The server's context (its supervisor, runs folder, records).
    """
    from imucalib.web.calibrate_job import ResultsFolder, start_job
    from imucalib.web.supervisor import RunSupervisor

    sup = web.supervisor
    if not isinstance(sup, RunSupervisor):
        return []
    started = []
    for view in sup.runs():
        if view.status != "finished":
            continue
        results = ResultsFolder.of(web.runs_dir, view.run_id)
        if not results.state("certificate").running and results.certificate_asked():
            _certificate_again(web, results)
        if results.state("calibrate").status != "none":
            continue
        try:
            start_job(results, "calibrate", who=view.operator, db=web.records_url,
                      recording=view.recording_path)
        except CalibrationError as exc:
            _log.warning("run %s: not calibrated: %s", view.run_id, exc)
            continue
        web.records.audit(view.operator, "calibrate", station=web.station,
                          run_ref=view.run_id, details={"automatic": True})
        started.append(view.run_id)
    return started


def _certificate_again(web: Any, results: Any) -> None:
    """Write a certificate a review asked for while the last one was being written."""
    from imucalib.web.calibrate_job import start_job

    summary = results.summary() or {}
    try:
        start_job(results, "certificate", who=results.state("certificate").who,
                  db=web.records_url, records_run=summary.get("records_run_id"))
    except CalibrationError as exc:
        _log.warning("%s: the certificate was not written again: %s", results.folder, exc)


async def _watch(web: Any) -> None:
    while True:
        try:
            await run_in_threadpool(calibrate_finished, web)
        except Exception as exc:  # the watcher outlives any one look (a file mid-write, a
            # database busy): it must never end while the server runs
            _log.warning("the calibrate watcher: %s: %s", type(exc).__name__, exc)
        await asyncio.sleep(PERIOD_S)


@contextlib.asynccontextmanager
async def lifespan(app: Any) -> AsyncIterator[None]:
    """Run the watcher while the server runs (a router's lifespan, merged into the app's)."""
    task = asyncio.create_task(_watch(app.state.web))
    try:
        yield
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
