"""Logins, sessions, CSRF and roles of the web page (docs/web.md, "Security")."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

import sqlalchemy as sa
from fastapi.testclient import TestClient

from imucalib.records.schema import WebSession


def _audit(app: Any) -> list[tuple[str, str]]:
    return [(r.actor, r.action) for r in reversed(app.state.web.records.audit_log())]


def test_a_wrong_password_is_refused_and_audited(web_app, web):
    client = TestClient(web_app)
    answer = web.login(client, "Oli Operator", "not the password")
    assert answer.status_code == 401
    assert "wrong name or password" in answer.text
    assert "imucalib_session" not in client.cookies
    assert web.login(client, "Nobody", "whatever-long").status_code == 401
    assert client.get("/", follow_redirects=False).status_code == 303
    assert _audit(web_app)[-2:] == [("Oli Operator", "login_failed"),
                                    ("Nobody", "login_failed")]


def test_a_login_sets_a_strict_http_only_cookie_and_logout_ends_it(web_app, web):
    client = TestClient(web_app)
    answer = web.login(client, "Oli Operator")
    assert answer.status_code == 303 and answer.headers["location"] == "/"
    cookie = answer.headers["set-cookie"]
    assert "HttpOnly" in cookie and "SameSite=strict" in cookie and "Secure" not in cookie
    page = client.get("/")
    assert page.status_code == 200 and "Oli Operator (operator)" in page.text
    token = client.cookies["imucalib_session"]
    csrf = page.text.split('name="csrf_token" value="')[1].split('"')[0]
    assert client.post("/logout", data={"csrf_token": csrf},
                       follow_redirects=False).status_code == 303
    client.cookies.set("imucalib_session", token)          # the old cookie, replayed
    assert client.get("/", follow_redirects=False).status_code == 303
    assert _audit(web_app)[-2:] == [("Oli Operator", "login"), ("Oli Operator", "logout")]


def test_the_login_form_needs_its_own_token(web_app, web):
    client = TestClient(web_app)
    answer = client.post("/login", data={"name": "Oli Operator", "password": web.PASSWORD},
                         follow_redirects=False)
    assert answer.status_code == 403 and "login form" in answer.text
    client.get("/login")
    forged = client.post("/login", data={"name": "Oli Operator", "password": web.PASSWORD,
                                         "form_token": "guessed"}, follow_redirects=False)
    assert forged.status_code == 403


def test_an_expired_session_is_refused(web_app, browser):
    operator = browser("operator")
    assert operator.get("/").status_code == 200
    with web_app.state.web.records.engine.begin() as conn:
        conn.execute(sa.update(WebSession).values(expires_utc=datetime(2000, 1, 1, tzinfo=UTC)))
    answer = operator.get("/")
    assert answer.status_code == 303 and answer.headers["location"].startswith("/login")
    assert operator.post("/lock/take").status_code == 401


def test_a_disabled_user_s_session_stops_working(web_app, browser):
    operator = browser("operator")
    web_app.state.web.records.disable_user("Oli Operator", "left", by="Ada Admin")
    assert operator.get("/").status_code == 303


def test_a_post_without_the_csrf_token_is_refused(browser):
    operator = browser("operator")
    missing = operator.post("/lock/take", csrf=False)
    assert missing.status_code == 403 and "CSRF" in missing.text
    wrong = operator.post("/lock/take", {"csrf_token": "x" * 43}, csrf=False)
    assert wrong.status_code == 403
    by_header = operator.client.post("/lock/take", headers={"X-CSRF-Token": operator.csrf},
                                     follow_redirects=False)
    assert by_header.status_code == 303


def test_an_observer_only_reads(browser):
    observer = browser("observer")
    assert observer.get("/").status_code == 200
    assert observer.get("/runs/20261129T120000Z-abcdef").status_code == 200
    for path in ("/lock/take", "/runs/new", "/runs/20261129T120000Z-abcdef/abort"):
        answer = observer.post(path)
        assert answer.status_code == 403, path
        assert "Obi Observer is an observer" in answer.text


def test_a_reviewer_cannot_start_a_run_and_an_operator_can(browser, supervisor):
    from imucalib.plan.io import plan_to_toml
    from imucalib.procedures.p1.plan import generate_p1_plan

    plan = plan_to_toml(generate_p1_plan()).encode()
    files = {"plan_upload": ("p1.toml", plan, "application/toml")}
    reviewer = browser("reviewer")
    refused = reviewer.post("/runs/new", {"station": "sim", "serials": "SN1"}, files=files)
    assert refused.status_code == 403 and "role operator or engineer may run" in refused.text
    operator = browser("operator")
    no_lock = operator.post("/runs/new", {"station": "sim", "serials": "SN1"}, files=files)
    assert no_lock.status_code == 409 and "lock first" in no_lock.text
    assert operator.post("/lock/take").status_code == 303
    started = operator.post("/runs/new", {"station": "sim", "serials": "SN1 SN2"}, files=files)
    assert started.status_code == 303, started.text
    assert started.headers["location"].startswith("/runs/")
    kind, (path, station, serials, who) = supervisor.calls[-1]
    assert (kind, station, serials, who) == ("start", "sim", ["SN1", "SN2"], "Oli Operator")
    assert path.read_bytes() == plan


def test_the_next_parameter_never_leaves_the_site(web_app, web):
    client = TestClient(web_app)
    page = client.get("/login?next=//evil.example/x")
    assert 'name="next" value="/"' in page.text
    answer = client.post("/login", data={"name": "Oli Operator", "password": web.PASSWORD,
                                         "form_token": web.form_token(page.text),
                                         "next": "https://evil.example/"},
                         follow_redirects=False)
    assert answer.headers["location"] == "/"


def test_every_answer_carries_the_security_headers(web_app):
    answer = TestClient(web_app).get("/login")
    assert answer.headers["x-frame-options"] == "DENY"
    assert "frame-ancestors 'none'" in answer.headers["content-security-policy"]
    assert answer.headers["x-content-type-options"] == "nosniff"


def test_a_secure_server_sets_secure_cookies(records_url, tmp_path, web):
    from imucalib.web.app import create_app

    web.add_users(records_url)
    app = create_app(records_url, tmp_path / "runs", object(), secure_cookies=True)
    try:
        client = TestClient(app, base_url="https://testserver")
        assert "Secure" in web.login(client, "Oli Operator").headers["set-cookie"]
    finally:
        app.state.web.close()


def test_too_many_failed_logins_are_refused_with_429(web_app, web, monkeypatch):
    from imucalib.records import access

    monkeypatch.setattr(access, "MAX_FAILED_LOGINS", 3)
    client = TestClient(web_app)
    for _ in range(3):
        assert web.login(client, "Oli Operator", "guess").status_code == 401
    answer = web.login(client, "Oli Operator")
    assert answer.status_code == 429 and "3 failed logins" in answer.text
