"""No GET changes anything: every state change is a POST with the CSRF token (docs/web.md)."""

from __future__ import annotations

import re

RUN = "20261129T120000Z-abcdef"
#: Words of a path that changes something.
VERBS = re.compile(r"take|release|request|answer|abort|resume|add|disable|enable|password|"
                   r"logout|start|review|approve|reject|calibrate")


def test_no_get_route_changes_state(web_app, browser, supervisor):
    from imucalib.web.app import route_table

    table = route_table()
    for method, path in table:
        if VERBS.search(path):
            assert method == "POST", (method, path)
    records = web_app.state.web.records
    for role in ("admin", "operator", "reviewer"):
        who = browser(role)
        before = (records.audit_log(limit=10_000), records.station_lock("bench-1"),
                  len(supervisor.calls), records.users())
        for method, path in table:
            if method == "GET":
                answer = who.get(path.replace("{run_id}", RUN).replace("{serial}", "SN-1")
                                 .replace("{name:path}", "none.pdf"))
                expected = (200, 303, 403, 404) if "{" in path else (200, 303, 403)
                assert answer.status_code in expected, (role, path, answer.status_code)
        after = (records.audit_log(limit=10_000), records.station_lock("bench-1"),
                 len(supervisor.calls), records.users())
        assert after == before, role


def test_a_post_route_refuses_get(browser):
    answer = browser("operator").get("/lock/take")
    assert answer.status_code == 405 and "GET is not allowed on /lock/take" in answer.text
