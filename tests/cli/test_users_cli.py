"""`imucalib users …`, `records review` as a control and `records show` (docs/records.md,
"Users and roles")."""

from __future__ import annotations

import json
from datetime import UTC, date, datetime
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.models.result import CalibrationResult, Provenance, triad_parameter_names
from imucalib.records import open_records

runner = CliRunner()


def _result(serial: str) -> CalibrationResult:
    """A small per-axis accelerometer result of unit `serial`."""
    names = triad_parameter_names("accel", "per-axis")
    values = np.array([1.0, 1.001, 1.002, 0.01, -0.01, 0.02])
    units = {n: "1" if "_K_" in n else "m/s^2" for n in names}
    return CalibrationResult(
        sensor_id=serial, procedure="p1", model="per-axis", param_names=names, values=values,
        covariance=np.diag(np.full(len(names), 1e-8)), units=units,
        provenance=Provenance(plan_hash="ab" * 32, recording="run.h5",
                              software_version="0.1.0", created_utc="2026-03-01T00:00:00Z"))


def _ok(*args: str) -> str:
    res = runner.invoke(app, list(args))
    assert res.exit_code == 0, res.output
    return " ".join(res.output.split())


def _refused(*args: str) -> str:
    """The command fails with one `error:` line and no traceback; return that line."""
    res = runner.invoke(app, list(args))
    assert res.exit_code == 2, res.output
    assert res.exception is None or isinstance(res.exception, SystemExit), res.exception
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), res.output
    assert "Traceback" not in res.output
    return lines[0]


@pytest.fixture
def lab(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """A database with an admin, an operator and a reviewer, and one result operated by Oli."""
    monkeypatch.delenv("IMUCALIB_USER", raising=False)
    db = str(tmp_path / "lab.db")
    assert "user 1: Ada Admin (AA), admin" in _ok("users", "add", "Ada Admin", "--initials",
                                                  "AA", "--role", "admin", "--db", db)
    _ok("users", "add", "Oli Operator", "--initials", "OO", "--role", "operator", "--user", "AA",
        "--db", db)
    _ok("users", "add", "Rae Reviewer", "--initials", "RR", "--role", "reviewer", "--user",
        "Ada Admin", "--db", db)
    with open_records(db) as records:
        station = records.add_station("lab 1")
        table = records.add_equipment(station, "rate table", "ACT 2000", "T-1", "C-17",
                                      date(2026, 1, 5), date(2027, 1, 5))
        run = records.record_run(plan_name="p1-tactical", procedure="p1",
                                 operator="Oli Operator", station=station, equipment=[table],
                                 started_utc=datetime(2026, 3, 1, 8, tzinfo=UTC),
                                 ended_utc=datetime(2026, 3, 1, 9, 30, tzinfo=UTC))
        assert records.record_result(run, _result("IMU-7"), passed=True) == 1
    return db


def test_users_are_added_listed_and_disabled(lab, monkeypatch):
    rows = json.loads(runner.invoke(app, ["users", "list", "--db", lab, "--json"]).output)
    assert [(u["name"], u["initials"], u["role"], u["active"], u["added_by"]) for u in rows] == [
        ("Ada Admin", "AA", "admin", True, ""), ("Oli Operator", "OO", "operator", True,
                                                 "Ada Admin"),
        ("Rae Reviewer", "RR", "reviewer", True, "Ada Admin")]
    res = runner.invoke(app, ["users", "list", "--db", lab])
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())  # the table may wrap at the console's width
    assert all(w in text for w in ("Rae", "Reviewer", "RR", "reviewer", "yes", "Ada", "Admin"))
    # once there are users, who is acting must be said; once there is an admin, an admin
    assert "who is acting?" in _refused("users", "add", "Cy", "--role", "reviewer", "--db", lab)
    assert "only an admin may add a user; Oli Operator is an operator" in _refused(
        "users", "add", "Cy", "--role", "reviewer", "--user", "OO", "--db", lab)
    assert "role must be one of operator, engineer, reviewer, admin; got 'boss'" in _refused(
        "users", "add", "Cy", "--role", "boss", "--user", "AA", "--db", lab)
    monkeypatch.setenv("IMUCALIB_USER", "Ada Admin")
    assert "user Oli Operator disabled" in _ok("users", "disable", "Oli Operator", "--reason",
                                               "left the lab", "--db", lab)
    rows = json.loads(runner.invoke(app, ["users", "list", "--db", lab, "--json"]).output)
    assert rows[1]["active"] is False
    assert rows[1]["events"][0]["reason"] == "left the lab"
    assert rows[1]["events"][0]["by"] == "Ada Admin"
    assert "is disabled (left the lab)" in _refused("users", "add", "Cy", "--role", "reviewer",
                                                    "--user", "Oli Operator", "--db", lab)
    _ok("users", "enable", "Oli Operator", "--reason", "back", "--db", lab)
    assert "intact" in _ok("records", "verify", "--db", lab)


def test_a_reviewer_approves_another_users_run_and_the_result_is_released(lab):
    assert "--decision must be approve or reject (none given); a review has no default" in \
        _refused("records", "review", "1", "--user", "RR", "--db", lab)
    assert "(got 'yes')" in _refused("records", "review", "1", "--decision", "yes", "--user",
                                     "RR", "--db", lab)
    assert "who is acting?" in _refused("records", "review", "1", "--decision", "approve",
                                        "--db", lab)
    assert "Oli Operator is an operator: only a reviewer or an admin may review" in _refused(
        "records", "review", "1", "--decision", "approve", "--user", "OO", "--db", lab)
    assert "a rejection needs a comment" in _refused(
        "records", "review", "1", "--decision", "reject", "--user", "RR", "--db", lab)
    out = _ok("records", "review", "1", "--decision", "approve", "--comment",
              "residuals within limits", "--user", "rr", "--db", lab)
    assert "result 1 approved by Rae Reviewer; released: approved by Rae Reviewer (RR, " \
           "reviewer)" in out
    shown = json.loads(runner.invoke(app, ["records", "show", "1", "--db", lab,
                                           "--json"]).output)
    assert shown["release"]["released"] is True
    assert shown["release"]["reviewer"] == "Rae Reviewer"
    assert [r["reviewer"] for r in shown["reviews"]] == ["Rae Reviewer"]


def test_self_approval_is_refused(lab):
    with open_records(lab) as records:               # a reviewer who operated the run herself
        records.add_user("Sam Both", "SB", "reviewer", by="Ada Admin")
        run = records.record_run(plan_name="p1-tactical", operator="Sam Both")
        rid = records.record_result(run, _result("IMU-8"), passed=True)
    line = _refused("records", "review", str(rid), "--decision", "approve", "--user", "SB",
                    "--db", lab)
    assert line == (f"error: review of result {rid} refused: Sam Both is the operator of run "
                    f"{run}: a result is reviewed by someone other than its operator "
                    "(reviewers: Ada Admin (admin), Rae Reviewer (reviewer), Sam Both "
                    "(reviewer))")


def test_records_show_gives_the_result_its_run_equipment_reviews_and_release(lab):
    text = _ok("records", "show", "1", "--db", lab)
    for expected in ("result 1: unit IMU-7, procedure p1, version 1 (current), PASS",
                     "run 1: plan p1-tactical", "operator Oli Operator", "station lab 1",
                     "started 2026-03-01 08:00:00 UTC, ended 2026-03-01 09:30:00 UTC",
                     "ACT 2000", "T-1", "C-17", "2027-01-05", "accel_b_x",
                     "reviews of result 1: none", "not released: result 1 has no review"):
        assert expected in text, expected
    shown = json.loads(runner.invoke(app, ["records", "show", "1", "--db", lab,
                                           "--json"]).output)
    assert set(shown) == {"result", "run", "equipment", "reviews", "release", "document",
                          "reviews_unverified"}
    assert shown["reviews_unverified"] == ""            # the records verify: reviews shown
    assert shown["run"]["operator"] == "Oli Operator"
    assert shown["run"]["started_utc"].startswith("2026-03-01T08:00:00")
    assert [(e["serial"], e["certificate"], e["due_on"]) for e in shown["equipment"]] == [
        ("T-1", "C-17", "2027-01-05")]
    assert shown["release"]["released"] is False and shown["reviews"] == []
    assert shown["document"]["sensor_id"] == "IMU-7"
    assert "no result with id 9" in _refused("records", "show", "9", "--db", lab)


def test_without_users_a_review_still_needs_a_name_and_a_decision(tmp_path, monkeypatch):
    """(U.1) the single-person setup: the reviewer named is recorded as given."""
    monkeypatch.delenv("IMUCALIB_USER", raising=False)
    db = str(tmp_path / "solo.db")
    with open_records(db) as records:
        records.record_result(records.record_run(operator="bo"), _result("IMU-1"))
    assert "name the reviewer: pass --user NAME or set IMUCALIB_USER" in _refused(
        "records", "review", "1", "--decision", "approve", "--db", db)
    monkeypatch.setenv("IMUCALIB_USER", "bo")
    out = _ok("records", "review", "1", "--decision", "approve", "--db", db)
    assert "approved by bo; not released:" in out and "no users were registered" in out


def test_without_a_name_the_os_account_is_named_and_the_note_says_where(consumer_run, tmp_path,
                                                                          monkeypatch):
    monkeypatch.delenv("IMUCALIB_USER", raising=False)
    (tmp_path / "lab.toml").write_text("", encoding="utf-8")  # no [operator] default
    monkeypatch.setenv("IMUCALIB_CONFIG", str(tmp_path / "lab.toml"))
    done = runner.invoke(app, ["calibrate", str(consumer_run), "--out", str(tmp_path / "o"),
                               "--no-record"])
    assert done.exit_code in (0, 1), done.output
    assert "note: named in the result as" in done.output and "recorded as" not in done.output
