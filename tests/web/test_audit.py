"""The audit trail: every action a chained, signed row; tampering is found by verify."""

from __future__ import annotations

import html

import sqlalchemy as sa

RUN = "20261129T120000Z-abcdef"


def _rows(app):
    return [(r.actor, r.action, r.run_ref) for r in reversed(app.state.web.records.audit_log())]


def test_each_action_is_an_audit_row_naming_the_user(web_app, browser, web):
    operator = browser("operator")
    operator.post("/lock/take")
    answer = operator.post(f"/runs/{RUN}/answer",
                           {"prompt_id": 7, "step_index": 1, "confirmed": "true"})
    assert answer.status_code == 303, answer.text
    operator.post(f"/runs/{RUN}/abort", {"step_index": 1})
    operator.post(f"/runs/{RUN}/resume")
    operator.post("/lock/release")
    oli = web.BY_ROLE["operator"]
    tail = _rows(web_app)[-6:]
    assert tail == [(oli, "login", ""), (oli, "lock", ""), (oli, "prompt_answer", RUN),
                    (oli, "abort", RUN), (oli, "resume", RUN), (oli, "unlock", "")]
    assert web_app.state.web.records.verify(recordings=False) == []


def test_the_audit_page_shows_the_rows_and_the_chain_state(web_app, browser, web):
    reviewer = browser("reviewer")
    page = reviewer.get("/audit")
    assert page.status_code == 200
    assert "login" in page.text and web.BY_ROLE["reviewer"] in page.text
    assert "verify (hash chain and" in page.text
    with web_app.state.web.records.engine.begin() as conn:
        conn.execute(sa.text("UPDATE audit_events SET actor = 'Someone Else' WHERE seq = 1"))
    page = reviewer.get("/audit")
    assert "The records do not verify" in html.unescape(page.text)


def test_an_edited_deleted_or_forged_audit_row_is_named_by_verify(web_app, browser):
    browser("operator").post("/lock/take")
    records = web_app.state.web.records
    heads = records.heads()
    assert records.verify(recordings=False) == []
    with records.engine.begin() as conn:
        conn.execute(sa.text("UPDATE audit_events SET action = 'unlock' WHERE seq = 2"))
    assert [(p.table, p.key) for p in records.verify(recordings=False)] == [("audit_events", 2)]
    with records.engine.begin() as conn:
        conn.execute(sa.text("UPDATE audit_events SET action = 'lock' WHERE seq = 2"))
        last = conn.execute(sa.text("SELECT max(seq) FROM audit_events")).scalar()
        conn.execute(sa.text("DELETE FROM audit_events WHERE seq = :s"), {"s": last})
    problems = records.verify(recordings=False, anchors=heads)
    assert ("audit_events", last) in [(p.table, p.key) for p in problems]


def test_a_swapped_password_hash_is_named_by_verify(web_app):
    from imucalib.records.access import hash_password

    records = web_app.state.web.records
    with records.engine.begin() as conn:
        conn.execute(sa.text("UPDATE user_credentials SET password_hash = :h WHERE seq = 2"),
                     {"h": hash_password("the intruder's")})
    assert [(p.table, p.key) for p in records.verify(recordings=False)] == [
        ("user_credentials", 2)]
