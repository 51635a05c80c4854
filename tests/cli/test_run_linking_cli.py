"""One calibration, one run (docs/records.md): `run` opens the run, `calibrate` of its recording
attaches the result to it, a re-analysis is the result's next version, data no run recorded
get an unplanned run; equipment recertified from the command line; `--no-record` still checks
the due dates."""

from __future__ import annotations

import json
from datetime import UTC, date, datetime, timedelta
from pathlib import Path

import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.io import open_recording
from imucalib.plan.io import plan_to_toml
from imucalib.procedures import registry
from imucalib.records import open_records

from .test_allan_command import _canonical

runner = CliRunner()


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    from imucalib.cli import _app

    monkeypatch.setattr(_app.console, "width", 240)


def _plan(tmp_path: Path) -> Path:
    plan = registry.get("tumble").generate_plan(n_positions=8, axes=("z",), record_s=5.0,
                                                settle_s=2.0, sample_rate_hz=50.0)
    path = tmp_path / "tumble.toml"
    path.write_text(plan_to_toml(plan), encoding="utf-8")
    return path


def _ok(args: list[str]) -> str:
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    return " ".join(res.output.split())


def _refused(args: list[str], code: int = 2) -> str:
    res = runner.invoke(app, args)
    assert res.exit_code == code, res.output
    assert "Traceback" not in res.output and res.output.startswith("error: "), res.output
    return " ".join(res.output.split())


def test_calibrate_attaches_to_the_run_of_its_recording_and_reanalyses_are_versions(tmp_path):
    db = str(tmp_path / "lab.db")
    rec = tmp_path / "run.h5"
    before = datetime.now(UTC)
    out = _ok(["run", str(_plan(tmp_path)), "--yes", "-q", "-o", str(rec), "--db", db,
               "--operator", "J. Doe"])
    after = datetime.now(UTC)
    assert "recorded run 1 " in out
    out = _ok(["calibrate", str(rec), "-q", "-o", str(tmp_path / "a"), "--db", db])
    assert "recorded result(s) 1 in run 1 of plan tumble" in out
    out = _ok(["calibrate", str(rec), "-q", "-o", str(tmp_path / "b"), "--db", db,
               "--set", "angle-std-arcsec=5"])
    assert "recorded result(s) 2 (re-analysis, replaces 1) in run 1" in out
    out = _ok(["calibrate", str(rec), "-q", "-o", str(tmp_path / "c"), "--db", db,
               "--reason", "checking the gravity value"])
    assert "recorded result(s) 3 (re-analysis, replaces 2) in run 1" in out
    with open_records(db) as records:
        [run] = records.runs_of_plan("tumble")
        assert run.run_id == 1 and run.result_ids == (1, 2, 3)
        assert run.operator == "J. Doe" and run.opened_by == "run" and not run.unplanned
        assert run.started_utc is not None and run.ended_utc is not None
        assert before <= run.started_utc <= run.ended_utc <= after
        history = records.history("IMU-0001")
        assert [(e.result_id, e.version, e.replaces, e.run_id) for e in history] == [
            (1, 1, None, 1), (2, 2, 1, 1), (3, 3, 2, 1)]
        assert history[1].amendment_reason.startswith("re-analysis by ")
        assert "with options" in history[1].amendment_reason
        assert "angle_std_arcsec=5.0" in history[1].amendment_reason
        assert history[2].amendment_reason.endswith(": checking the gravity value")
        # the calibration date is the run's, whichever version
        assert {e.calibrated_utc for e in history} == {run.started_utc}
        [status] = records.unit_status()
        assert status.result_id == 3 and status.last_calibrated == run.started_utc.date()
        assert records.verify() == []
    # an amendment keeps the calibration date, and so the due date
    result_file = next((tmp_path / "c").glob("*.result.json"))
    _ok(["records", "amend", "3", str(result_file), "--reason", "typo", "--db", db])
    rows = json.loads(runner.invoke(app, ["records", "list", "--db", db, "--json"]).output)
    assert rows[0]["result_id"] == 4
    assert rows[0]["last_calibrated"] == run.started_utc.date().isoformat()
    assert rows[0]["due_on"] == (run.started_utc.date() + timedelta(days=365)).isoformat()


def test_data_no_run_recorded_get_an_unplanned_run(tmp_path):
    db = str(tmp_path / "lab.db")
    log = _canonical(tmp_path)
    out = _ok(["allan", str(log), "--gyro-unit", "deg/s", "--out", str(tmp_path / "o"),
               "--db", db])
    assert "recorded run 1, result(s) 1 in" in out
    out = _ok(["allan", str(log), "--gyro-unit", "deg/s", "--out", str(tmp_path / "p"),
               "--db", db])
    assert "recorded result(s) 2 (re-analysis, replaces 1) in run 1 in" in out
    with open_records(db) as records:
        run = records.run(1)
        assert run.unplanned and run.opened_by == "calibrate" and run.plan_hash == ""
        assert run.environment["source"] == "log" and run.recording_path == str(log.resolve())
        assert run.result_ids == (1, 2) and run.started_utc is None
        first, second = records.history("imu")
        assert second.calibrated_utc == first.calibrated_utc == first.created_utc


def test_recertify_unblocks_the_run_and_no_record_still_checks_due_dates(tmp_path):
    db = str(tmp_path / "lab.db")
    plan = str(_plan(tmp_path))
    yesterday = (date.today() - timedelta(days=1)).isoformat()
    _ok(["records", "add-equipment", "--kind", "rate-table", "--model", "AC1120S", "--serial",
         "T-9", "--certificate", "C-17", "--due-on", yesterday, "--db", db])
    first = tmp_path / "first.h5"
    for extra in ([], ["--no-record"], ["--no-record", "--override-due", " "]):
        out = _refused(["run", plan, "--yes", "-q", "-o", str(first), "--db", db, *extra])
        assert "overdue" in out and "C-17" in out and "records recertify" in out
    assert not first.exists()
    # overridden without a records entry: the reason travels in the recording, and the run that
    # calibrate opens for it carries it, with the equipment
    _ok(["run", plan, "--yes", "-q", "-o", str(first), "--db", db, "--no-record",
         "--override-due", "renewal booked for Monday"])
    with open_recording(first) as rec:
        assert rec.metadata["override_due"] == "renewal booked for Monday"
    out = _ok(["calibrate", str(first), "-q", "-o", str(tmp_path / "a"), "--db", db])
    assert "recorded run 1, result(s) 1" in out
    with open_records(db) as records:
        run = records.run(1)
    assert run.opened_by == "calibrate" and not run.unplanned and run.plan_name == "tumble"
    assert run.environment["override_due"] == "renewal booked for Monday"
    assert run.equipment_ids == (1,) and run.station == "sim" and run.started_utc is not None
    # the renewed certificate replaces the old one, which stays in the history
    assert "error: --calibrated-on wants a date" in _refused(
        ["records", "recertify", "1", "--certificate", "C-18", "--calibrated-on",
         "2026-13-01", "--due-on", "2027-01-01", "--db", db])
    assert "must come after --calibrated-on" in _refused(
        ["records", "recertify", "1", "--certificate", "C-18", "--calibrated-on",
         "2027-01-02", "--due-on", "2027-01-01", "--db", db])
    assert "no equipment with id 7" in _refused(
        ["records", "recertify", "7", "--certificate", "C-18", "--calibrated-on",
         date.today().isoformat(), "--due-on", "2099-01-01", "--db", db])
    out = _ok(["records", "recertify", "1", "--certificate", "C-18", "--calibrated-on",
               date.today().isoformat(), "--due-on", "2099-01-01", "--db", db])
    assert "equipment 2 replaces equipment 1" in out and "C-18" in out
    assert "recertify 2" in _refused(["records", "recertify", "1", "--certificate", "C-19",
                                      "--calibrated-on", date.today().isoformat(), "--due-on",
                                      "2099-01-01", "--db", db])
    listed = json.loads(runner.invoke(app, ["records", "equipment", "--db", db,
                                            "--json"]).output)
    assert [(e["equipment_id"], e["certificate"], e["status"]) for e in listed] == [
        (2, "C-18", "current")]
    listed = json.loads(runner.invoke(app, ["records", "equipment", "--all", "--db", db,
                                            "--json"]).output)
    assert [(e["equipment_id"], e["certificate"], e["replaces"], e["status"])
            for e in listed] == [(1, "C-17", None, "replaced by 2"), (2, "C-18", 1, "current")]
    assert "C-18" in _ok(["records", "equipment", "--all", "--db", db])
    # no longer overdue: the run goes, with the new certificate, and no override recorded
    second = tmp_path / "second.h5"
    assert "recorded run 2 " in _ok(["run", plan, "--yes", "-q", "-o", str(second),
                                     "--db", db])
    with open_records(db) as records:
        run = records.run(2)
        assert run.equipment_ids == (2,) and run.environment["override_due"] == ""
        assert records.due_equipment() == [] and records.verify() == []


def test_an_override_is_recorded_with_the_run(tmp_path):
    db = str(tmp_path / "lab.db")
    yesterday = (date.today() - timedelta(days=1)).isoformat()
    _ok(["records", "add-equipment", "--kind", "chamber", "--serial", "CH-2", "--certificate",
         "C-5", "--due-on", yesterday, "--db", db])
    rec = tmp_path / "run.h5"
    _ok(["run", str(_plan(tmp_path)), "--yes", "-q", "-o", str(rec), "--db", db,
         "--override-due", "chamber not used by this plan"])
    with open_records(db) as records:
        [run] = records.runs_of_plan("tumble")
    assert run.environment["override_due"] == "chamber not used by this plan"
    assert [e["certificate"] for e in run.environment["overdue_equipment"]] == ["C-5"]
    # without a records database, --no-record has nothing to check and creates none
    absent = tmp_path / "absent.db"
    _ok(["run", str(_plan(tmp_path)), "--yes", "-q", "-o", str(tmp_path / "x.h5"),
         "--db", str(absent), "--no-record"])
    assert not absent.exists()
