"""The tumble from the command line: plan new, run on the twin, calibrate (docs/tumble.md)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.plan import load_plan

runner = CliRunner()


def test_plan_new_run_and_calibrate(tmp_path: Path) -> None:
    result = runner.invoke(app, ["plan", "new", "tumble", "--out", str(tmp_path / "t.toml")])
    assert result.exit_code == 0, result.output
    plan = load_plan(tmp_path / "t.toml")
    assert plan.procedure == "tumble" and len(plan.steps) == 42
    # a short plan of the same kind through run and calibrate (8 positions about z, 5 s each)
    result = runner.invoke(app, ["plan", "new", "tumble", "--out", str(tmp_path / "short.toml"),
                                 "--n-positions", "8", "--axes", "z", "--record-s", "5",
                                 "--settle-s", "2", "--sample-rate-hz", "50"])
    assert result.exit_code == 0, result.output
    result = runner.invoke(app, ["run", str(tmp_path / "short.toml"), "--station", "sim",
                                 "--out", str(tmp_path / "t.h5"), "--yes"])
    assert result.exit_code == 0, result.output
    result = runner.invoke(app, ["calibrate", str(tmp_path / "t.h5"), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    # the console shows every estimate with its uncertainty, then the (absent) decision
    assert "delta_x_head_z" in result.output and "std. uncertainty" in result.output
    assert "no decision" in result.output.lower()  # NO DECISION (the tumble has no limits)
    report = json.loads((tmp_path / "t.IMU-0001.tumble.report.json").read_text())
    assert report["procedure"] == "tumble"
    assert [a["head_axis"] for a in report["accelerometers"]] == ["z", "z"]
    assert report["accelerometers"][0]["coefficients"] == ["K0", "K1", "delta", "K2", "Kip",
                                                           "K3"]
    with (tmp_path / "t.IMU-0001.tumble.parameters.csv").open() as f:
        rows = {r["parameter"]: r for r in csv.DictReader(f)}
    assert rows["delta_x_head_z"]["unit"] == "rad"
    assert {"accel_bias_x", "accel_M_xx", "accel_M_xy", "accel_M_yx", "accel_K2_y"} <= set(rows)
