"""One calibration's life through the command line (docs/records.md, "A calibration's life").

Users (an admin, an operator, a reviewer) are registered; the operator runs a P1 plan on the
twin with the station's registered rate table and calibrates the recording, which attaches the
result to the same run; the operator's own approval is refused; the reviewer approves, which
releases the certificate; ``report --run N`` then gives the released certificate with the
customer named at the run, the same id as the draft written at calibration time, the equipment's
serial and certificate number, the operator and the reviewer, the calibration and issue dates,
the uncertainty budget, the statement that the results relate only to the item, the decision
and, the station being the twin, that the results are not traceable. The records rows are read
back with ``records show``.
"""

from __future__ import annotations

import json
import re
from datetime import date, timedelta
from pathlib import Path

from pypdf import PdfReader
from typer.testing import CliRunner

from imucalib.cli import app

runner = CliRunner()
P1_SHORT = ["--static-s", "20", "--record-s", "5", "--settle-s", "2", "--rate-settle-s", "2",
            "--warm-up-s", "5", "--revolutions", "1", "--sample-rate-hz", "100"]


def _ok(args: list[str]) -> str:
    res = runner.invoke(app, [str(a) for a in args])
    assert res.exit_code == 0, res.output
    assert "Traceback" not in res.output
    return " ".join(res.output.split())


def _pdf_text(path: Path) -> tuple[list[str], str]:
    pages = [" ".join(p.extract_text().split()) for p in PdfReader(str(path)).pages]
    return pages, " ".join(pages)


def test_plan_run_calibrate_review_release_report(tmp_path: Path, monkeypatch):
    monkeypatch.delenv("IMUCALIB_USER", raising=False)
    db = str(tmp_path / "lab.db")
    _ok(["users", "add", "Ada Admin", "--initials", "AA", "--role", "admin", "--db", db])
    for name, initials, role in (("Oli Operator", "OO", "operator"),
                                 ("Rae Reviewer", "RR", "reviewer")):
        _ok(["users", "add", name, "--initials", initials, "--role", role, "--user", "AA",
             "--db", db])
    due = (date.today() + timedelta(days=200)).isoformat()
    _ok(["records", "add-equipment", "--kind", "rate-table", "--model", "AC1120S", "--serial",
         "T-4711", "--certificate", "DKD-2026-042", "--due-on", due, "--db", db])
    plan, rec, out = tmp_path / "p1.toml", tmp_path / "run.h5", tmp_path / "out"
    _ok(["plan", "new", "p1", "--out", plan, *P1_SHORT])
    # who runs must be named once the records have users
    refused = runner.invoke(app, ["run", str(plan), "--station", "sim", "--out",
                                  str(tmp_path / "x.h5"), "--yes", "--db", db])
    assert refused.exit_code == 2 and refused.output.startswith("error: ")
    ran = _ok(["run", plan, "--station", "sim", "--out", rec, "--yes", "--db", db,
               "--operator", "Oli Operator", "--customer", "Acme Robotics GmbH"])
    (run_id,) = re.findall(r"recorded run (\d+)", ran)
    done = runner.invoke(app, ["calibrate", str(rec), "--out", str(out), "--db", db, "--user",
                               "OO"])
    assert done.exit_code in (0, 1) and "Traceback" not in done.output, done.output
    text = " ".join(done.output.split())
    # the result joins the run that made the recording: no second run
    (result_id, linked_run) = re.findall(r"recorded result\(s\) (\d+) in run (\d+)", text)[0]
    assert linked_run == run_id
    draft_pages, draft = _pdf_text(out / "run.IMU-0001.p1.report.pdf")
    (rid,) = set(re.findall(r"IMUCAL-P1-IMU-0001-[0-9a-f]{12}", draft))
    assert all("DRAFT" in p for p in draft_pages)
    # the operator cannot approve their own calibration; the reviewer can
    own = runner.invoke(app, ["records", "review", result_id, "--decision", "approve",
                              "--user", "Oli Operator", "--db", db])
    assert own.exit_code == 2 and own.output.startswith("error: ") and "Traceback" not in own.output
    assert "operator" in own.output
    _ok(["records", "review", result_id, "--decision", "approve", "--comment",
         "checked against the plan", "--user", "Rae Reviewer", "--db", db])
    certificate = tmp_path / "certificate"
    _ok(["report", "--run", run_id, "--db", db, "--out", certificate])
    (pdf,) = sorted(certificate.glob("*.pdf"))
    pages, released = _pdf_text(pdf)
    assert not any("DRAFT" in p for p in pages)
    for n, page in enumerate(pages, start=1):
        assert rid in page and f"page {n} of {len(pages)}" in page
    for fact in ("T-4711", "DKD-2026-042", "Oli Operator", "Rae Reviewer", "Acme Robotics GmbH",
                 "The results relate only to the item calibrated", "not traceable",
                 "Type A", "Type B", "U (k = 2)", date.today().isoformat()):
        assert fact.lower() in released.lower(), fact
    assert re.search(r"Decision: (PASS|FAIL)", released)
    # the records rows: one run, its operator, the result with the reviewer's approval
    shown = json.loads(_ok(["records", "show", result_id, "--json", "--db", db]))
    assert shown["run"]["run_id"] == int(run_id) and shown["run"]["operator"] == "Oli Operator"
    assert [(r["reviewer"], r["approved"]) for r in shown["reviews"]] == [
        ("Rae Reviewer", True)]
    assert "intact" in _ok(["records", "verify", "--db", db])
