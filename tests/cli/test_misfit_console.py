"""A misfit is visible on the console: the default g-sensitivity run (docs/g-sensitivity.md) is
a model misfit on all three gyros (bias instability makes the position means scatter beyond
their white-noise σ); the table's σ are the Birge-scaled ones and each fit's χ²/ν is printed."""

from __future__ import annotations

import csv
import json
import math

from typer.testing import CliRunner

from imucalib.cli import app

runner = CliRunner()


def test_the_default_g_sensitivity_run_prints_its_misfit(tmp_path):
    plan, rec = tmp_path / "g.toml", tmp_path / "g.h5"
    assert runner.invoke(app, ["plan", "new", "g-sensitivity", "--out", str(plan)]).exit_code == 0
    done = runner.invoke(app, ["run", str(plan), "--station", "sim", "--out", str(rec), "--yes",
                               "-q"])
    assert done.exit_code == 0, done.output
    res = runner.invoke(app, ["calibrate", str(rec), "--out", str(tmp_path), "--no-record"],
                        terminal_width=400)
    assert res.exit_code == 0, res.output
    lines = [ln for ln in res.output.splitlines() if "χ²/ν =" in ln]
    assert [ln.split(":")[0] for ln in lines] == ["gyro x", "gyro y", "gyro z"]
    assert all("MODEL MISFIT" in ln for ln in lines), lines
    report = json.loads((tmp_path / "g.IMU-0001.g-sensitivity.report.json").read_text())
    scale = {q["group"]: q["sigma_scale"] for q in report["fit_quality"]}
    assert all(s > 1.5 for s in scale.values()), scale
    with (tmp_path / "g.IMU-0001.g-sensitivity.parameters.csv").open() as fh:
        rows = {r["parameter"]: r for r in csv.DictReader(fh)}
    # the reported σ are the Birge-scaled ones: the console shows them in °/h
    sigma_dph = float(rows["gyro_bias_x"]["std_uncertainty"]) / (math.pi / 180 / 3600)
    row = next(ln for ln in res.output.splitlines() if "gyro_bias_x" in ln)
    cells = [c.strip() for c in row.split("│") if c.strip()]
    assert cells[3] == "°/h" and math.isclose(float(cells[2]), sigma_dph, rel_tol=0.05)
