"""Logins, sessions, CSRF and roles of the web page (docs/web.md, "Security").

Contents
--------
:data:`PERMISSIONS`
    Which roles may do what (the table of docs/web.md).
:func:`can`, :func:`require`
    Whether a login may act; the route dependency that refuses (401 without a session, 403 for
    a role that may not or a POST without its CSRF token).
:data:`router`
    ``GET /login``, ``POST /login``, ``POST /logout``.

Sessions: the cookie holds a random token (256 bits) whose SHA-256 the records database keeps
with its user, its expiry and its CSRF token (:mod:`imucalib.records.access`); the cookie is
``HttpOnly``, ``SameSite=Strict`` and, over TLS, ``Secure``. Every state-changing request is a
POST carrying the session's CSRF token (form field ``csrf_token`` or header ``X-CSRF-Token``);
the login form carries a token of its own (a cookie and a field that must match).
"""

from __future__ import annotations

import secrets
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Annotated, Final

from fastapi import APIRouter, Form, Request
from fastapi.responses import RedirectResponse
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from imucalib.records.users import ROLES
from imucalib.web.context import context_of
from imucalib.web.render import WebError, render

if TYPE_CHECKING:
    from imucalib.records.access import LoginSession

__all__ = ["COOKIE", "PERMISSIONS", "article", "can", "current_login", "require", "router"]

#: The session cookie's name.
COOKIE: Final = "imucalib_session"
#: The login form's CSRF cookie.
LOGIN_COOKIE: Final = "imucalib_login"
#: What each role may do (docs/web.md, "Roles").
PERMISSIONS: Final[dict[str, frozenset[str]]] = {
    "view": frozenset(ROLES),
    "run": frozenset({"operator", "engineer"}),         # start, answer a prompt, resume
    "abort": frozenset({"operator", "engineer"}),
    "lock": frozenset({"operator", "engineer"}),        # take, release, request the station
    "force_unlock": frozenset({"admin"}),
    "review": frozenset({"reviewer", "admin"}),
    "audit": frozenset({"reviewer", "admin"}),
    "users": frozenset({"admin"}),
    "override_due": frozenset({"engineer"}),            # start on overdue equipment
}
_WHO: Final = {"run": "run the station", "abort": "abort a run", "lock": "hold the station",
               "force_unlock": "release another user's lock", "review": "review results",
               "audit": "read the audit trail", "users": "manage users", "view": "view",
               "override_due": "start a run on equipment overdue for calibration"}


def can(login: LoginSession | None, action: str) -> bool:
    """Return whether `login`'s role may do `action` (a key of :data:`PERMISSIONS`)."""
    return login is not None and login.user.role in PERMISSIONS[action]


async def current_login(request: Request) -> LoginSession | None:
    """Return the request's live session (None: no cookie, unknown, expired, user disabled)."""
    token = request.cookies.get(COOKIE, "")
    if not token:
        return None
    web = context_of(request)
    login = await run_in_threadpool(web.records.web_session, token)
    request.state.login = login
    return login


async def _csrf_of(request: Request) -> str:
    header = request.headers.get("x-csrf-token")
    if header:
        return header
    if request.headers.get("content-type", "").startswith(
            ("application/x-www-form-urlencoded", "multipart/form-data")):
        value = (await request.form()).get("csrf_token")
        return value if isinstance(value, str) else ""
    return ""


def require(action: str) -> Callable[[Request], Awaitable[LoginSession]]:
    """Return the dependency that lets only a login whose role may do `action` through.

    A GET without a session is sent to the login page (303); any other request without one
    is refused with 401. A POST must carry the session's CSRF token (403 without it). A role
    that may not is refused with 403.
    """
    if action not in PERMISSIONS:
        raise ValueError(f"action must be one of {', '.join(PERMISSIONS)}; got {action!r}")

    async def dependency(request: Request) -> LoginSession:
        login = await current_login(request)
        if login is None:
            raise WebError(401, "log in first: this page needs a session (none, or it expired)")
        if request.method not in ("GET", "HEAD"):
            sent = await _csrf_of(request)
            if not sent or not secrets.compare_digest(sent, login.csrf_token):
                raise WebError(403, "refused: the request did not carry this session's CSRF "
                                    "token (reload the page and try again)")
        if login.user.role not in PERMISSIONS[action]:
            allowed = " or ".join(r for r in ROLES if r in PERMISSIONS[action])
            raise WebError(403, f"{login.user.name} is {article(login.user.role)}: only a "
                                f"user with role {allowed} may {_WHO[action]}")
        return login
    return dependency


def article(role: str) -> str:
    """Return "an admin", "a reviewer": the role with its article."""
    return f"an {role}" if role[:1] in "aeiou" else f"a {role}"


def _safe_next(target: str) -> str:
    """Return `target` if it is a path of this site (no open redirect), else ``/``."""
    if target.startswith("/") and not target.startswith("//") and "\\" not in target:
        return target
    return "/"


router = APIRouter()


@router.get("/login")
async def login_page(request: Request, next: str = "/") -> Response:
    """Show the login form (with its own CSRF token)."""
    token = secrets.token_urlsafe(24)
    response = render(request, "login.html", form_token=token, next=_safe_next(next),
                      error="")
    _set_cookie(request, response, LOGIN_COOKIE, token, max_age=3600)
    return response


@router.post("/login")
async def login(request: Request, name: Annotated[str, Form()],
                password: Annotated[str, Form()], form_token: Annotated[str, Form()] = "",
                next: Annotated[str, Form()] = "/") -> Response:
    """Check the name and password; start a session (both outcomes are audited)."""
    cookie = request.cookies.get(LOGIN_COOKIE, "")
    if not form_token or not cookie or not secrets.compare_digest(form_token, cookie):
        raise WebError(403, "refused: the login form's token is missing or does not match "
                            "its cookie (reload the login page)")
    web = context_of(request)
    source = request.client.host if request.client else ""
    from imucalib.records.access import LoginThrottledError

    try:
        result = await run_in_threadpool(lambda: web.records.login(
            name, password, station=web.station, hours=web.session_hours, source=source))
    except LoginThrottledError as exc:
        raise WebError(429, str(exc)) from exc
    if result is None:
        token = secrets.token_urlsafe(24)
        response = render(request, "login.html", status=401, form_token=token,
                          next=_safe_next(next),
                          error="wrong name or password (or the user is disabled or has no "
                                "password: imucalib users set-password)")
        _set_cookie(request, response, LOGIN_COOKIE, token, max_age=3600)
        return response
    _user, session_token, _csrf, _expires = result
    response = RedirectResponse(_safe_next(next), status_code=303)
    _set_cookie(request, response, COOKIE, session_token,
                max_age=int(web.session_hours * 3600))
    response.delete_cookie(LOGIN_COOKIE, path="/")
    return response


@router.post("/logout")
async def logout(request: Request) -> Response:
    """End the session (audited) and go to the login page."""
    await require("view")(request)
    web = context_of(request)
    token = request.cookies.get(COOKIE, "")
    await run_in_threadpool(lambda: web.records.logout(token, station=web.station))
    response = RedirectResponse("/login", status_code=303)
    response.delete_cookie(COOKIE, path="/")
    return response


def _set_cookie(request: Request, response: Response, name: str, value: str,
                max_age: int) -> None:
    web = context_of(request)
    response.set_cookie(name, value, max_age=max_age, path="/", httponly=True,
                        samesite="strict", secure=web.secure_cookies)
