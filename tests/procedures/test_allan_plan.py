"""The Allan procedure end to end: plan, twin run, `imucalib calibrate`, outputs, truth."""

from __future__ import annotations

import json
import re

import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import ConfigurationError
from imucalib.io import open_recording
from imucalib.models import ImuModel
from imucalib.plan import load_plan
from imucalib.procedures import generate_allan_plan
from imucalib.procedures.allan.analysis import NoiseCharacterization
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation

runner = CliRunner()


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    from imucalib.cli import _app

    monkeypatch.setattr(_app.console, "width", 240)


def test_plan_structure_and_refusals():
    plan = generate_allan_plan(record_s=1800.0, temperatures_degc=[-10.0, 40.0])
    kinds = [s.kind for s in plan.steps]
    assert kinds == ["operator-check", "warm-up", "soak", "static", "soak", "static"]
    assert plan.procedure == "allan" and plan.twin is not None and plan.twin.chamber.enabled
    assert [s.tags for s in plan.steps if s.kind == "static"] == [("allan", "T-10"),
                                                                  ("allan", "T+40")]
    with pytest.raises(ConfigurationError, match="at least 600 s"):
        generate_allan_plan(record_s=60.0)
    with pytest.raises(ConfigurationError, match="`grade` must be one of"):
        generate_allan_plan(grade="military")


@pytest.mark.slow
def test_allan_run_and_calibrate_recover_the_configured_noise(tmp_path):
    result = runner.invoke(app, ["plan", "new", "allan", "--out", str(tmp_path / "a.toml"),
                                 "--record-s", "1800", "--sample-rate-hz", "100",
                                 "--grade", "tactical", "--seed", "5"])
    assert result.exit_code == 0, result.output
    plan = load_plan(tmp_path / "a.toml")
    plan = plan.model_copy(update={"steps": tuple(
        s.model_copy(update={"duration_s": 60.0}) if s.kind == "warm-up" else s
        for s in plan.steps)})
    assert plan.twin is not None
    station = SimStation(plan.twin)
    rec_path = tmp_path / "allan.h5"
    summary = run_plan(plan, station, rec_path, options=RunOptions(tick_s=5.0,
                                                                   truth=station.truth))
    assert summary.status == "done"
    result = runner.invoke(app, ["calibrate", str(rec_path), "--out", str(tmp_path / "res")])
    assert result.exit_code == 0, result.output
    assert "Angle random walk" in result.output and "Velocity random walk" in result.output
    res = tmp_path / "res"
    char = NoiseCharacterization.load(res / "allan.IMU-0001.allan.json")
    assert len(char.segments) == 1 and char.settings["tau_min_s"] > 0
    kalibr = (res / "allan.IMU-0001.allan.kalibr.yaml").read_text()
    assert "gyroscope_noise_density" in kalibr
    assert re.search(r"update_rate:\s+100\b", kalibr)
    assert "accelerometer_noise_density" in (res / "allan.IMU-0001.allan.openvins.yaml"
                                             ).read_text()
    assert (res / "allan.IMU-0001.allan.table.md").read_text().startswith("|")
    assert len(list((res / "allan.IMU-0001.allan.figures").glob("*.png"))) == 2
    with open_recording(rec_path) as rec:
        truth = ImuModel.from_dict(rec.truth["imu_models"]["IMU-0001"])
    seg = char.segments[0]
    for axis in "xyz":
        for sensor, true_n in (("gyro", truth.gyro_noise.white_density),
                               ("accel", truth.accel_noise.white_density)):
            term = seg.channel(f"{sensor}_{axis}").fit.term("white")
            i = "xyz".index(axis)
            assert abs(term.value_si - true_n[i]) < 4 * term.std_si + 0.01 * true_n[i], (
                sensor, axis, term.value_si / true_n[i])
    report = json.loads((res / "allan.IMU-0001.allan.json").read_text())
    assert report["format_version"] == 1
