"""`imucalib records …` and the recording by default of `run` and `calibrate` (docs/records.md)."""

from __future__ import annotations

import json
from datetime import date, timedelta
from pathlib import Path

import h5py
import numpy as np
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.models.result import CalibrationResult
from imucalib.sim import handheld_session, write_session_csv

runner = CliRunner()


def _calibrate(tmp_path: Path, db: str, seed: int, name: str) -> Path:
    s = handheld_session("tactical", seed=seed, noise="white")
    written = write_session_csv(s, tmp_path / f"{name}.csv", layout="counts")
    res = runner.invoke(app, ["calibrate", "field", str(written.path), "--imu", "SN-7",
                              "--db", db, "-o", str(tmp_path / name), *written.cli_args])
    assert res.exit_code == 0, res.output
    assert "recorded run" in res.output and db in " ".join(res.output.split())
    return tmp_path / name / f"{name}.SN-7.field.result.json"


def test_calibrations_are_recorded_queried_reviewed_amended_verified_and_backed_up(tmp_path):
    db = str(tmp_path / "lab.db")
    first = _calibrate(tmp_path, db, 71, "jan")
    _calibrate(tmp_path, db, 72, "feb")
    res = runner.invoke(app, ["records", "history", "SN-7", "--db", db, "--json"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.output)
    assert [r["procedure"] for r in rows] == ["field", "field"]
    res = runner.invoke(app, ["records", "drift", "SN-7", "accel_bias_x", "--db", db,
                              "--json", "--figure", str(tmp_path / "drift.png")])
    assert res.exit_code == 0, res.output
    points = json.loads(res.output)
    assert len(points) == 2 and (tmp_path / "drift.png").stat().st_size > 1000
    cal = CalibrationResult.load(first)
    assert points[0]["value"] == cal.value("accel_bias_x")
    # without --json: in the display unit of a bias (µg), as every console shows it
    res = runner.invoke(app, ["records", "drift", "SN-7", "accel_bias_x", "--db", db],
                        terminal_width=200)
    assert res.exit_code == 0, res.output
    ug = cal.value("accel_bias_x") / (1e-6 * 9.80665)
    first_row = next(line for line in res.output.splitlines() if line.count("│") >= 5)
    assert "µg" in first_row and f"{ug:+.0f}"[:3] in first_row.replace(" ", "")
    first_id = rows[0]["result_id"]
    res = runner.invoke(app, ["records", "review", str(first_id), "--user", "A. Auditor",
                              "--decision", "approve", "--comment", "ok", "--db", db])
    assert res.exit_code == 0 and "approved by A. Auditor" in res.output
    # the certificate of that result carries its review (imucalib report, docs/reporting.md)
    import pypdf

    pdf = tmp_path / "jan.report.pdf"
    res = runner.invoke(app, ["report", str(first), "--result-id", str(first_id), "--db", db,
                              "-o", str(pdf)])
    assert res.exit_code == 0, res.output
    text = " ".join(page.extract_text() for page in pypdf.PdfReader(pdf).pages)
    flat = " ".join(text.split())
    assert "A. Auditor" in text and f"records run 1, result {first_id}" in flat
    assert "uses no rotation table" in text                # a field calibration's references
    res = runner.invoke(app, ["records", "amend", str(first_id), str(first), "--reason",
                              "re-analysed", "--db", db])
    assert res.exit_code == 0, res.output
    history = json.loads(runner.invoke(app, ["records", "history", "SN-7", "--db", db,
                                             "--json"]).output)
    assert len(history) == 3
    assert any(h["replaces"] == first_id for h in history)
    assert any(h["result_id"] == first_id and h["replaced_by"] for h in history)
    res = runner.invoke(app, ["records", "verify", "--db", db])
    assert res.exit_code == 0 and "intact" in res.output
    # backup to two places, then restore into a fresh database, which verifies
    res = runner.invoke(app, ["records", "backup", str(tmp_path / "b1"), str(tmp_path / "b2"),
                              "--db", db])
    assert res.exit_code == 0, res.output
    assert res.output.count("verified") == 2
    restored = str(tmp_path / "restored.db")
    res = runner.invoke(app, ["records", "restore", str(tmp_path / "b1"), "--db", restored])
    assert res.exit_code == 0 and "verify" in res.output, res.output
    # a deleted last row is caught by the anchor log, and against the heads a backup kept
    import sqlite3

    with sqlite3.connect(db) as conn:
        conn.execute("DELETE FROM reviews WHERE seq = (SELECT MAX(seq) FROM reviews)")
    res = runner.invoke(app, ["records", "verify", "--db", db], terminal_width=200)
    assert res.exit_code == 1 and "anchor log" in res.output, res.output
    res = runner.invoke(app, ["records", "verify", "--db", db, "--anchors",
                              str(tmp_path / "b2" / "heads.json")])
    assert res.exit_code == 1 and "reviews" in res.output
    # an edited row is named

    with sqlite3.connect(db) as conn:
        conn.execute("UPDATE result_parameters SET value = value + 1 WHERE rowid = 1")
    res = runner.invoke(app, ["records", "verify", "--db", db, "--json"])
    assert res.exit_code == 1
    assert any(p["table"] == "results" for p in json.loads(res.output))


def test_a_run_is_recorded_and_overdue_equipment_refused_unless_overridden(tmp_path: Path):
    db = str(tmp_path / "lab.db")
    plan = tmp_path / "field.toml"
    res = runner.invoke(app, ["plan", "new", "field", "--n-poses", "6", "--no-full-turns",
                              "-o", str(plan)])
    assert res.exit_code == 0, res.output
    yesterday = (date.today() - timedelta(days=1)).isoformat()
    res = runner.invoke(app, ["records", "add-equipment", "--kind", "rate-table", "--model",
                              "AC1120S", "--serial", "T-9", "--certificate", "C-17",
                              "--due-on", yesterday, "--db", db])
    assert res.exit_code == 0, res.output
    out = tmp_path / "run.h5"
    res = runner.invoke(app, ["run", str(plan), "--station", "sim", "--yes", "-o", str(out),
                              "--db", db])
    assert res.exit_code == 2 and "overdue" in res.output and "C-17" in res.output
    assert not out.exists()
    res = runner.invoke(app, ["run", str(plan), "--station", "sim", "--yes", "-o", str(out),
                              "--db", db, "--override-due", "certificate renewal booked"])
    assert res.exit_code == 0, res.output
    assert "recorded run" in res.output
    res = runner.invoke(app, ["records", "runs", "field", "--db", db, "--json"])
    runs = json.loads(res.output)
    assert len(runs) == 1 and runs[0]["recording_path"] == str(out.resolve())
    res = runner.invoke(app, ["records", "due", "--equipment", "--db", db, "--json"])
    assert [e["certificate"] for e in json.loads(res.output)] == ["C-17"]
    with h5py.File(out, "a") as f:                      # an edited recording is named
        ds = next(iter(f["streams"]["imu"].values()))
        name = next(iter(ds))
        ds[name][0] = np.asarray(ds[name][0]) + 1
    res = runner.invoke(app, ["records", "verify", "--db", db])
    assert res.exit_code == 1 and "recording" in res.output
