"""`imucalib calibrate field DATA` on real-format logs the twin writes (docs/field.md)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.models.result import CalibrationResult
from imucalib.sim import handheld_session, write_session_csv

from ..procedures._field_twin import field_truth

runner = CliRunner()


def test_a_raw_count_log_is_calibrated_and_corrected_end_to_end(tmp_path: Path):
    s = handheld_session("consumer", seed=41, noise="white")
    written = write_session_csv(s, tmp_path / "mpu.csv", layout="counts")
    args = list(written.cli_args)
    out = tmp_path / "out"
    res = runner.invoke(app, ["calibrate", "field", str(written.path), "--latitude",
                              str(s.site.latitude_deg), "-o", str(out), *args])
    assert res.exit_code == 0, res.output
    assert "gyro (rotations): χ²/ν" in res.output and "6 full turns" in res.output
    result = CalibrationResult.load(out / "mpu.IMU.field.result.json")
    assert result.procedure == "field" and result.has_triad("gyro")
    truth = field_truth(s.model)
    std = result.std(scaled=True)
    z = {n: (result.value(n) - truth[n]) / std[n] for n in result.param_names
         if n in truth and std[n] > 0}
    assert len(z) == 33 and max(abs(v) for v in z.values()) < 4.0
    report = json.loads((out / "mpu.IMU.field.report.json").read_text(encoding="utf-8"))
    assert report["accel_form"] == "gravity-norm" and len(report["poses"]) == 25
    assert (out / "mpu.IMU.field.parameters.csv").read_text(encoding="utf-8").startswith(
        "parameter,value,std_uncertainty,unit,std_noise\n")
    # its report (the default PDF): the field process with every fit's χ²/ν, field traceability
    from pypdf import PdfReader

    text = " ".join(" ".join(p.extract_text() for p in
                             PdfReader(str(out / "mpu.IMU.field.report.pdf")).pages).split())
    assert "Procedure field: calibration without equipment" in text and "(docs/field.md)" in text
    for q in report["fit_quality"]:
        assert f"{q['group']}: χ²/ν = {q['reduced_chi2']:.3g}" in text
    assert "a field calibration by hand uses no rotation table" in text
    assert "gyro_M_xy" in text and "U (k = 2)" in text
    # the C99 runtime of the result compiles as firmware would build it (docs/c-runtime.md)
    import shutil
    import subprocess

    res = runner.invoke(app, ["export", str(out / "mpu.IMU.field.result.json"), "--format",
                              "c-runtime", "-o", str(tmp_path / "fw")])
    assert res.exit_code == 0, res.output
    folder = tmp_path / "fw" / "mpu.IMU.field.c"
    cc = shutil.which("cc")
    assert cc, "a C compiler (cc) is needed"
    done = subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-c",
                           str(folder / "imucalib_runtime.c"), "-o", str(tmp_path / "rt.o")],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert "gyro" in (folder / "imucal_params.h").read_text(encoding="utf-8")
    # the same import options correct the log: at rest the corrected norm is local g
    corrected = tmp_path / "corrected.csv"
    res = runner.invoke(app, ["apply", str(out / "mpu.IMU.field.result.json"),
                              str(written.path), "-o", str(corrected), *args])
    assert res.exit_code == 0, res.output
    df = pd.read_csv(corrected)
    t = df.iloc[:, 0].to_numpy()
    accel = df.iloc[:, 4:7].to_numpy()
    raw_err, fixed_err = [], []
    raw = s.accel_mps2
    for p in s.statics:
        keep = (t > p.start_time_s + 0.5) & (t < p.stop_time_s - 0.5)
        fixed_err.append(np.linalg.norm(accel[keep].mean(axis=0)) - res_g(report))
        raw_err.append(np.linalg.norm(raw[keep].mean(axis=0)) - res_g(report))
    assert np.sqrt(np.mean(np.square(fixed_err))) < 0.1 * np.sqrt(np.mean(np.square(raw_err)))


def res_g(report: dict) -> float:
    return float(report["gravity_mps2"])


def test_a_vendor_csv_in_degrees_and_g_with_its_own_names(tmp_path: Path):
    s = handheld_session("tactical", seed=42, noise="white")
    path = tmp_path / "vendor.csv"
    frame = pd.DataFrame({"Time [ms]": s.time_s * 1e3,
                          **{f"Gyr{a.upper()}": np.degrees(s.gyro_rps[:, i])
                             for i, a in enumerate("xyz")},
                          **{f"Acc{a.upper()}": s.accel_mps2[:, i] / 9.80665
                             for i, a in enumerate("xyz")}})
    frame.to_csv(path, index=False)
    res = runner.invoke(app, ["calibrate", "field", str(path), "--imu", "SN-42", "-o",
                              str(tmp_path), "--column-map",
                              "t=Time [ms],gx=GyrX,gy=GyrY,gz=GyrZ,ax=AccX,ay=AccY,az=AccZ",
                              "--units", "t=ms", "--gyro-unit", "deg/s", "--accel-unit", "g",
                              "--gyro-form", "turns", "--gravity", "9.80665"])
    assert res.exit_code == 0, res.output
    result = CalibrationResult.load(tmp_path / "vendor.SN-42.field.result.json")
    assert result.sensor_id == "SN-42"
    assert "known-angle turns" in res.output


def test_bad_field_inputs_exit_2_with_one_line(tmp_path: Path):
    res = runner.invoke(app, ["calibrate", "field"])
    assert res.exit_code == 2 and "needs the data" in res.output
    res = runner.invoke(app, ["calibrate", "field", str(tmp_path / "none.csv")])
    assert res.exit_code == 2 and "no such file" in res.output
    gyro_only = tmp_path / "gyro.csv"
    pd.DataFrame({"time_s": np.arange(50) * 0.01, "gyro_x_rps": 0.0, "gyro_y_rps": 0.0,
                  "gyro_z_rps": 0.0}).to_csv(gyro_only, index=False)
    res = runner.invoke(app, ["calibrate", "field", str(gyro_only)])
    assert res.exit_code == 2 and "accelerometer" in res.output
    assert "Traceback" not in res.output
    csv_without_procedure = runner.invoke(app, ["calibrate", str(gyro_only)])
    assert csv_without_procedure.exit_code == 2
    assert "imucalib calibrate field DATA" in csv_without_procedure.output
    res = runner.invoke(app, ["calibrate", "p1", str(gyro_only)])
    assert res.exit_code == 2 and "analyses a Recording" in res.output


def test_a_serial_with_a_slash_names_files_not_folders(tmp_path: Path):
    s = handheld_session("tactical", seed=43, noise="white")
    written = write_session_csv(s, tmp_path / "u.csv", layout="counts")
    res = runner.invoke(app, ["calibrate", "field", str(written.path), "--imu", "SN/42",
                              "--no-record", "-o", str(tmp_path), *written.cli_args])
    assert res.exit_code == 0, res.output
    result = tmp_path / "u.SN_42.field.result.json"
    assert CalibrationResult.load(result).sensor_id == "SN/42"
    res = runner.invoke(app, ["export", str(result), "--format", "ros-yaml", "-o",
                              str(tmp_path / "x")])
    assert res.exit_code == 0, res.output


def test_the_accelerometer_floor_option_takes_a_number_or_auto(tmp_path: Path):
    res = runner.invoke(app, ["calibrate", "field", str(tmp_path / "none.csv"),
                              "--accel-instability-ug", "lots"])
    assert res.exit_code == 2 and "must be a number of µg or 'auto'; got 'lots'" in res.output
    res = runner.invoke(app, ["calibrate", "field", str(tmp_path / "none.csv"),
                              "--accel-instability-ug", "auto"])
    assert res.exit_code == 2 and "no such file" in res.output  # 'auto' itself accepted
