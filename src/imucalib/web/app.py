"""The station's web server: :func:`create_app` (docs/web.md).

One server per station, on the records database (users, sessions, the audit trail, the
station lock) and the run supervisor (:mod:`imucalib.web.supervisor`: the runner of
``imucalib run`` in a worker process). The routes are in :mod:`imucalib.web.auth`,
:mod:`imucalib.web.lock`, :mod:`imucalib.web.pages`, :mod:`imucalib.web.run_start`,
:mod:`imucalib.web.live`, :mod:`imucalib.web.audit` and :mod:`imucalib.web.users_page`.

Every answer carries headers that keep the page out of frames and scripts of other sites; a
refused request gets one line (an HTML page, or JSON for the page's script), never a traceback.
"""

from __future__ import annotations

import logging
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any, Final
from urllib.parse import quote

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles
from fastapi.templating import Jinja2Templates
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.responses import Response

from imucalib.web.render import WebError, render, wants_json

__all__ = ["SECURITY_HEADERS", "create_app", "route_table", "routers"]

HERE: Final = Path(__file__).resolve().parent
#: Headers of every answer.
SECURITY_HEADERS: Final = {
    "Content-Security-Policy": "default-src 'self'; img-src 'self' data:; object-src 'none'; "
                               "base-uri 'none'; form-action 'self'; frame-ancestors 'none'",
    "X-Frame-Options": "DENY",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "same-origin",
    "Cache-Control": "no-store",
}
_log = logging.getLogger(__name__)


def create_app(records_url: str | None, runs_dir: Path, supervisor: Any = None, *,
               plans_dir: Path | None = None, stations_dir: Path | None = None,
               station: str = "station", secure_cookies: bool = False,
               session_hours: float | None = None,
               abort_escalate_s: float | None = None) -> FastAPI:
    """Return the web application of one station.

    Parameters
    ----------
    records_url : str or None
        The records database (None: ``imucalib records``' default, docs/records.md).
    runs_dir : Path
        The supervisor's runs folder.
    supervisor : RunSupervisor, optional
        Made on first use from `runs_dir` when None (tests pass a stand-in).
    plans_dir, stations_dir : Path, optional
        The plan files and station files offered on /runs/new.
    station : str
        This station's name (its lock, its audit rows).
    secure_cookies : bool
        Served over TLS: the session cookie is ``Secure``.
    session_hours : float, optional
        How long a login lasts (default :data:`imucalib.records.access.SESSION_HOURS`). [h]
    abort_escalate_s : float, optional
        How long an abort may take before the supervisor ends the worker (default
        :data:`imucalib.web.abort_watch.ABORT_ESCALATE_S`; docs/web-runs.md). [s]

    Raises
    ------
    RecordsError
        The database cannot be opened.
    """
    from imucalib.records import open_records
    from imucalib.records.access import SESSION_HOURS
    from imucalib.web.context import WebContext

    records = open_records(records_url)
    web = WebContext(records=records, runs_dir=Path(runs_dir), plans_dir=plans_dir,
                     stations_dir=stations_dir, station=station,
                     secure_cookies=secure_cookies,
                     session_hours=SESSION_HOURS if session_hours is None else session_hours,
                     templates=Jinja2Templates(directory=str(HERE / "templates")),
                     supervisor=supervisor, records_url=records_url,
                     abort_escalate_s=abort_escalate_s)

    @asynccontextmanager
    async def lifespan(_app: FastAPI) -> AsyncIterator[None]:
        yield
        web.close()

    app = FastAPI(title="imucalib station", docs_url=None, redoc_url=None, openapi_url=None,
                  lifespan=lifespan)
    app.state.web = web
    for router in routers():
        app.include_router(router)
    app.mount("/static", StaticFiles(directory=str(HERE / "static")), name="static")
    _handlers(app)

    @app.middleware("http")
    async def headers(request: Request,
                      call_next: Callable[[Request], Awaitable[Response]]) -> Response:
        response = await call_next(request)
        for name, value in SECURITY_HEADERS.items():
            response.headers.setdefault(name, value)
        if secure_cookies:
            response.headers.setdefault("Strict-Transport-Security", "max-age=31536000")
        return response
    return app


def routers() -> list[Any]:
    """Return the routers of the server, in the order they are matched (/runs/new first)."""
    from imucalib.web import (
        audit,
        auth,
        history,
        live,
        lock,
        overview,
        pages,
        results,
        run_start,
        users_page,
    )

    return [m.router for m in (auth, lock, run_start, pages, results, history, live, overview,
                               audit, users_page)]


def route_table() -> list[tuple[str, str]]:
    """Return every (method, path) the server answers (``WS`` for a WebSocket), static aside."""
    out = []
    for router in routers():
        for route in router.routes:
            methods = getattr(route, "methods", None) or {"WS"}
            out += [(m, route.path) for m in sorted(methods)]
    return out


def _refusal(request: Request, status: int, message: str) -> Response:
    if status == 401 and request.method in ("GET", "HEAD") and not wants_json(request):
        target = request.url.path + (f"?{request.url.query}" if request.url.query else "")
        return RedirectResponse(f"/login?next={quote(target, safe='/')}", status_code=303)
    if wants_json(request) or request.url.path.startswith("/ws/"):
        return JSONResponse({"ok": False, "error": message}, status_code=status)
    return render(request, "error.html", status=status, status_code=status, message=message)


def _handlers(app: FastAPI) -> None:
    @app.exception_handler(WebError)
    async def web_error(request: Request, exc: WebError) -> Response:
        return _refusal(request, exc.status, exc.message)

    @app.exception_handler(RequestValidationError)
    async def invalid(request: Request, exc: RequestValidationError) -> Response:
        first = exc.errors()[0] if exc.errors() else {}
        where = ".".join(str(p) for p in first.get("loc", ()) if p not in ("body", "query"))
        return _refusal(request, 422, f"the request's {where or 'form'}: "
                                      f"{first.get('msg', 'is not valid')}")

    @app.exception_handler(StarletteHTTPException)
    async def http_error(request: Request, exc: StarletteHTTPException) -> Response:
        words = {404: f"no page {request.url.path} here",
                 405: f"{request.method} is not allowed on {request.url.path}"}
        return _refusal(request, exc.status_code, words.get(exc.status_code, str(exc.detail)))

    @app.exception_handler(Exception)
    async def crash(request: Request, exc: Exception) -> Response:
        _log.error("%s %s failed: %s: %s", request.method, request.url.path,
                   type(exc).__name__, exc)
        return _refusal(request, 500, f"the server failed ({type(exc).__name__}: "
                                      f"{str(exc)[:200]}); the run, if any, is not affected")
