"""One operator holds the station at a time; everyone sees who, and may ask (docs/web.md)."""

from __future__ import annotations

import html

RUN = "20261129T120000Z-abcdef"


def _text(answer):
    return html.unescape(answer.text)


def test_one_holder_at_a_time_visible_to_all(web_app, browser):
    operator, engineer, observer = browser("operator"), browser("engineer"), browser("observer")
    assert "Free." in observer.get("/").text
    assert operator.post("/lock/take").status_code == 303
    assert "Held by <strong>Oli Operator</strong>" in observer.get("/").text
    taken = engineer.post("/lock/take")
    assert taken.status_code == 409 and "held by Oli Operator" in _text(taken)
    assert engineer.post("/lock/request").status_code == 303
    assert "Eve Engineer asked for the station" in _text(operator.get("/"))
    refused = engineer.post("/lock/release")
    assert refused.status_code == 409 and "only its holder" in _text(refused)
    assert operator.post("/lock/release").status_code == 303
    assert engineer.post("/lock/take").status_code == 303
    lock = web_app.state.web.records.station_lock("bench-1")
    assert (lock.holder, lock.requested_by) == ("Eve Engineer", "")


def test_an_admin_releases_a_lock_whose_holder_left(web_app, browser):
    browser("operator").post("/lock/take")
    admin = browser("admin")
    assert "Release Oli Operator" in _text(admin.get("/"))
    assert admin.post("/lock/release").status_code == 303
    assert web_app.state.web.records.station_lock("bench-1").holder == ""
    rows = web_app.state.web.records.audit_log(limit=1)
    assert (rows[0].actor, rows[0].action, rows[0].details) == (
        "Ada Admin", "unlock", {"holder": "Oli Operator"})


def test_starting_answering_and_resuming_need_the_lock_aborting_does_not(browser, supervisor):
    holder, other = browser("operator"), browser("engineer")
    holder.post("/lock/take")
    answer = other.post(f"/runs/{RUN}/answer", {"prompt_id": 7, "step_index": 1,
                                                "confirmed": "true"})
    assert answer.status_code == 409 and "held by Oli Operator" in _text(answer)
    assert other.post(f"/runs/{RUN}/resume").status_code == 409
    assert other.post(f"/runs/{RUN}/abort", {"step_index": 1}).status_code == 303
    assert supervisor.calls[-1] == ("abort", (RUN, 1, "Eve Engineer"))
