"""``imucalib segments``: static and rotating intervals of data without step records."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib import units
from imucalib.cli import app
from imucalib.io import open_recording

runner = CliRunner()

SCENARIO = """name = "segments-test"
seed = 4
[table]
kind = "single-axis"
[[imus]]
name = "IMU-3"
grade = "tactical"
sample_rate_hz = 100
[[steps]]
kind = "position"
angles_deg = [0]
settle_s = 1
record_s = 6
[[steps]]
kind = "rate"
axis = 0
rate_dps = 60
settle_s = 3
revolutions = 2
[[steps]]
kind = "position"
angles_deg = [90]
settle_s = 3
record_s = 6
"""


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    from imucalib.cli import _app

    monkeypatch.setattr(_app.console, "width", 240)


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("segments")
    scenario = tmp / "s.toml"
    scenario.write_text(SCENARIO, encoding="utf-8")
    out = tmp / "s.h5"
    result = runner.invoke(app, ["simulate", str(scenario), "--out", str(out)])
    assert result.exit_code == 0, result.output
    return out


def _check(doc: dict, rec_path: Path) -> None:
    segs = doc["segments"]
    assert [s["kind"] for s in segs] == ["static", "rotating", "static"]
    with open_recording(rec_path) as rec:
        steps = rec.steps
    # each segment holds its step's valid window (the detector trims half a window, the
    # settling and the stop ramp)
    for seg, step in zip(segs, steps, strict=True):
        assert seg["start_time_s"] <= step.valid_start_s + 0.6
        assert seg["end_time_s"] >= step.valid_end_s - 0.6
    rate = np.linalg.norm(segs[1]["mean_rate_rps"]) / units.DEG_PER_S
    assert rate == pytest.approx(60.0, rel=0.01)
    for seg in (segs[0], segs[2]):
        assert np.linalg.norm(seg["mean_rate_rps"]) < 0.01 * units.DEG_PER_S
        assert np.linalg.norm(seg["mean_specific_force_mps2"]) == pytest.approx(units.G0_MPS2,
                                                                               rel=0.01)


def test_segments_of_a_recording_match_its_steps(recording, tmp_path):
    out = tmp_path / "seg.json"
    result = runner.invoke(app, ["segments", str(recording), "--json", str(out)])
    assert result.exit_code == 0, result.output
    assert "3 segments" in result.output and "rotating" in result.output
    _check(json.loads(out.read_text()), recording)


def test_segments_of_an_exported_csv_equal_those_of_the_recording(recording, tmp_path):
    csv = tmp_path / "imu.csv"
    result = runner.invoke(app, ["export", str(recording), "--stream", "imu/IMU-3", "--out",
                                 str(csv)])
    assert result.exit_code == 0, result.output
    out = tmp_path / "seg.json"
    result = runner.invoke(app, ["segments", str(csv), "--json", str(out)])
    assert result.exit_code == 0, result.output
    doc = json.loads(out.read_text())
    _check(doc, recording)
    ref = tmp_path / "ref.json"
    runner.invoke(app, ["segments", str(recording), "--json", str(ref)])
    assert [(s["start_index"], s["stop_index"]) for s in doc["segments"]] == [
        (s["start_index"], s["stop_index"]) for s in json.loads(ref.read_text())["segments"]]


@pytest.mark.parametrize(("content", "args", "message"), [
    ("time_s,accel_x_mps2\n0,1\n", [], "needs the gyro columns"),
    ("time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps\n0,0,0,0\n0.01,0,0,0\n", [],
     "at least three windows"),
    ("time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps\n0,0,0,NaN\n0.01,0,0,0\n", [], "finite"),
    ("time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps\n0,0,0,0\n0.01,0,x1,0\n", [],
     "column 'gyro_y_rps' holds a non-numeric value 'x1' at data row 2"),
])
def test_bad_data_is_named(tmp_path, content, args, message):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    result = runner.invoke(app, ["segments", str(path), *args])
    assert result.exit_code == 2, result.output
    assert message in " ".join(result.output.split())


def test_unknown_imu_of_a_recording_is_named(recording):
    result = runner.invoke(app, ["segments", str(recording), "--unit", "IMU-9"])
    assert result.exit_code == 2
    assert "no IMU 'IMU-9'" in result.output and "IMU-3" in result.output


def test_segments_of_a_twin_recording_use_the_counter_time_base(tmp_path):
    """The twin's receive times come in bursts (equal times); segments must still run."""
    from ..conftest import write_planless_recording

    path = write_planless_recording(tmp_path / "rest.h5")
    with open_recording(path) as rec:
        t = rec.read_stream("imu", rec.streams[0].unit).time_s
    assert np.any(np.diff(t) == 0.0)  # what made `segments` refuse the file
    done = CliRunner().invoke(app, ["segments", str(path), "--window-s", "0.2",
                                    "--min-static-s", "0.5"])
    assert done.exit_code == 0, done.output
