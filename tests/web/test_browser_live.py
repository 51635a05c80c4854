"""The live view in a real browser (Debian's chromium driven by Playwright; docs/web.md).

An operator starts a short P1 plan on the twin from the page, through the real run supervisor
(a worker process running the runner of ``imucalib run``, paced so that the run lasts a few
seconds); the page shows the steps, live values that change, window means as they arrive; a
dropped socket reconnects and the run goes on; abort stops the run safely, the resume button
appears, and the resumed run finishes; the lab overview shows the station held and the run.
Screenshots go to ``out/web/live_run/``. Without chromium the test fails, it is not skipped.
"""

from __future__ import annotations

import os
import re
import signal
from pathlib import Path
from typing import Any

import pytest

from imucalib.web.supervisor import RunSupervisor

#: Wall seconds per station second: the small plan's ~330 s of station time in ~10 s.
PACE = 0.03


class PacedSupervisor(RunSupervisor):
    """The real supervisor, with the twin paced (the page starts runs without a pace)."""

    def start(self, plan_path: Path, **kw: Any) -> str:
        kw["pace"] = PACE
        return super().start(plan_path, **kw)


@pytest.fixture
def live_app(records_url: str, tmp_path: Path, web, p1_tools):
    from imucalib.web.app import create_app

    web.add_users(records_url)
    plans = tmp_path / "plans"
    plans.mkdir()
    p1_tools.small_plan_file(plans)
    sup = PacedSupervisor(tmp_path / "runs", record=False)
    app = create_app(records_url, tmp_path / "runs", sup, plans_dir=plans, station="bench-1")
    yield app
    app.state.web.close()
    sup.close()
    for v in sup.runs():                    # never leave a worker behind
        pid = tmp_path / "runs" / v.run_id / "worker.pid"
        if v.status in ("starting", "running", "waiting", "aborting") and pid.exists():
            try:
                os.kill(int(pid.read_text()), signal.SIGKILL)
            except ProcessLookupError:
                pass


def test_the_live_view_updates_and_abort_then_resume_finish_the_run(live_app, web, live):
    from playwright.sync_api import expect, sync_playwright

    executable = live.chromium_path()
    shots = live.screenshot_dir("live_run")
    with live.live_server(live_app) as base, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=executable, args=live.CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.on("dialog", lambda d: d.accept())      # "Stop the run safely now?"
            sockets: list[Any] = []

            def through(ws: Any) -> None:                 # the page's sockets, passed on
                ws.connect_to_server()
                sockets.append(ws)

            page.route_web_socket(re.compile(r".*/ws/runs/.*"), through)
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.on("console", lambda m: errors.append(m.text) if m.type == "error"
                    and "Failed to load resource" not in m.text else None)  # a 409: stale
            page.goto(f"{base}/login")
            page.fill("#name", web.BY_ROLE["operator"])
            page.fill("#password", web.PASSWORD)
            page.click("#login")
            page.click("#take-lock")
            page.goto(f"{base}/runs/new")
            page.select_option("#plan_file", "plan.toml")
            page.select_option("#station", "sim")
            page.fill("#serials", "IMU-0001")
            page.click("#start")
            expect(page.locator("#connection")).to_have_text("live")
            expect(page.locator("#steps li")).to_have_count(26)
            expect(page.locator("#prompt")).to_be_visible(timeout=20_000)
            page.click("#confirm")
            expect(page.locator("#status")).to_have_text("running")
            # live values arrive and change: the station time and the table's angle
            expect(page.locator("#v-table-angle")).not_to_have_text("–", timeout=20_000)
            first = page.locator("#station-time").text_content()
            expect(page.locator("#station-time")).not_to_have_text(first or "", timeout=10_000)
            expect(page.locator("#units svg.gyro path")).to_have_count(3, timeout=10_000)
            # the socket drops: the page reconnects, the run goes on
            sockets[-1].close(code=1012, reason="the test drops the socket")
            expect(page.locator("#connection")).to_contain_text("reconnecting")
            expect(page.locator("#connection")).to_have_text("live", timeout=10_000)
            assert len(sockets) == 2
            expect(page.locator("#status")).to_have_text("running")
            moved = page.locator("#station-time").text_content()
            expect(page.locator("#station-time")).not_to_have_text(moved or "", timeout=10_000)
            # a window mean with its σ
            expect(page.locator("#window-table tbody tr").first).to_contain_text(
                "±", timeout=20_000)
            expect(page.locator("#steps li.step-done").first).to_be_visible()
            page.screenshot(path=str(shots / "1-live.png"), full_page=True)
            page.click("#abort")
            expect(page.locator("#status")).to_have_text("stopped", timeout=20_000)
            expect(page.locator("#resume")).to_be_visible()
            expect(page.locator("#log")).to_contain_text("stopped safely")
            done_at_abort = page.locator("#steps li.step-done").count()
            assert 0 < done_at_abort < 26
            page.screenshot(path=str(shots / "2-stopped.png"), full_page=True)
            page.click("#resume")
            expect(page.locator("#connection")).to_have_text("live", timeout=10_000)
            expect(page.locator("#status")).to_have_text("finished", timeout=40_000)
            expect(page.locator("#steps li.step-done")).to_have_count(26)
            expect(page.locator("#resume")).to_be_hidden()
            expect(page.locator("#time-left")).to_have_text("0 s")
            page.screenshot(path=str(shots / "3-finished.png"), full_page=True)
            # the script ran without an error (a refused command would be a console error too)
            assert errors == []
            # the lab overview: this station, held by the operator, with the run
            page.goto(f"{base}/lab")
            station = page.locator('[data-station="bench-1"]')
            expect(station).to_contain_text(f"held by {web.BY_ROLE['operator']}")
            expect(station).to_contain_text("cli-run")
            expect(station).to_contain_text("IMU-0001")
            page.screenshot(path=str(shots / "4-lab.png"), full_page=True)
        finally:
            browser.close()
    actions = [r.action for r in reversed(live_app.state.web.records.audit_log())]
    assert [a for a in actions if a in ("start", "prompt_answer", "abort", "resume")] == [
        "start", "prompt_answer", "abort", "resume"]
    assert sorted(p.name for p in shots.glob("*.png")) == [
        "1-live.png", "2-stopped.png", "3-finished.png", "4-lab.png"]
