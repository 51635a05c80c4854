"""The lab overview, GET /lab (docs/web.md, "Lab overview"): every station of the shared
records database, read-only, for every logged-in role."""

from __future__ import annotations

import re
from datetime import UTC, date, datetime, timedelta

import pytest

ROLES = ["admin", "operator", "engineer", "reviewer", "observer"]


def _lab(records, web) -> None:
    """Two stations: bench-1 run from its page, bench-2 recorded by ``imucalib run``."""
    today = datetime.now(UTC).date()
    records.take_station("bench-1", web.BY_ROLE["operator"])
    records.request_station("bench-1", web.BY_ROLE["engineer"])
    records.audit(web.BY_ROLE["operator"], "start", station="bench-1",
                  run_ref="20261129T120000Z-abcdef",
                  details={"plan": "p1-short", "serials": ["SN-7", "SN-8"]})
    records.audit(web.BY_ROLE["operator"], "abort", station="bench-1",
                  run_ref="20261129T120000Z-abcdef", details={"step_index": 4})
    records.add_station("bench-2", "room 3")
    records.add_equipment("bench-2", "rate table", "T-100", "RT-1", "cert-1",
                          date(2020, 1, 1), today - timedelta(days=1))
    records.add_equipment("bench-2", "chamber", "C-9", "CH-1", "cert-2",
                          date(2020, 1, 1), today + timedelta(days=10))
    records.add_equipment("bench-2", "centrifuge", "F-1", "CF-1", "cert-3",
                          date(2020, 1, 1), today + timedelta(days=400))
    records.record_run(plan_name="p2-lot", operator=web.BY_ROLE["engineer"], station="bench-2",
                       environment={"status": "done"},
                       started_utc=datetime(2026, 11, 28, 9, 0, tzinfo=UTC))


@pytest.mark.parametrize("role", ROLES)
def test_every_role_sees_every_station_s_lock_runs_and_due_equipment(web_app, browser, web,
                                                                     role):
    records = web_app.state.web.records
    _lab(records, web)
    answer = browser(role).get("/lab")
    assert answer.status_code == 200
    html = answer.text
    one = html[html.index('data-station="bench-1"'):html.index('data-station="bench-2"')]
    two = html[html.index('data-station="bench-2"'):]
    assert "held" in one and web.BY_ROLE["operator"] in one
    assert f"{web.BY_ROLE['engineer']} asked for it" in one
    assert "p1-short" in one and "SN-7, SN-8" in one and "abort by" in one
    assert 'href="/runs/20261129T120000Z-abcdef"' in one         # this server's run
    assert "free" in two and "p2-lot" in two and "done" in two
    assert re.search(r"due</span>\s*rate table T-100 RT-1", two)
    assert re.search(r"soon</span>\s*chamber C-9 CH-1", two)
    assert "CF-1" not in two                                      # not due for a year


def test_the_lab_page_needs_a_login_and_changes_nothing(web_app, browser, web):
    records = web_app.state.web.records
    _lab(records, web)
    assert browser(None).get("/lab").status_code == 303
    before = (records.audit_log(limit=10_000), records.station_lock("bench-1"))
    assert browser("observer").get("/lab").status_code == 200
    after = (records.audit_log(limit=10_000), records.station_lock("bench-1"))
    # the observer's login is the only new row
    assert after[1] == before[1] and [r.action for r in after[0][:-len(before[0]) or None]] == [
        "login"]


def test_a_station_whose_page_was_used_is_listed_before_its_first_run(browser):
    html = browser("observer").get("/lab").text
    # the observer's own login names this station in the audit trail
    assert 'data-station="bench-1"' in html and "No runs." in html and "free" in html


def test_the_overview_reads_one_snapshot_and_a_read_that_writes_is_refused(web_app, web):
    """``Records.read_snapshot``: the lab overview's public read; a write in it is refused."""
    from sqlalchemy import func, select

    from imucalib.errors import RecordsError
    from imucalib.records.schema import Station
    from imucalib.web.lab_state import lab_overview

    records = web_app.state.web.records
    _lab(records, web)
    assert records.read_snapshot(lambda s: s.scalar(select(func.count()).select_from(Station))
                                 ) == 1
    with pytest.raises(RecordsError, match="tried to change them; nothing was written"):
        records.read_snapshot(lambda s: s.add(Station(name="bench-9", location="")))
    assert [s.name for s in lab_overview(records)] == ["bench-1", "bench-2"]   # bench-9 not
