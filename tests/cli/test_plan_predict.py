"""``imucalib plan show PLAN --predict [--json]`` (docs/test-design.md)."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.plan import write_plan
from imucalib.procedures import registry
from imucalib.procedures.p1.plan import generate_p1_plan

runner = CliRunner()


def _plan(folder: Path, **kwargs) -> Path:
    plan = generate_p1_plan(repetitions=1, static_s=60.0, warm_up_s=10.0, **kwargs)
    return write_plan(plan, folder / "plan.toml")


def test_predict_json(tmp_path):
    result = runner.invoke(app, ["plan", "show", str(_plan(tmp_path)), "--predict", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["confounded"] == [] and data["station_time_s"] > 0
    names = [p["name"] for p in data["parameters"]]
    assert names[0] == "accel_bias_x" and "gyro_G_xy" in names and len(names) == 33
    assert all(set(p) == {"name", "predicted_std", "unit"} for p in data["parameters"])


def test_predict_table(tmp_path):
    result = runner.invoke(app, ["plan", "show", str(_plan(tmp_path)), "--predict"])
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "accel_bias_x" in out and "µg" in out and "°/h" in out
    assert "gyro: rank 21 of 21, condition number" in out
    assert "station time with moves and settling" in out


def test_unidentifiable_plan_exits_2_naming_the_confounded(tmp_path):
    result = runner.invoke(app, ["plan", "show", str(_plan(tmp_path, z_rates=False)),
                                 "--predict"])
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    assert result.stderr == ("error: plan 'p1-dual-axis' cannot identify gyro_M_xz, gyro_M_yz, "
                             "gyro_M_zz (confounded)\n")


def test_procedure_without_predict_one_line(tmp_path):
    path = write_plan(registry.get("allan").generate_plan(), tmp_path / "allan.toml")
    result = runner.invoke(app, ["plan", "show", str(path), "--predict"])
    assert result.exit_code == 2
    assert result.stderr == "error: prediction is not available for procedure allan yet\n"
    assert result.stdout == ""


def test_json_without_predict_is_refused(tmp_path):
    result = runner.invoke(app, ["plan", "show", str(_plan(tmp_path)), "--json"])
    assert result.exit_code == 2
    assert result.stderr.startswith("error: --json goes with --predict")
