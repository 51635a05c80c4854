"""The web page in a real browser: Debian's chromium driven by Playwright (docs/web.md).

The server runs in this process (uvicorn, 127.0.0.1, a free port) on a fresh records database
and a stand-in supervisor; the browser reaches nothing else. Screenshots go to ``out/web/``.
Without chromium the test fails, it is not skipped (``scripts/chromium.sh`` installs it).
"""

from __future__ import annotations


def test_an_operator_logs_in_takes_the_station_and_logs_out(web_app, web, live):
    from playwright.sync_api import expect, sync_playwright

    executable = live.chromium_path()
    shots = live.screenshot_dir("operator_lock")
    operator = web.BY_ROLE["operator"]
    with live.live_server(web_app) as base, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=executable, args=live.CHROMIUM_ARGS)
        try:
            page = browser.new_page()
            page.goto(f"{base}/")
            expect(page).to_have_url(f"{base}/login?next=/")
            page.fill("#name", operator)
            page.fill("#password", web.PASSWORD)
            page.screenshot(path=str(shots / "1-login.png"))
            page.click("#login")
            expect(page).to_have_url(f"{base}/")
            expect(page.locator("#who")).to_have_text(f"{operator} (operator)")
            expect(page.locator("#lock-state")).to_have_text("Free.")
            expect(page.locator("#recent")).to_contain_text("p1-short")
            page.screenshot(path=str(shots / "2-station.png"), full_page=True)
            page.click("#take-lock")
            expect(page.locator("#lock-state")).to_contain_text(f"Held by {operator}")
            page.screenshot(path=str(shots / "3-lock-taken.png"), full_page=True)
            page.click("#logout")
            expect(page).to_have_url(f"{base}/login")
            expect(page.locator("#login")).to_be_visible()
        finally:
            browser.close()
    actions = [r.action for r in reversed(web_app.state.web.records.audit_log())]
    assert actions[-3:] == ["login", "lock", "logout"]
    assert web_app.state.web.records.station_lock("bench-1").holder == operator
    assert sorted(p.name for p in shots.glob("*.png")) == [
        "1-login.png", "2-station.png", "3-lock-taken.png"]


def test_the_run_page_shows_the_prompt_live_and_sends_the_answer(web_app, web, supervisor,
                                                                live):
    """run.js: the socket's snapshot opens the dialog; Confirm posts the answer with its ids."""
    from playwright.sync_api import expect, sync_playwright

    executable = live.chromium_path()
    shots = live.screenshot_dir("run_prompt")
    run_id = supervisor.runs()[0].run_id
    with live.live_server(web_app) as base, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=executable, args=live.CHROMIUM_ARGS)
        try:
            page = browser.new_page()
            page.goto(f"{base}/login")
            page.fill("#name", web.BY_ROLE["operator"])
            page.fill("#password", web.PASSWORD)
            page.click("#login")
            page.click("#take-lock")
            page.goto(f"{base}/runs/{run_id}")
            expect(page.locator("#connection")).to_have_text("live")
            expect(page.locator("#prompt")).to_be_visible()
            expect(page.locator("#prompt-text")).to_have_text(
                "turn the cube so that its +y face points up")
            page.fill("#prompt-note", "seated")
            page.screenshot(path=str(shots / "1-prompt.png"), full_page=True)
            page.click("#confirm")
            expect(page.locator("#prompt")).to_be_hidden()
            page.wait_for_function("document.getElementById('log').textContent.length > 0")
            page.screenshot(path=str(shots / "2-answered.png"), full_page=True)
        finally:
            browser.close()
    answers = [c for c in supervisor.calls if c[0] == "answer"]
    assert answers == [("answer", (run_id, 7, 1, True, web.BY_ROLE["operator"], "seated"))]


def test_without_chromium_the_browser_tests_fail_not_skip(monkeypatch, live):
    import os

    import pytest

    monkeypatch.setenv(live.CHROMIUM_ENV, "/nonexistent/chromium")
    monkeypatch.setattr(os, "access", lambda *_a: False)
    with pytest.raises(pytest.fail.Exception, match=r"need chromium.*scripts/chromium\.sh"):
        live.chromium_path()
