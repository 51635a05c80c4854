"""Calibrating a run again from the results page needs a reason (docs/web.md).

A stopped run's recording (a small P1 plan on the twin) is calibrated from the page; calibrating
it again without a reason is refused in one line, and with one it is done: the reason is the
new result's amendment reason in the records (it replaces the first), the ``calibrate`` audit
row's, and the page shows it. The stand-in supervisor holds the run; the jobs are real.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

RUN = "20261129T120000Z-abcdef"
REASON = "lever arm of the fixture corrected in the station file"


def _wait_done(who: Any, timeout_s: float = 120.0) -> str:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        page = who.get(f"/runs/{RUN}/results").text
        if "The calibration failed" in page:
            raise AssertionError(page.split("The calibration failed", 1)[1][:400])
        if 'id="calibration-state" class="ok"' in page:
            return page
        time.sleep(0.3)
    raise AssertionError(f"not calibrated within {timeout_s} s")


def test_calibrating_a_calibrated_run_again_needs_a_reason_that_is_recorded_and_shown(
        browser, supervisor, web_app, tmp_path, p1_tools, web):
    from imucalib.plan import load_plan

    recording = p1_tools.run_twin(load_plan(p1_tools.small_plan_file(tmp_path)),
                                  tmp_path / "run.h5")
    supervisor.add(status="stopped")
    supervisor._views[RUN] = replace(supervisor._views[RUN], recording_path=str(recording))
    engineer = browser("engineer")
    first = engineer.get(f"/runs/{RUN}/results").text
    assert 'id="calibrate"' in first and 'id="calibrate-reason"' not in first
    assert engineer.post(f"/runs/{RUN}/calibrate").status_code == 303
    page = _wait_done(engineer)
    assert 'id="calibrate-reason"' in page and 'id="calibration-reason"' not in page

    refused = engineer.post(f"/runs/{RUN}/calibrate", {"reason": "  "},
                            headers={"Accept": "application/json"})
    assert refused.status_code == 422
    assert refused.json() == {"ok": False, "error": f"run {RUN} is already calibrated: "
                              "calibrating it again needs a reason (recorded with the new "
                              "result and in the audit trail); got none"}
    assert engineer.post(f"/runs/{RUN}/calibrate", {"reason": f" {REASON}\n"}
                         ).status_code == 303
    page = _wait_done(engineer)
    assert "Calibrated again" in page
    assert f"Calibrated again by Eve Engineer, because: {REASON}" in page

    records = web_app.state.web.records
    calibrations = [(r.actor, r.details) for r in records.audit_log(run_ref=RUN)
                    if r.action == "calibrate"]
    assert sorted(calibrations, key=str) == sorted([
        ("Eve Engineer", {"automatic": False}),
        ("Eve Engineer", {"automatic": False, "again": True, "reason": REASON})], key=str)
    (unit,) = records.units()
    old, new = records.history(unit)
    assert new.replaces == old.result_id and not old.current and new.current
    assert new.amendment_reason == f"re-analysis by Eve Engineer: {REASON}"
