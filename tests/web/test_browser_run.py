"""A whole run in a real browser: start, prompt, finish, results, review (docs/web.md).

Debian's chromium driven by Playwright against a uvicorn server this test starts on 127.0.0.1
(with its lifespan, so that a finished run is calibrated by itself), the real run supervisor
and a small P1 plan on the twin: the operator logs in, takes the station, starts the plan,
answers its operator check in the dialog, sees the run finish and its results (the parameter
table) and downloads the report; a reviewer then approves it with a comment and the page shows
it released, and the certificate written again with the review. Screenshots go to
``out/web/run_release/``. Without chromium the test fails.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path
from typing import Any


def _log_in(page: Any, base: str, name: str, password: str) -> None:
    page.goto(f"{base}/login")
    page.fill("#name", name)
    page.fill("#password", password)
    page.click("#login")


def test_an_operator_runs_a_plan_and_a_reviewer_releases_its_result(records_url, tmp_path,
                                                                     web, p1_tools, live):
    from playwright.sync_api import expect, sync_playwright

    from imucalib.records import open_records
    from imucalib.web.app import create_app

    executable = live.chromium_path()
    shots = live.screenshot_dir("run_release")
    for old in shots.glob("*.png"):
        old.unlink()
    web.add_users(records_url)
    plans = tmp_path / "plans"
    plans.mkdir()
    shutil.move(p1_tools.small_plan_file(tmp_path), plans / "p1-short.toml")
    app = create_app(records_url, tmp_path / "runs", None, plans_dir=plans, station="bench-1")
    operator, reviewer = web.BY_ROLE["operator"], web.BY_ROLE["reviewer"]
    with live.live_server(app, lifespan=True) as base, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=executable, args=live.CHROMIUM_ARGS)
        try:
            page = browser.new_page(accept_downloads=True)
            _log_in(page, base, operator, web.PASSWORD)
            page.click("#take-lock")
            expect(page.locator("#lock-state")).to_contain_text(f"Held by {operator}")
            page.goto(f"{base}/runs/new")
            page.select_option("#plan_file", "p1-short.toml")
            page.select_option("#station", "sim")
            page.fill("#serials", "IMU-0001")            # the twin's unit
            page.click("#start")
            expect(page).to_have_url(re.compile(rf"{base}/runs/[0-9TZ]+-[0-9a-f]+$"))
            run_id = page.url.rsplit("/", 1)[1]
            expect(page.locator("#prompt")).to_be_visible(timeout=30_000)
            page.fill("#prompt-note", "unit seated, cable tied")
            page.screenshot(path=str(shots / "1-prompt.png"), full_page=True)
            page.click("#confirm")
            expect(page.locator("#prompt")).to_be_hidden()
            expect(page.locator("#status")).to_have_text("finished", timeout=60_000)
            page.screenshot(path=str(shots / "2-finished.png"), full_page=True)
            page.click(f"a[href='/runs/{run_id}/results']")
            expect(page.locator("#calibration-state")).to_contain_text("Calibrated",
                                                                        timeout=90_000)
            table = page.locator("table.parameters").first
            expect(table).to_be_visible()
            expect(table).to_contain_text("µg")
            expect(page.locator(".release-status").first).to_have_text("NOT RELEASED")
            page.screenshot(path=str(shots / "3-results.png"), full_page=True)
            link = page.locator("#downloads a[href$='.report.pdf']").first
            with page.expect_download() as info:
                link.click()
            download = info.value
            assert download.suggested_filename.endswith(".report.pdf")
            assert Path(download.path()).read_bytes().startswith(b"%PDF")
            page.click("#logout")
            expect(page).to_have_url(f"{base}/login")

            _log_in(page, base, reviewer, web.PASSWORD)
            expect(page.locator("#who")).to_have_text(f"{reviewer} (reviewer)")
            page.goto(f"{base}/runs/{run_id}/results")
            comment = page.locator("input[name='comment']").first
            comment.fill("residuals and checks reviewed")
            page.locator("button[value='approve']").first.click()
            expect(page.locator(".release-status").first).to_have_text("RELEASED")
            expect(page.locator("#release")).to_contain_text("residuals and checks reviewed")
            # the certificate is written again with the review (the page reloads meanwhile)
            expect(page.locator("#certificate-state")).to_contain_text("Certificate written",
                                                                        timeout=90_000)
            expect(page.locator("#downloads a[href*='/files/certificate/']").first
                   ).to_be_visible()
            page.screenshot(path=str(shots / "4-released.png"), full_page=True)
        finally:
            browser.close()
    with open_records(records_url) as records:
        actions = [(r.actor, r.action) for r in records.audit_log(run_ref=run_id)]
    assert (operator, "start") in actions and (operator, "prompt_answer") in actions
    assert (operator, "calibrate") in actions and (reviewer, "approve") in actions
    assert sorted(p.name for p in shots.glob("*.png")) == [
        "1-prompt.png", "2-finished.png", "3-results.png", "4-released.png"]
