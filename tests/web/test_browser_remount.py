"""A P2 run's remount prompts answered in a real browser (docs/web.md, "Live view").

Debian's chromium driven by Playwright against a uvicorn server this test starts on 127.0.0.1,
the real run supervisor and the shortest P2 plan on the twin: two temperature points (P2's
least), one unit at 50 Hz, a 10-s soak criterion, 1-s settles and 2-s statics, so it runs in
seconds, yet it has all of P2's operator checks: the mounting check, then six remounts per
temperature point. Some remounts are given a yaw (the plan's ``remount_yaw_deg``), so that the
figure's turn is checked too. The operator answers every check in the page's dialog; each
remount dialog must draw the face the plan puts up and its yaw (the figure's attributes, its
labels and the top view's rotation), the mounting check none. The run must finish with every
step done. Screenshots go to ``out/web/p2_remount/``. Without chromium the test fails.
"""

from __future__ import annotations

import re
import time
from pathlib import Path

#: The yaws given to the remounts, in turn (P2's own are 0°). [°]
YAWS_DEG = (0.0, 90.0, -45.0)


def _short_p2_plan(folder: Path) -> tuple[list[str], list[tuple[int, str | None, float]]]:
    """Write the shortest P2 plan; return its units and operator checks (step, face, yaw)."""
    from imucalib.plan import write_plan
    from imucalib.plan.schema import OperatorCheckStep
    from imucalib.procedures.p2.plan import generate_p2_plan

    plan = generate_p2_plan(n_imus=1, temperatures_degc=(25.0, 27.0), held_out_degc=(),
                            rate_dps=90.0, revolutions=1, static_s=2.0, settle_s=1.0,
                            ramp_degc_per_min=10.0, stable_for_s=10.0, resoak_s=0.0,
                            soak_timeout_s=600.0, sample_rate_hz=50.0, name="p2-remount")
    steps, checks, k = [], [], 0
    for i, step in enumerate(plan.steps):
        if isinstance(step, OperatorCheckStep) and step.remount is not None:
            step = step.model_copy(update={"remount_yaw_deg": YAWS_DEG[k % len(YAWS_DEG)]})
            k += 1
        if isinstance(step, OperatorCheckStep):
            checks.append((i, step.remount, float(step.remount_yaw_deg)))
        steps.append(step)
    plan = plan.model_copy(update={"steps": tuple(steps)})
    write_plan(plan, folder / "p2-remount.toml")
    assert plan.twin is not None
    return [imu.name for imu in plan.twin.imus], checks


def test_an_operator_answers_a_p2_plans_remount_prompts_in_the_browser(records_url, tmp_path,
                                                                       web, live):
    from playwright.sync_api import expect, sync_playwright

    from imucalib.web.app import create_app

    executable = live.chromium_path()
    shots = live.screenshot_dir("p2_remount")
    for old in shots.glob("*.png"):
        old.unlink()
    web.add_users(records_url)
    plans = tmp_path / "plans"
    plans.mkdir()
    units, checks = _short_p2_plan(plans)
    remounts = [c for c in checks if c[1] is not None]
    assert len(remounts) == 12 and {c[1] for c in remounts} == {"+x", "-x", "+y", "-y", "+z",
                                                                "-z"}
    assert {c[2] for c in remounts} == set(YAWS_DEG)
    app = create_app(records_url, tmp_path / "runs", None, plans_dir=plans, station="bench-1")
    operator = web.BY_ROLE["operator"]
    started = time.monotonic()
    seen: list[tuple[int, str | None, float]] = []
    with live.live_server(app) as base, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=executable, args=live.CHROMIUM_ARGS)
        try:
            page = browser.new_page()
            page.goto(f"{base}/login")
            page.fill("#name", operator)
            page.fill("#password", web.PASSWORD)
            page.click("#login")
            page.click("#take-lock")
            expect(page.locator("#lock-state")).to_contain_text(f"Held by {operator}")
            page.goto(f"{base}/runs/new")
            page.select_option("#plan_file", "p2-remount.toml")
            page.select_option("#station", "sim")
            page.fill("#serials", " ".join(units))          # the twin's unit
            page.click("#start")
            expect(page).to_have_url(re.compile(rf"{base}/runs/[0-9TZ]+-[0-9a-f]+$"))
            dialog, figure = page.locator("#prompt"), page.locator("#prompt-figure")
            for n, (index, face, yaw) in enumerate(checks):
                # the page shows this check: its step is the current one, the dialog open
                expect(page.locator("#step")).to_have_text(str(index + 1), timeout=30_000)
                expect(dialog).to_be_visible(timeout=30_000)
                if face is None:
                    expect(figure).to_be_hidden()
                    seen.append((index, None, 0.0))
                else:
                    expect(figure).to_be_visible()
                    expect(figure).to_have_attribute("data-face", face)
                    assert float(figure.get_attribute("data-yaw-deg") or "nan") == yaw
                    expect(page.locator("#remount-face-label")).to_have_text(face)
                    expect(page.locator("#remount-yaw-label")).to_have_text(f"yaw {yaw:g}°")
                    turn = page.locator("#remount-yaw").get_attribute("transform") or ""
                    found = re.fullmatch(r"rotate\((\S+) \S+ \S+\)", turn)
                    assert found and float(found.group(1)) == -yaw, turn
                    # drawn: the shaded face and the turned cube have a size on the page
                    for part in ("#remount-face", "#remount-yaw"):
                        box = page.locator(part).bounding_box()
                        assert box is not None and box["width"] > 10 and box["height"] > 10
                    expect(dialog).to_contain_text(f"{face} face up")
                    seen.append((index, face, yaw))
                if n in (0, 1, 3):
                    page.screenshot(path=str(shots / f"{n + 1}-check-step-{index + 1}.png"))
                page.click("#confirm")
                expect(dialog).to_be_hidden()
            expect(page.locator("#status")).to_have_text("finished", timeout=60_000)
            expect(page.locator("#steps li.step-done")).to_have_count(
                page.locator("#steps li").count())
            page.screenshot(path=str(shots / "5-finished.png"), full_page=True)
        finally:
            browser.close()
    elapsed = time.monotonic() - started
    assert seen == checks
    assert sorted(p.name for p in shots.glob("*.png")) == [
        f"{n + 1}-check-step-{checks[n][0] + 1}.png" for n in (0, 1, 3)] + ["5-finished.png"]
    assert elapsed < 60, f"the P2 browser run took {elapsed:.0f} s"
