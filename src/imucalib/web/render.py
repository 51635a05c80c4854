"""Rendering a page, and the answers of a refused request (docs/web.md).

:class:`WebError` is what a route raises to refuse (a status and one line saying what was
expected and what was found); :func:`render` fills a template with what every page shows (who
is logged in, their CSRF token, what their role may do).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from starlette.requests import Request
    from starlette.responses import Response

    from imucalib.records.access import LoginSession

__all__ = ["WebError", "render", "wants_json"]


class WebError(Exception):
    """A refused request: an HTTP status and one line of why."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


def wants_json(request: Request) -> bool:
    """Return whether the request is the page's script (it asks for JSON), not a browser load."""
    return "application/json" in request.headers.get("accept", "")


def render(request: Request, template: str, *, status: int = 200, **values: Any) -> Response:
    """Return `template` rendered with `values` and the page's common values."""
    from imucalib.web.auth import can
    from imucalib.web.context import context_of

    web = context_of(request)
    login: LoginSession | None = getattr(request.state, "login", None)
    common = {"login": login, "user": login.user if login else None,
              "csrf": login.csrf_token if login else "", "station": web.station,
              "can": (lambda action: can(login, action))}
    return web.templates.TemplateResponse(request, template, {**common, **values},
                                          status_code=status)
