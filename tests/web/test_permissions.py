"""Every endpoint × every role (and no session) gives the documented answer (docs/web.md).

"ok" means the role passes the permission check: the answer is neither 401 nor 403 (it may
still be a 409 for a lock another user holds, a 422 for a form without its fields, …).
"""

from __future__ import annotations

import pytest

RUN = "20261129T120000Z-abcdef"
ROLES = ["admin", "operator", "engineer", "reviewer", "observer"]
ALL = set(ROLES)
RUNNERS = {"operator", "engineer"}
#: (method, path, roles allowed); a GET without a session is sent to /login (303), anything
#: else without one is refused with 401.
MATRIX = [
    ("GET", "/", ALL),
    ("GET", "/runs/new", RUNNERS),
    ("POST", "/runs/new", RUNNERS),
    ("GET", f"/runs/{RUN}", ALL),
    ("GET", f"/runs/{RUN}/results", ALL),
    ("POST", f"/runs/{RUN}/calibrate", RUNNERS),
    ("POST", f"/runs/{RUN}/review", {"reviewer", "admin"}),
    ("GET", f"/runs/{RUN}/files/{{name:path}}", ALL),
    ("GET", "/units/{serial}", ALL),
    ("GET", "/units/{serial}/drift.svg", ALL),
    ("GET", "/records", ALL),
    ("GET", "/lab", ALL),
    ("POST", f"/runs/{RUN}/answer", RUNNERS),
    ("POST", f"/runs/{RUN}/abort", RUNNERS),
    ("POST", f"/runs/{RUN}/resume", RUNNERS),
    ("POST", "/lock/take", RUNNERS),
    ("POST", "/lock/request", RUNNERS),
    ("POST", "/lock/release", RUNNERS | {"admin"}),
    ("GET", "/audit", {"reviewer", "admin"}),
    ("GET", "/users", {"admin"}),
    ("POST", "/users/add", {"admin"}),
    ("POST", "/users/password", {"admin"}),
    ("POST", "/users/disable", {"admin"}),
    ("POST", "/users/enable", {"admin"}),
    ("POST", "/logout", ALL),
]


def test_the_matrix_covers_every_route_and_role(web):
    from imucalib.records.users import ROLES as ALL_ROLES
    from imucalib.web.app import route_table

    assert sorted(ROLES) == sorted(ALL_ROLES) == sorted(r for _n, _i, r in web.USERS)
    routes = {(m, p.replace("{run_id}", RUN)) for m, p in route_table()}
    assert routes - {("GET", "/login"), ("POST", "/login"), ("WS", f"/ws/runs/{RUN}")} == {
        (m, p) for m, p, _ in MATRIX}


@pytest.mark.parametrize("role", [None, *ROLES])
def test_each_role_gets_the_documented_answer(browser, role):
    who = browser(role)
    got = {}
    for method, path, _allowed in MATRIX:
        if path == "/logout":
            continue                        # would end the session: checked last, below
        answer = who.get(path) if method == "GET" else who.post(path)
        got[(method, path)] = answer.status_code
    want = {}
    for method, path, allowed in MATRIX:
        if path == "/logout":
            continue
        if role is None:
            want[(method, path)] = 303 if method == "GET" else 401
        elif role not in allowed:
            want[(method, path)] = 403
        else:
            want[(method, path)] = "ok"
    seen = {k: ("ok" if v not in (401, 403) and want[k] == "ok" else v) for k, v in got.items()}
    assert seen == want
    logout = who.post("/logout")
    assert logout.status_code == (401 if role is None else 303)


def test_the_websocket_needs_a_session_and_this_site_s_origin(browser, supervisor):
    from starlette.websockets import WebSocketDisconnect

    nobody = browser(None)
    with nobody.client.websocket_connect(f"/ws/runs/{RUN}",
                                         headers={"origin": "http://testserver"}) as ws, \
            pytest.raises(WebSocketDisconnect) as closed:
        ws.receive_text()
    assert closed.value.code == 4401
    observer = browser("observer")
    with observer.client.websocket_connect(f"/ws/runs/{RUN}",
                                           headers={"origin": "http://evil.example"}) as ws, \
            pytest.raises(WebSocketDisconnect) as closed:
        ws.receive_text()
    assert closed.value.code == 4403
    with observer.client.websocket_connect(f"/ws/runs/{RUN}",
                                           headers={"origin": "http://testserver"}) as ws:
        first = ws.receive_json()
        supervisor._publish(RUN, {"type": "end", "run_id": RUN, "status": "finished"})
        assert ws.receive_json()["type"] == "end"
        assert ws.receive()["type"] == "websocket.close"
    assert first["type"] == "snapshot" and first["view"]["prompt"]["prompt_id"] == 7


@pytest.mark.parametrize("role", [None, *ROLES])
def test_only_an_engineer_may_override_overdue_equipment(browser, role):
    """``override_due`` of ``POST /runs/new``: an engineer's; any other role's is refused."""
    who = browser(role)
    answer = who.post("/runs/new", {"station": "sim", "override_due": "certificate renewal "
                                    "booked"}, headers={"Accept": "application/json"})
    if role is None:
        assert answer.status_code == 401
    elif role == "engineer":
        assert answer.status_code not in (401, 403)   # on to the lock and the form's checks
    else:
        assert answer.status_code == 403
        assert "only" in answer.json()["error"]
