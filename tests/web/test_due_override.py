"""Starting a run on equipment overdue for calibration from the page (docs/web.md).

The station ``sim`` is given a rotation table whose certificate was due yesterday. An operator's
start is refused in one line that says only an engineer may override it, and an operator who
gives a reason anyway is refused (403); an engineer's start without a reason is refused in one
line pointing at the override field, and with one it starts, the reason passed to the
supervisor and kept in the ``start`` audit row naming the engineer. The real supervisor then
carries the reason to the run: the worker's run is not refused, and the recording and the
records' run hold the reason, as ``imucalib run --override-due`` does.
"""

from __future__ import annotations

import html
import json
import time
from datetime import date, timedelta
from pathlib import Path
from typing import Any

import pytest

REASON = "table recertification booked for Monday; its last check was in tolerance"


def _taking_the_override(fake: type) -> type:
    """The stand-in supervisor's class, its ``start`` taking the reason as the real one does."""

    class OverrideSupervisor(fake):  # type: ignore[misc,valid-type]
        def start(self, plan_path: Path, *, station: str, serials: list[str], operator: str,
                  override_due: str | None = None) -> str:
            self.calls.append(("start", (plan_path, station, serials, operator, override_due)))
            return str(self.add(f"20261129T12000{len(self.calls) % 10}Z-000000",
                                operator=operator))

    return OverrideSupervisor


def _overdue_table(url: str) -> int:
    from imucalib.records import open_records

    with open_records(url) as records:
        records.add_station("sim")
        return records.add_equipment("sim", "rotation table", "AC-2", "T-42", "CERT-17",
                                     calibrated_on=date.today() - timedelta(days=366),
                                     due_on=date.today() - timedelta(days=1))


@pytest.fixture
def overdue_app(records_url: str, tmp_path: Path, web: Any, supervisor: Any) -> Any:
    from imucalib.plan.io import plan_to_toml
    from imucalib.procedures.p1.plan import generate_p1_plan
    from imucalib.web.app import create_app

    web.add_users(records_url)
    table = _overdue_table(records_url)
    plans = tmp_path / "plans"
    plans.mkdir()
    (plans / "p1.toml").write_text(plan_to_toml(generate_p1_plan()), encoding="utf-8")
    sup = _taking_the_override(type(supervisor))(tmp_path / "runs")
    app = create_app(records_url, tmp_path / "runs", sup, plans_dir=plans, station="bench-1")
    yield app, sup, table
    app.state.web.close()


def _errors(answer: Any) -> str:
    page = html.unescape(answer.text)
    assert 'id="errors"' in page, page[:400]
    return page.split('id="errors"')[1].split("</section>")[0]


def test_only_an_engineer_starts_on_overdue_equipment_with_a_reason(overdue_app, records_url,
                                                                    web):
    from imucalib.records import open_records

    app, sup, table = overdue_app
    form = {"plan_file": "p1.toml", "station": "sim", "serials": "IMU-0001"}
    operator = web.Browser(app, "operator")
    operator.post("/lock/take")
    refused = operator.post("/runs/new", form)
    assert refused.status_code == 422
    line = _errors(refused)
    assert "overdue for calibration" in line and f"equipment {table}" in line
    assert "only an engineer may start a run on it" in line
    assert 'id="override_due"' not in operator.get("/runs/new").text   # not offered
    forced = operator.post("/runs/new", {**form, "override_due": "I say so"},
                           headers={"Accept": "application/json"})
    assert forced.status_code == 403
    assert forced.json() == {"ok": False, "error": "Oli Operator is an operator: only an "
                             "engineer may start a run on equipment overdue for calibration"}
    operator.post("/lock/release")
    assert [c for c in sup.calls if c[0] == "start"] == []

    engineer = web.Browser(app, "engineer")
    engineer.post("/lock/take")
    assert 'id="override_due"' in engineer.get("/runs/new").text
    asked = engineer.post("/runs/new", form)
    assert asked.status_code == 422 and "Override overdue equipment" in _errors(asked)
    blank = engineer.post("/runs/new", {**form, "override_due": "   "})
    assert blank.status_code == 422
    started = engineer.post("/runs/new", {**form, "override_due": f"  {REASON} "})
    assert started.status_code == 303, started.text
    (call,) = [c for c in sup.calls if c[0] == "start"]
    assert call[1][3] == "Eve Engineer" and call[1][4] == REASON
    run_id = started.headers["location"].rsplit("/", 1)[1]
    with open_records(records_url) as records:
        (row,) = [r for r in records.audit_log(run_ref=run_id) if r.action == "start"]
    assert row.actor == "Eve Engineer"
    assert row.details["override_due"] == REASON
    assert row.details["overdue_equipment"] == [table]
    with open_records(records_url) as records:
        (own,) = [r for r in records.audit_log(run_ref=run_id) if r.action == "override_due"]
    assert own.actor == "Eve Engineer"
    assert own.details == {"reason": REASON, "overdue_equipment": [table]}


def test_an_override_without_overdue_equipment_overrides_nothing(records_url, tmp_path, web,
                                                                 supervisor):
    from imucalib.plan.io import plan_to_toml
    from imucalib.procedures.p1.plan import generate_p1_plan
    from imucalib.records import open_records
    from imucalib.web.app import create_app

    web.add_users(records_url)
    plans = tmp_path / "plans"
    plans.mkdir()
    (plans / "p1.toml").write_text(plan_to_toml(generate_p1_plan()), encoding="utf-8")
    sup = _taking_the_override(type(supervisor))(tmp_path / "runs")
    app = create_app(records_url, tmp_path / "runs", sup, plans_dir=plans, station="bench-1")
    try:
        engineer = web.Browser(app, "engineer")
        engineer.post("/lock/take")
        started = engineer.post("/runs/new", {"plan_file": "p1.toml", "station": "sim",
                                              "serials": "IMU-0001", "override_due": REASON})
        assert started.status_code == 303
        (call,) = [c for c in sup.calls if c[0] == "start"]
        assert call[1][4] is None
        run_id = started.headers["location"].rsplit("/", 1)[1]
        with open_records(records_url) as records:
            (row,) = [r for r in records.audit_log(run_ref=run_id) if r.action == "start"]
        assert "override_due" not in row.details
    finally:
        app.state.web.close()


def test_the_worker_runs_with_the_reason_and_records_it(records_url, tmp_path, p1_tools):
    from imucalib.io import open_recording
    from imucalib.records import open_records
    from imucalib.web.supervisor import RunSupervisor

    table = _overdue_table(records_url)
    plan = p1_tools.small_plan_file(tmp_path)
    sup = RunSupervisor(tmp_path / "runs", db=records_url)
    try:
        refused = sup.start(plan, station="sim", serials=[], operator="Eve Engineer")
        run_id = sup.start(plan, station="sim", serials=[], operator="Eve Engineer",
                           override_due=REASON)
        deadline, answered = time.monotonic() + 120, set()
        while {sup.view(r).status for r in (refused, run_id)} & {"starting", "running",
                                                                    "waiting", "aborting"}:
            assert time.monotonic() < deadline, "the runs did not end in 120 s"
            prompt = sup.view(run_id).prompt
            if prompt is not None and prompt.prompt_id not in answered:  # the mounting check
                sup.answer(run_id, prompt.prompt_id, prompt.step_index, True, "Eve Engineer")
                answered.add(prompt.prompt_id)
            time.sleep(0.1)
        no = sup.view(refused)
        assert no.status == "failed" and no.error is not None and "overdue" in no.error
        view = sup.view(run_id)
        assert view.status == "finished", view.error
        events = (sup.runs_dir / run_id / "events.jsonl").read_text(encoding="utf-8")
        logged = [json.loads(x)["line"] for x in events.splitlines() if '"log"' in x]
        assert any(f"overridden by Eve Engineer: {REASON}" in line for line in logged)
    finally:
        sup.close()
    with open_recording(Path(view.recording_path)) as rec:
        assert rec.metadata["override_due"] == REASON
    with open_records(records_url) as records:
        (run,) = [records.run(i) for i in (1, 2, 3) if _exists(records, i)]
    assert run.environment["override_due"] == REASON and run.equipment_ids == (table,)


def _exists(records: Any, run_id: int) -> bool:
    from imucalib.errors import CalibrationError

    try:
        records.run(run_id)
    except CalibrationError:
        return False
    return True
