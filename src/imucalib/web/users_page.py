"""``/users``: the admin's page of users, roles and passwords (docs/web.md).

The rules are the records' (docs/records.md, "Users and roles"; :mod:`imucalib.records.users`,
:mod:`imucalib.records.access`): users are never removed, only disabled; every change is a
chained row naming the admin who made it.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Form, Request
from fastapi.responses import RedirectResponse
from starlette.concurrency import run_in_threadpool
from starlette.responses import Response

from imucalib.errors import CalibrationError
from imucalib.records.access import LoginSession
from imucalib.records.users import ROLES
from imucalib.web.auth import require
from imucalib.web.context import context_of
from imucalib.web.render import WebError, render

__all__ = ["router"]

router = APIRouter()


@router.get("/users")
async def users_page(request: Request,
                     login: Annotated[LoginSession, Depends(require("users"))]) -> Response:
    """List the users, their roles and state."""
    web = context_of(request)
    users = await run_in_threadpool(web.records.users)
    return render(request, "users.html", users=users, roles=ROLES)


async def _act(request: Request, work: object) -> Response:
    try:
        await run_in_threadpool(work)  # type: ignore[arg-type]
    except CalibrationError as exc:
        raise WebError(409 if "already" in str(exc) else 422, str(exc)) from exc
    return RedirectResponse("/users", status_code=303)


@router.post("/users/add")
async def add_user(request: Request,
                   login: Annotated[LoginSession, Depends(require("users"))],
                   name: Annotated[str, Form()], role: Annotated[str, Form()],
                   initials: Annotated[str, Form()] = "",
                   password: Annotated[str, Form()] = "") -> Response:
    """Add a user (and set their first password when one is given)."""
    web = context_of(request)
    admin = login.user.name

    def work() -> None:
        web.records.add_user(name, initials, role, by=admin)
        if password:
            web.records.set_password(name, password, by=admin)
    return await _act(request, work)


@router.post("/users/password")
async def set_password(request: Request,
                       login: Annotated[LoginSession, Depends(require("users"))],
                       name: Annotated[str, Form()],
                       password: Annotated[str, Form()]) -> Response:
    """Set a user's password."""
    web = context_of(request)
    return await _act(request, lambda: web.records.set_password(name, password,
                                                                by=login.user.name))


@router.post("/users/disable")
async def disable_user(request: Request,
                       login: Annotated[LoginSession, Depends(require("users"))],
                       name: Annotated[str, Form()], reason: Annotated[str, Form()]
                       ) -> Response:
    """Disable a user (their sessions stop working)."""
    web = context_of(request)
    return await _act(request, lambda: web.records.disable_user(name, reason,
                                                                by=login.user.name))


@router.post("/users/enable")
async def enable_user(request: Request,
                      login: Annotated[LoginSession, Depends(require("users"))],
                      name: Annotated[str, Form()], reason: Annotated[str, Form()]
                      ) -> Response:
    """Enable a disabled user again."""
    web = context_of(request)
    return await _act(request, lambda: web.records.enable_user(name, reason,
                                                               by=login.user.name))
