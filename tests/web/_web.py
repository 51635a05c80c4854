"""Helpers of the web tests: the users (one per role), logging in, a logged-in client.

Import it by its path (the fixture ``web`` of conftest.py hands it over).
"""

from __future__ import annotations

import re
from typing import Any

PASSWORD = "correct horse battery"
#: One user per role: (name, initials, role).
USERS = (("Ada Admin", "AA", "admin"), ("Oli Operator", "OO", "operator"),
         ("Eve Engineer", "EE", "engineer"), ("Rae Reviewer", "RR", "reviewer"),
         ("Obi Observer", "OB", "observer"))
BY_ROLE = {role: name for name, _i, role in USERS}


def add_users(url: str) -> None:
    """Add one user per role, each with :data:`PASSWORD`."""
    from imucalib.records import open_records

    with open_records(url) as records:
        for name, initials, role in USERS:
            records.add_user(name, initials, role, by=None if role == "admin" else "Ada Admin")
            records.set_password(name, PASSWORD, by="Ada Admin")


def form_token(html: str) -> str:
    found = re.search(r'name="form_token" value="([^"]+)"', html)
    assert found, html[:500]
    return found.group(1)


def csrf_of(html: str) -> str:
    found = re.search(r'name="csrf_token" value="([^"]+)"', html)
    assert found, html[:500]
    return found.group(1)


def login(client: Any, name: str, password: str = PASSWORD) -> Any:
    """Log `client` in through the login form; return the answer."""
    page = client.get("/login")
    return client.post("/login", data={"name": name, "password": password,
                                       "form_token": form_token(page.text)},
                       follow_redirects=False)


class Browser:
    """A TestClient logged in as one user, with the session's CSRF token."""

    def __init__(self, app: Any, role: str | None) -> None:
        from fastapi.testclient import TestClient

        self.client = TestClient(app)
        self.csrf = ""
        self.role = role
        if role is not None:
            answer = login(self.client, BY_ROLE[role])
            assert answer.status_code == 303, answer.text
            self.csrf = csrf_of(self.client.get("/").text)

    def get(self, path: str, **kw: Any) -> Any:
        return self.client.get(path, follow_redirects=False, **kw)

    def post(self, path: str, data: dict[str, Any] | None = None, *, csrf: bool = True,
             **kw: Any) -> Any:
        body = dict(data or {})
        if csrf and self.csrf:
            body["csrf_token"] = self.csrf
        return self.client.post(path, data=body, follow_redirects=False, **kw)
