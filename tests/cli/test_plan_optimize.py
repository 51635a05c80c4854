"""``imucalib plan optimize p1`` (docs/test-design.md, "The optimiser (P1)")."""

from __future__ import annotations

import re

import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.plan import load_plan
from imucalib.procedures.p1.predict import predict_p1
from imucalib.report.console import display_unit

runner = CliRunner()


@pytest.fixture(scope="module")
def optimized(tmp_path_factory):
    out = tmp_path_factory.mktemp("opt") / "p1-opt.toml"
    result = runner.invoke(app, ["plan", "optimize", "p1", "--target-default", "--coarse",
                                 "--out", str(out)])
    return out, result


def test_writes_a_valid_plan_and_prints_the_comparison(optimized):
    out, result = optimized
    assert result.exit_code == 0, result.output
    text = result.stdout
    assert "default plan (4.60 h) vs optimised" in text
    assert re.search(r"station time: default 16,549 s \(4\.60 h\), optimised", text)
    assert "worst σ/target: default 1.000, optimised" in text
    check = runner.invoke(app, ["plan", "validate", str(out)])
    assert check.exit_code == 0 and "valid plan" in check.stdout


def test_predict_on_the_written_plan_reproduces_the_printed_sigma(optimized):
    out, result = optimized
    printed = {}
    for line in result.stdout.splitlines():
        cells = [c.strip() for c in line.split("│") if c.strip()]
        if len(cells) == 6 and cells[0].startswith(("accel_", "gyro_")):
            printed[cells[0]] = cells[3]
    prediction = predict_p1(load_plan(out))
    assert len(printed) == len(prediction.parameters) == 33
    for p in prediction.parameters:
        _, scale = display_unit(p.name, p.unit)
        assert printed[p.name] == f"{p.predicted_std / scale:.3g}"


def test_errors_are_one_line_exit_2(tmp_path):
    out = str(tmp_path / "x.toml")
    cases = [
        (["--target", "gyro_bias=1e-12", "--time-budget", "0.1"], "no P1 plan fits within 0.10 h"),
        (["--target", "nope=1"], "names no P1 parameter"),
        (["--target-default", "--target-from-spec"], "give one of --target-default"),
        (["--criterion", "D"], "criterion D needs a time budget"),
    ]
    for args, message in cases:
        result = runner.invoke(app, ["plan", "optimize", "p1", "--out", out, *args])
        assert result.exit_code == 2, result.output
        assert result.stderr.startswith("error: ") and message in result.stderr
        assert result.stderr.count("\n") == 1 and "Traceback" not in result.output
    result = runner.invoke(app, ["plan", "optimize", "allan", "--out", out])
    assert result.exit_code == 2
    assert result.stderr == "error: the optimiser is not available for procedure allan yet\n"
