"""A run's results, its review and release, a unit's history, the records page (docs/web.md).

The first test runs a small P1 plan on the twin through the real supervisor; the server's
watcher calibrates it when it finishes (in a process of its own), the page shows the tables and
the files, a reviewer who is not the run's operator releases it and the certificate is written
again with the review. The others use the stand-in supervisor and hand-made results folders.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

RUN = "20261129T120000Z-abcdef"



def wait_for(check, timeout_s: float = 60.0, every_s: float = 0.2):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        got = check()
        if got:
            return got
        time.sleep(every_s)
    raise AssertionError(f"not reached within {timeout_s} s")


def _app(records_url: str, runs: Path, supervisor) -> object:
    from imucalib.web.app import create_app

    return create_app(records_url, runs, supervisor, station="bench-1")


def _job_log(runs: Path, run_id: str) -> str:
    log = runs / run_id / "results" / "job.log"
    return log.read_text(errors="replace")[-3000:] if log.exists() else "(no job.log)"


def test_a_finished_run_is_calibrated_reviewed_released_and_its_history_shown(
        records_url, tmp_path, web, p1_tools):
    from fastapi.testclient import TestClient

    from imucalib.web.supervisor import RunSupervisor

    web.add_users(records_url)
    plans = tmp_path / "plans"
    plans.mkdir()
    plan = p1_tools.small_plan_file(plans)
    runs = tmp_path / "runs"
    sup = RunSupervisor(runs, db=records_url)
    app = _app(records_url, runs, sup)
    try:
        # the run's operator is an admin, so that the records' (U.3) can be seen refusing
        operator = web.BY_ROLE["admin"]
        run_id = sup.start(plan, station="sim", serials=[], operator=operator)
        p = wait_for(lambda: sup.view(run_id).prompt, 30)
        sup.answer(run_id, p.prompt_id, p.step_index, True, operator)
        wait_for(lambda: sup.view(run_id).status == "finished", 60)
        # finished, the watcher not yet at it: the page says so and reloads itself until the
        # calibration shows (a page loaded in that second must not stay there)
        early = web.Browser(app, "reviewer").get(f"/runs/{run_id}/results")
        assert "Not calibrated." in early.text and "Refresh" in early.headers
        lifespan = TestClient(app)                  # its lifespan: the calibrate watcher
        lifespan.__enter__()
        reviewer = web.Browser(app, "reviewer")
        page = wait_for(lambda: (a := reviewer.get(f"/runs/{run_id}/results")).status_code
                        == 200 and "Calibrated" in a.text and a, 120, 0.5)
        text = page.text
        assert "Refresh" not in page.headers
        assert "<table class=\"parameters\">" in text and "µg" in text and "°/h" in text
        assert "PASS" in text or "FAIL" in text
        assert "NOT RELEASED" in text
        results = runs / run_id / "results"
        summary = app.state.web.records.run(
            json.loads((results / "summary.json").read_text())["records_run_id"])
        assert summary.run_id == sup.view(run_id).records_run_id  # attached to the run's
        (rid,) = summary.result_ids
        # the files: listed, and sent
        report = next(n for n in os.listdir(results) if n.endswith(".report.pdf"))
        assert f"/runs/{run_id}/files/{report}" in text
        got = reviewer.get(f"/runs/{run_id}/files/{report}")
        assert got.status_code == 200 and got.content.startswith(b"%PDF")
        assert "attachment" in got.headers["content-disposition"]
        # review: the operator's own review is refused by the records, a rejection needs a
        # comment, an operator or observer may not review at all
        admin = web.Browser(app, "admin")
        refused = admin.post(f"/runs/{run_id}/review", {"result_id": rid,
                                                        "decision": "approve"})
        assert refused.status_code == 409 and "operator of run" in refused.text
        for role in ("operator", "observer"):
            assert web.Browser(app, role).post(f"/runs/{run_id}/review", {
                "result_id": rid, "decision": "approve"}).status_code == 403
        no_csrf = reviewer.post(f"/runs/{run_id}/review",
                                {"result_id": rid, "decision": "approve"}, csrf=False)
        assert no_csrf.status_code == 403
        bare = reviewer.post(f"/runs/{run_id}/review", {"result_id": rid, "decision": "reject"})
        assert bare.status_code == 400 and "needs a comment" in bare.text
        other = reviewer.post(f"/runs/{run_id}/review", {"result_id": rid + 99,
                                                         "decision": "approve"})
        assert other.status_code in (400, 409)
        assert reviewer.post(f"/runs/{run_id}/review", {
            "result_id": rid, "decision": "reject", "comment": "bias too large"}
        ).status_code == 303
        assert reviewer.post(f"/runs/{run_id}/review", {
            "result_id": rid, "decision": "approve", "comment": "checked the residuals"}
        ).status_code == 303
        assert app.state.web.records.release_status(rid).released
        page = reviewer.get(f"/runs/{run_id}/results").text
        assert "RELEASED" in page and "checked the residuals" in page
        actions = [(r.actor, r.action) for r in app.state.web.records.audit_log(run_ref=run_id)]
        reviewer_name = web.BY_ROLE["reviewer"]
        assert (reviewer_name, "approve") in actions and (reviewer_name, "reject") in actions
        assert (operator, "calibrate") in actions                  # the automatic one
        # the certificate is written again with the review
        state = wait_for(lambda: json.loads(
            (results / "certificate.json").read_text()).get("status") in ("done", "failed")
            and json.loads((results / "certificate.json").read_text()), 120, 0.5)
        assert state["status"] == "done", (state, _job_log(runs, run_id))
        html = next((results / "certificate").glob("*.report.html")).read_text()
        assert reviewer_name in html and "checked the residuals" in html
        cert = next((results / "certificate").glob("*.report.pdf")).name
        assert reviewer.get(f"/runs/{run_id}/files/certificate/{cert}").status_code == 200
        # history, drift and the records page
        serial = app.state.web.records.result(rid).serial
        unit = reviewer.get(f"/units/{serial}")
        assert unit.status_code == 200 and f"Unit {serial}" in unit.text
        assert "released" in unit.text and "due on" in unit.text
        name = app.state.web.records.result(rid).parameters[0].name
        svg = reviewer.get(f"/units/{serial}/drift.svg?parameter={name}")
        assert svg.status_code == 200 and svg.headers["content-type"].startswith(
            "image/svg+xml") and b"<svg" in svg.content
        assert reviewer.get("/units/NO-SUCH-UNIT").status_code == 404
        records = web.Browser(app, "observer").get("/records")
        assert records.status_code == 200 and "Every record verifies" in records.text
        assert serial in records.text
        lifespan.__exit__(None, None, None)
    finally:
        sup.close()
        app.state.web.close()


@pytest.fixture
def results(tmp_path):
    """The stand-in run's results folder with a report, a figure and a certificate."""
    folder = tmp_path / "runs" / RUN / "results"
    (folder / "certificate").mkdir(parents=True)
    (folder / "x.IMU.p1.report.pdf").write_bytes(b"%PDF-1.4 report")
    (folder / "x.IMU.p1.residuals.png").write_bytes(b"\x89PNG figure")
    (folder / "certificate" / "x.IMU.p1.report.html").write_text("<p>certificate</p>")
    (folder / "calibrate.json").write_text('{"status": "done", "who": "Oli"}')
    (folder.parent / "run.json").write_text('{"secret": 1}')
    (tmp_path / "secret.txt").write_text("secret")
    os.symlink(tmp_path / "secret.txt", folder / "link.txt")
    return folder


def test_downloads_are_only_files_of_the_run_s_results(browser, results):
    who = browser("observer")
    ok = who.get(f"/runs/{RUN}/files/x.IMU.p1.report.pdf")
    assert ok.status_code == 200 and ok.content == b"%PDF-1.4 report"
    assert ok.headers["content-type"] == "application/pdf"
    assert who.get(f"/runs/{RUN}/files/certificate/x.IMU.p1.report.html").status_code == 200
    for bad in ("../run.json", "..%2Frun.json", "%2e%2e/run.json", "certificate/../../run.json",
                "link.txt", "calibrate.json", "job.log", str(results.parent / "run.json"),
                "/etc/passwd", "certificate", "nothing.pdf", "x.IMU.p1.report.pdf/"):
        answer = who.get(f"/runs/{RUN}/files/{bad}")
        assert answer.status_code == 404, (bad, answer.status_code)
        assert b"secret" not in answer.content
    assert who.get("/runs/20261129T120000Z-000000/files/x.IMU.p1.report.pdf").status_code == 404
    page = who.get(f"/runs/{RUN}/results").text
    assert "x.IMU.p1.report.pdf" in page and "link.txt" not in page
    assert "calibrate.json" not in page
    assert f'<img src="/runs/{RUN}/files/x.IMU.p1.residuals.png"' in page
    assert browser(None).get(f"/runs/{RUN}/files/x.IMU.p1.report.pdf").status_code == 303


def test_the_calibrate_button_is_for_runners_of_an_ended_run(browser, supervisor, web_app,
                                                             tmp_path):
    operator = browser("operator")
    live = operator.post(f"/runs/{RUN}/calibrate")
    assert live.status_code == 409 and "is waiting" in live.text
    assert browser("reviewer").post(f"/runs/{RUN}/calibrate").status_code == 403
    assert operator.post(f"/runs/{RUN}/calibrate", csrf=False).status_code == 403
    assert browser(None).post(f"/runs/{RUN}/calibrate").status_code == 401
    supervisor.add(status="stopped")                  # its recording /tmp/x.h5: not there
    gone = operator.post(f"/runs/{RUN}/calibrate")
    assert gone.status_code == 409 and "is not there" in gone.text
    assert "Calibrate" in operator.get(f"/runs/{RUN}/results").text
    assert 'id="calibrate"' not in browser("observer").get(f"/runs/{RUN}/results").text


def test_a_failed_calibration_is_one_line_and_audited(browser, supervisor, web_app, tmp_path,
                                                      web):
    from dataclasses import replace

    bogus = tmp_path / "bogus.h5"
    bogus.write_text("not a recording")
    supervisor.add(status="stopped")
    supervisor._views[RUN] = replace(supervisor._views[RUN], recording_path=str(bogus))
    operator = browser("operator")
    assert operator.post(f"/runs/{RUN}/calibrate").status_code == 303
    page = wait_for(lambda: "The calibration failed" in (t := operator.get(
        f"/runs/{RUN}/results").text) and t, 60, 0.3)
    line = page.split("The calibration failed: ", 1)[1].split("</p>", 1)[0]
    assert "Traceback" not in line and "\n" not in line.strip() and len(line) <= 400
    actions = [(r.actor, r.action, r.details) for r in
               web_app.state.web.records.audit_log(run_ref=RUN)]
    assert actions == [(web.BY_ROLE["operator"], "calibrate", {"automatic": False})]


def test_one_calibration_at_a_time(browser, supervisor, results):
    """A job that runs (its process names the results folder) refuses a second one."""
    supervisor.add(status="stopped")
    job = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)",
                            str(results)])
    try:
        (results / "calibrate.json").write_text(json.dumps({"status": "running",
                                                            "pid": job.pid, "who": "Oli"}))
        page = browser("observer").get(f"/runs/{RUN}/results")
        assert "Calibrating" in page.text and page.headers["refresh"] == "2"
        busy = browser("operator").post(f"/runs/{RUN}/calibrate")
        assert busy.status_code == 409 and "already running" in busy.text
    finally:
        job.kill()
        job.wait()


def test_a_dead_job_is_shown_failed_and_a_review_needs_a_result_of_the_run(browser, results,
                                                                          supervisor):
    (results / "calibrate.json").write_text('{"status": "running", "pid": 999999999}')
    page = browser("observer").get(f"/runs/{RUN}/results")
    assert "ended without finishing" in page.text
    assert page.headers["refresh"] == "10"           # the run itself is live
    supervisor.add(status="stopped")
    page = browser("observer").get(f"/runs/{RUN}/results")
    assert "ended without finishing" in page.text and "refresh" not in page.headers
    reviewer = browser("reviewer")
    answer = reviewer.post(f"/runs/{RUN}/review", {"result_id": 1, "decision": "approve"})
    assert answer.status_code in (400, 409)
    odd = reviewer.post(f"/runs/{RUN}/review", {"result_id": 1, "decision": "maybe"})
    assert odd.status_code == 400 and "approve or reject" in odd.text


def test_the_history_and_records_pages_need_a_session(browser, web_app):
    from imucalib.web import history

    if not any(getattr(r, "path", "") == "/records" for r in web_app.routes):
        web_app.include_router(history.router)
    assert browser(None).get("/records").status_code == 303
    assert browser(None).get("/units/SN-1").status_code == 303
    page = browser("observer").get("/records")
    assert page.status_code == 200 and "No unit recorded yet" in page.text
    assert browser("observer").get("/units/SN-1").status_code == 404
