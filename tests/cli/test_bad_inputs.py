"""Bad inputs at the command line: one error line on stderr, exit code 2, never a traceback."""

from __future__ import annotations

import json
from collections import namedtuple
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.models.result import CalibrationResult, triad_parameter_names
from imucalib.plan import budget as budget_module

runner = CliRunner()
GYRO = "gyro_x_rps,gyro_y_rps,gyro_z_rps"


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    from imucalib.cli import _app

    monkeypatch.setattr(_app.console, "width", 240)


def refused(args: list[str], message: str) -> None:
    result = runner.invoke(app, [str(a) for a in args])
    assert result.exit_code == 2, (result.output, result.exception)
    assert "Traceback" not in result.output
    assert result.stderr == f"error: {message}\n"


def result_file(tmp_path: Path) -> Path:
    names = (*triad_parameter_names("accel", "per-axis"),
             *triad_parameter_names("gyro", "per-axis"))
    res = CalibrationResult(sensor_id="IMU-7", procedure="p1", model="per-axis",
                            param_names=names, values=np.r_[np.ones(3), np.zeros(3),
                                                            np.ones(3), np.zeros(3)],
                            covariance=np.eye(12) * 1e-10, units=dict.fromkeys(names, "1"))
    path = tmp_path / "r.json"
    path.write_text(res.to_json(), encoding="utf-8")
    return path


def csv_file(tmp_path: Path, text: str, name: str = "d.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


GOOD_CSV = f"time_s,{GYRO}\n" + "".join(f"{i / 100},0,0,{i % 3}\n" for i in range(10))


def test_a_header_only_csv(tmp_path):
    data = csv_file(tmp_path, f"time_s,{GYRO}\n")
    message = f"{data}: no data rows after the header; expected at least one row of numbers"
    refused(["segments", data], message)
    refused(["apply", result_file(tmp_path), data, "--out", tmp_path / "o.csv"], message)
    assert not (tmp_path / "o.csv").exists()


def test_duplicated_and_unknown_units_in_the_header(tmp_path):
    data = csv_file(tmp_path, f"time_s,time_s [furlong],{GYRO}\n0,0,0,0,0\n")
    refused(["segments", data], f"{data}: column 'time_s [furlong]' has an unknown unit "
                                "'furlong'; time_s is a time, expected one of s, ms, us, ns, "
                                "min, h")
    data = csv_file(tmp_path, f"time_s,{GYRO},gyro_x_rps [deg/h]\n0,0,0,0,0\n")
    refused(["apply", result_file(tmp_path), data, "--out", tmp_path / "o.csv"],
            f"{data}: columns 'gyro_x_rps' and 'gyro_x_rps [deg/h]' (header fields 2 and 5) "
            "both hold gyro_x_rps; expected one column per quantity")


@pytest.mark.parametrize(("content", "message"), [
    (b"\xff\xfe\x00{}", "calibration result {p} is not UTF-8 text: byte 0xff at offset 0 cannot "
                        "be decoded (expected the JSON `imucalib calibrate` writes)"),
    (b"{not json", "calibration result {p} is not valid JSON: Expecting property name enclosed "
                   "in double quotes: line 1 column 2 (char 1)"),
    (b'{"format": "imucalib-calibration-result", "format_version": 7}',
     "calibration result {p}: format_version 7 is not supported; this imucalib reads versions "
     "1..4 (a newer version needs a newer imucalib)"),
])
def test_bad_result_files(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_bytes(content)
    data = csv_file(tmp_path, GOOD_CSV)
    refused(["apply", path, data, "--out", tmp_path / "o.csv"], message.format(p=path))


def test_result_fields_are_named(tmp_path):
    doc = json.loads(result_file(tmp_path).read_text())
    doc["parameters"][0]["value"] = float("nan")
    path = tmp_path / "nan.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    refused(["apply", path, csv_file(tmp_path, GOOD_CSV), "--out", tmp_path / "o.csv"],
            f"calibration result {path}: field 'parameters[0].value': expected a finite number; "
            "got NaN")


def test_apply_refuses_to_overwrite_its_input_and_corrects_a_good_csv(tmp_path):
    res, data = result_file(tmp_path), csv_file(tmp_path, GOOD_CSV)
    refused(["apply", res, data, "--out", data],
            f"--out {data} is the input file {data}; write the corrected data to another file")
    assert data.read_text() == GOOD_CSV
    result = runner.invoke(app, ["apply", str(res), str(data), "--out", str(tmp_path / "o.csv")])
    assert result.exit_code == 0, result.output
    assert "wrote" in result.output and "10 corrected samples" in result.output


def test_segments_window_longer_than_any_record(tmp_path):
    data = csv_file(tmp_path, GOOD_CSV)
    refused(["segments", data, "--window-s", "1e308"],
            "the record must be at least three windows long; got 10 samples, 0.09 s, for "
            "`window_s` = 1e+308 s")


def plan_file(tmp_path: Path, **step: object) -> Path:
    path = tmp_path / "p.toml"
    path.write_text(tomli_w.dumps({"name": "p", "steps": [{"kind": "position",
                                                           "angles_deg": [0.0, 0.0], **step}]}),
                    encoding="utf-8")
    return path


def test_plan_bounds_and_estimate(tmp_path):
    path = plan_file(tmp_path, settle_s=1e308)
    refused(["plan", "validate", path], f"invalid plan {path}: steps.0.position.settle_s: "
                                        "Input should be less than or equal to 3600 (got 1e+308)")
    path = plan_file(tmp_path, settle_s=30.0, record_s=600.0)
    result = runner.invoke(app, ["plan", "validate", str(path)])
    assert result.exit_code == 0, result.output
    assert "recording over 631 s (for 1 IMU at the plan's least acquisition rate, 100 Hz; a " \
           "station's IMUs and rates change it): ≈ 10.6 MB of disk at the most (the file as " \
           "written, then its compressed copy at close), ≈ 3.94 MB once closed (gzip)" \
           in " ".join(result.output.split())
    result = runner.invoke(app, ["plan", "show", str(path)])
    shown = " ".join(result.output.split())
    assert result.exit_code == 0 and "≈ 10.6 MB of disk at the most" in shown
    assert "≈ 3.94 MB once closed (gzip)" in shown


def test_plan_new_refuses_options_beyond_the_bounds(tmp_path):
    out = tmp_path / "p.toml"
    result = runner.invoke(app, ["plan", "new", "p1", "--out", str(out), "--static-s", "1e308"])
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert "--static-s takes a number in [0, 604800] [s]; got '1e308'" in result.output
    assert not out.exists()
    refused(["plan", "new", "allan", "--out", out, "--temperatures", "1e9"],
            "--temperatures takes numbers in [-100, 200] separated by commas [°C]; got '1e9'")


SCENARIO = {"name": "s", "imus": [{"name": "A", "sample_rate_hz": 100.0}],
            "steps": [{"kind": "static", "duration_s": 3000.0}]}


def test_simulate_refuses_out_of_bounds_scenarios(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(tomli_w.dumps({**SCENARIO, "table": {"kind": "single-axis"}, "steps": [
        {"kind": "position", "angles_deg": [0.0], "settle_s": 1e308}]}), encoding="utf-8")
    refused(["simulate", path, "--out", tmp_path / "s.h5"],
            f"invalid scenario {path}: steps.0.position.settle_s: Input should be less than or "
            "equal to 3600 (got 1e+308)")
    refused(["simulate", "static-hour", "--seed", str(2**64), "--out", tmp_path / "s.h5"],
            "invalid scenario static-hour: seed: Input should be less than 9223372036854775808 "
            "(got 18446744073709551616)")
    assert not (tmp_path / "s.h5").exists()


Usage = namedtuple("Usage", "total used free")


def test_simulate_refuses_a_file_larger_than_the_free_space(tmp_path, monkeypatch):
    path = tmp_path / "s.toml"
    path.write_text(tomli_w.dumps(SCENARIO), encoding="utf-8")
    monkeypatch.setattr(budget_module.shutil, "disk_usage", lambda p: Usage(0, 0, 12_000_000))
    refused(["simulate", path, "--out", tmp_path / "s.h5"],
            f"the recording of scenario 's' needs about 29.3 MB but {tmp_path} has only 12 MB "
            "free; free some space, write elsewhere (--out) or shorten the steps")
    assert not (tmp_path / "s.h5").exists()
    monkeypatch.setattr(budget_module.shutil, "disk_usage", lambda p: Usage(0, 0, 10**10))
    result = runner.invoke(app, ["simulate", str(path), "--out", str(tmp_path / "s.h5")])
    assert result.exit_code == 0, result.output
