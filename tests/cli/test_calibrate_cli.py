"""`imucalib plan …`, `imucalib calibrate` and `imucalib apply` from the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.exports.streams import export_csv
from imucalib.models.result import CalibrationResult
from imucalib.plan import load_plan

runner = CliRunner()


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    from imucalib.cli import _app

    monkeypatch.setattr(_app.console, "width", 240)


def test_plan_new_validate_show_and_schema(tmp_path):
    path = tmp_path / "p1.toml"
    result = runner.invoke(app, ["plan", "new", "p1", "--out", str(path), "--repetitions", "1",
                                 "--static-s", "600"])
    assert result.exit_code == 0, result.output
    plan = load_plan(path)
    assert plan.procedure == "p1" and plan.twin is not None
    result = runner.invoke(app, ["plan", "validate", str(path)])
    assert result.exit_code == 0 and "valid plan 'p1-dual-axis'" in result.output
    result = runner.invoke(app, ["plan", "show", str(path)])
    assert result.exit_code == 0
    assert "rep1 X down (pitch -90, roll 0)" in result.output and "steps; at least" in result.output
    schema = tmp_path / "plan.schema.json"
    result = runner.invoke(app, ["plan", "schema", "--out", str(schema)])
    assert result.exit_code == 0
    doc = json.loads(schema.read_text())
    assert doc["title"] == "imucalib test plan" and "steps" in doc["properties"]
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\n[[steps]]\nkind = "rate"\nrate_dps = 9999\nrecord_s = 1\n')
    result = runner.invoke(app, ["plan", "validate", str(bad)])
    assert result.exit_code == 2 and "rate_dps 9999 exceeds limits.max_rate_dps" in result.output
    result = runner.invoke(app, ["plan", "new", "p9", "--out", str(tmp_path / "x.toml")])
    assert result.exit_code == 2 and "unknown procedure 'p9'" in result.output


def test_calibrate_writes_the_result_and_the_report(tactical_run, tmp_path):
    result = runner.invoke(app, ["calibrate", str(tactical_run), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "PASS (simple acceptance" in result.output
    assert "accel_bias_x" in result.output and "repeatability" in result.output
    res_path = tmp_path / f"{tactical_run.stem}.IMU-0001.p1.result.json"
    report = json.loads((tmp_path / f"{tactical_run.stem}.IMU-0001.p1.report.json").read_text())
    res = CalibrationResult.from_json(res_path.read_text())
    assert res.model == "triad" and len(res.param_names) == 33
    assert report["decision"]["passed"] is True
    assert {c["name"] for c in report["checks"]} >= {"accelerometer residuals", "repeatability"}


def test_per_axis_model_fails_its_residual_rule_with_exit_1(consumer_run, tmp_path):
    result = runner.invoke(app, ["calibrate", str(consumer_run), "--model", "per-axis",
                                 "--out", str(tmp_path)])
    assert result.exit_code == 1
    assert "FAIL" in result.output and "accelerometer residuals" in result.output


def test_calibrate_refuses_a_recording_without_a_plan(tmp_path, p1_tools):
    p1_tools.write_planless_recording(tmp_path / "s.h5")
    result = runner.invoke(app, ["calibrate", str(tmp_path / "s.h5")])
    assert result.exit_code == 2 and "holds no plan" in result.output


def test_apply_to_a_recording_and_to_a_csv(tactical_run, tmp_path):
    runner.invoke(app, ["calibrate", str(tactical_run), "--out", str(tmp_path)])
    res_path = tmp_path / f"{tactical_run.stem}.IMU-0001.p1.result.json"
    out = tmp_path / "corrected.csv"
    result = runner.invoke(app, ["apply", str(res_path), str(tactical_run), "--out", str(out)])
    assert result.exit_code == 0, result.output
    header = out.read_text().splitlines()[0]
    assert header.startswith("time_s [s],") and "accel_z_mps2 [m/s^2]" in header
    # a level window corrected reads g on z and ~0 on x, y (a few hundred µg before)
    from imucalib.io import open_recording

    with open_recording(tactical_run) as rec:
        step = next(s for s in rec.steps if s.label.endswith("Z up (pitch 0, roll 0)"))
        g = rec.metadata["latitude_deg"] and 9.80619776937321
    data = np.genfromtxt(out, delimiter=",", skip_header=1)
    sel = (data[:, 0] >= step.valid_start_s) & (data[:, 0] < step.valid_end_s)
    cols = header.split(",")
    ax, az = cols.index("accel_x_mps2 [m/s^2]"), cols.index("accel_z_mps2 [m/s^2]")
    assert abs(data[sel, ax].mean()) < 1e-4 * 9.8 and abs(data[sel, az].mean() - g) < 1e-4 * 9.8
    # the same through a CSV export
    csv_in = tmp_path / "raw.csv"
    export_csv(tactical_run, "imu", "IMU-0001", csv_in, step=step.index)
    out2 = tmp_path / "corrected2.csv"
    result = runner.invoke(app, ["apply", str(res_path), str(csv_in), "--out", str(out2)])
    assert result.exit_code == 0, result.output
    data2 = np.genfromtxt(out2, delimiter=",", skip_header=1)
    np.testing.assert_allclose(data2[:, az].mean(), data[sel, az].mean(), rtol=1e-9)


def test_apply_refuses_a_bad_result_file(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "nope"}')
    result = runner.invoke(app, ["apply", str(bad), str(tmp_path / "x.csv"), "--out",
                                 str(tmp_path / "y.csv")])
    assert result.exit_code == 2 and "not an imucalib calibration result" in result.output
