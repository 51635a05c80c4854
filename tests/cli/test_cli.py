"""The command line: simulate, scenarios, inspect, export and recover, and their error exits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.io import open_recording

runner = CliRunner()


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    """Render rich tables wide enough that names are not folded, whatever the terminal."""
    from imucalib.cli import _app

    monkeypatch.setattr(_app.console, "width", 240)

SCENARIO = """name = "cli-test"
seed = 9
[table]
kind = "single-axis"
[[imus]]
name = "IMU-7"
grade = "consumer"
sample_rate_hz = 100
drop_probability = 0.01
[[steps]]
kind = "position"
angles_deg = [90]
settle_s = 1
record_s = 2
[[steps]]
kind = "rate"
axis = 0
rate_dps = 90
settle_s = 1
revolutions = 1
"""


@pytest.fixture(scope="module")
def simulated(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("cli")
    scenario = tmp / "s.toml"
    scenario.write_text(SCENARIO, encoding="utf-8")
    out = tmp / "s.h5"
    result = runner.invoke(app, ["simulate", str(scenario), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "wrote" in result.output and "2 steps" in result.output
    return out


def test_simulate_writes_a_recording(simulated):
    with open_recording(simulated) as rec:
        assert [s.kind for s in rec.steps] == ["position", "rate"]
        assert {s.name for s in rec.streams} == {"imu/IMU-7", "table/main"}


def test_simulate_refuses_to_overwrite_then_overwrites(simulated, tmp_path):
    scenario = tmp_path / "s.toml"
    scenario.write_text(SCENARIO, encoding="utf-8")
    result = runner.invoke(app, ["simulate", str(scenario), "--out", str(simulated)])
    assert result.exit_code == 2
    assert "exists" in result.output
    copy = tmp_path / "copy.h5"
    copy.write_bytes(b"x")
    result = runner.invoke(app, ["simulate", str(scenario), "--out", str(copy), "--overwrite",
                                 "--seed", "3"])
    assert result.exit_code == 0, result.output


def test_inspect_summarises_streams_steps_and_gaps(simulated):
    result = runner.invoke(app, ["inspect", str(simulated)])
    assert result.exit_code == 0, result.output
    for text in ("imu/IMU-7", "table/main", "position", "rate", "angle_azimuth_rad"):
        assert text in result.output


def test_export_csv_of_a_step(simulated, tmp_path):
    out = tmp_path / "step0.csv"
    result = runner.invoke(app, ["export", str(simulated), "--stream", "imu/IMU-7",
                                 "--step", "0", "--out", str(out)])
    assert result.exit_code == 0, result.output
    header = out.read_text(encoding="utf-8").splitlines()[0]
    assert "gyro_x_rps" in header
    with open_recording(simulated) as rec:
        step = rec.steps[0]
    times = np.loadtxt(out, delimiter=",", skiprows=2, usecols=0, ndmin=1)
    assert times.min() >= step.valid_start_s and times.max() <= step.valid_end_s


@pytest.mark.parametrize(("args", "message"), [
    (["export", "{f}", "--stream", "imu", "--out", "x.csv"], "DEVICE/UNIT"),
    (["export", "{f}", "--stream", "imu/IMU-7", "--out", "x.txt"], r"\.csv or \.mat"),
    (["inspect", "no-such-file.h5"], "no-such-file.h5"),
    (["simulate", "nonexistent-scenario", "--out", "x.h5"], "neither a built-in"),
])
def test_errors_exit_2_with_a_message(simulated, args, message):
    result = runner.invoke(app, [a.format(f=simulated) for a in args])
    assert result.exit_code == 2
    import re

    assert re.search(message, result.output), result.output


def test_scenarios_lists_the_builtins():
    result = runner.invoke(app, ["scenarios"])
    assert result.exit_code == 0
    for name in ("static-hour", "dual-axis-p1", "chamber-array", "centrifuge"):
        assert name in result.output


def test_recover_a_cleanly_closed_file_copies_it(simulated, tmp_path):
    out = tmp_path / "copy.h5"
    result = runner.invoke(app, ["recover", str(simulated), "--out", str(out)])
    assert result.exit_code == 0, result.output
    with open_recording(out) as rec, open_recording(simulated) as ref:
        assert rec.stream_info("imu", "IMU-7").n_samples == ref.stream_info(
            "imu", "IMU-7").n_samples
