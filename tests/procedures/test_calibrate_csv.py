"""Calibrating a CSV with its step file: the same P1 as the planned run it was exported from.

A P1 plan runs on the twin; ``imucalib export`` writes the IMU stream as CSV and the run's steps
as a step file; ``imucalib calibrate CSV --steps FILE`` imports both (the table stream is
reconstructed from the commanded states) and runs P1. The data are the same samples, so the
estimates must agree with the planned run's within one standard uncertainty of the planned run,
parameter by parameter, with a comparable σ. A second import drops every column a vendor log
lacks (counter, receive time, temperature, saturation), keeps the IMU's own timestamps as the
time column, writes the gyro in °/s and the accelerometer in g, and still agrees: the counter
comes from the time column, the units are converted at the door.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.io.opening import open_recording
from imucalib.models.result import CalibrationResult
from imucalib.procedures import generate_p1_plan
from imucalib.procedures.p1.analysis import analyze_p1
from imucalib.sim.scenario import load_scenario

from ..conftest import run_twin

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def planned(tmp_path_factory: pytest.TempPathFactory):
    tmp = tmp_path_factory.mktemp("csv")
    scenario = load_scenario("dual-axis-p1")
    plan = generate_p1_plan(grade="tactical", rates_dps=(-100.0, -50.0, 0.0, 50.0, 100.0),
                            held_out_rates_dps=(75.0,), revolutions=2, static_s=300.0,
                            settle_s=10.0, record_s=10.0, rate_settle_s=10.0, repetitions=1,
                            warm_up_s=10.0, seed=scenario.seed)
    plan = plan.model_copy(update={"twin": scenario.equipment})
    rec = run_twin(plan, tmp / "planned.h5")
    runner = CliRunner()
    done = runner.invoke(app, ["export", str(rec), "--stream", "imu/IMU-0001",
                               "--out", str(tmp / "run.csv"),
                               "--step-file", str(tmp / "steps.toml")])
    assert done.exit_code == 0, done.output
    analysis = analyze_p1(rec)
    # the exit status `calibrate` gives the same data: 0 PASS, 1 FAIL (the twin's IMU has a
    # nonlinear gyro that the triad model leaves out: with the grade's noise its residuals fail)
    return tmp, analysis.result, 0 if analysis.passed else 1


def _agree(result: CalibrationResult, planned: CalibrationResult) -> None:
    assert result.param_names == planned.param_names
    sigma = np.sqrt(np.diag(planned.covariance))
    z = (result.values - planned.values) / sigma
    worst = int(np.argmax(np.abs(z)))
    assert np.all(np.abs(z) <= 1.0), f"{planned.param_names[worst]}: {z[worst]:+.2f}σ apart"
    ratio = np.sqrt(np.diag(result.covariance)) / sigma
    assert np.all((ratio > 0.67) & (ratio < 1.5)), ratio


def test_an_exported_csv_and_its_step_file_calibrate_like_the_planned_run(planned):
    tmp, reference, status = planned
    out = tmp / "from-csv"
    done = CliRunner().invoke(app, ["calibrate", str(tmp / "run.csv"), "--steps",
                                    str(tmp / "steps.toml"), "--out", str(out)])
    assert done.exit_code == status, done.output  # the planned run's decision
    assert "reconstructed" in done.output
    result = CalibrationResult.load(out / "run.imported.IMU-0001.p1.result.json")
    _agree(result, reference)
    with open_recording(out / "run.imported.h5") as rec:
        assert rec.metadata["source"] == "csv-import"
        assert rec.metadata["table_feedback"] == "reconstructed from the step file"
        assert {s.role for s in rec.steps} == {"p1.accel-position", "p1.gyro-bias",
                                               "p1.gyro-rate", "p1.held-out-position",
                                               "p1.held-out-rate"}


def test_a_vendor_style_csv_without_counter_in_other_units_calibrates_alike(planned):
    tmp, reference, _ = planned
    df = pd.read_csv(tmp / "run.csv")
    g0, deg = 9.80665, np.pi / 180.0
    # a vendor log's time is the IMU's own timestamp; its first sample is at the receive time
    offset = df["time_s [s]"].iloc[0] - df["device_time_s [s]"].iloc[0]
    vendor = pd.DataFrame({"time_s [s]": df["device_time_s [s]"] + offset})
    for axis in "xyz":
        vendor[f"gyro_{axis}_rps [deg/s]"] = df[f"gyro_{axis}_rps [rad/s]"] / deg
    for axis in "xyz":
        vendor[f"accel_{axis}_mps2 [g]"] = df[f"accel_{axis}_mps2 [m/s^2]"] / g0
    vendor.to_csv(tmp / "vendor.csv", index=False, float_format="%.17g")
    out = tmp / "from-vendor"
    done = CliRunner().invoke(app, ["import", str(tmp / "vendor.csv"), "--steps",
                                    str(tmp / "steps.toml"), "--out", str(out / "v.h5")])
    assert done.exit_code == 0, done.output
    result = analyze_p1(out / "v.h5").result
    _agree(result, reference)


def test_a_step_outside_the_data_is_refused_and_nothing_is_written(planned, tmp_path):
    tmp, _, _ = planned
    text = (tmp / "steps.toml").read_text(encoding="utf-8")
    bad = text + ('\n[[steps]]\nstart_s = 1e6\nend_s = 1000010.0\nrole = "p1.accel-position"\n'
                  'label = "late"\nangles_deg = [0.0, 0.0]\n')
    (tmp_path / "bad.toml").write_text(bad, encoding="utf-8")
    done = CliRunner().invoke(app, ["calibrate", str(tmp / "run.csv"), "--steps",
                                    str(tmp_path / "bad.toml"), "--out", str(tmp_path)])
    assert done.exit_code == 2
    text = " ".join(done.output.split())
    assert "step 29 (late, 1e+06–1.00001e+06 s) is not inside the data" in text, text
    assert "Traceback" not in done.output
    assert not list(tmp_path.glob("*.result.json"))


def test_calibrate_steps_applies_the_import_options_and_maps_a_temperature(planned):
    """`calibrate CSV --steps` reads the CSV through the import options (header lines, column
    map, units) like `import` and `segments` do, a vendor temperature column included."""
    tmp, reference, status = planned
    df = pd.read_csv(tmp / "run.csv")
    g0, deg = 9.80665, np.pi / 180.0
    vendor = pd.DataFrame({"Time": df["time_s [s]"]})
    for axis in "xyz":
        vendor[f"Gyro{axis.upper()}"] = df[f"gyro_{axis}_rps [rad/s]"] / deg
    for axis in "xyz":
        vendor[f"Acc{axis.upper()}"] = df[f"accel_{axis}_mps2 [m/s^2]"] / g0
    vendor["Temp"] = 24.0 + 0.001 * np.arange(len(vendor))
    path = tmp / "vendor-preamble.csv"
    with path.open("w", encoding="utf-8") as fh:
        fh.write("# Vendor IMU logger v2\n# serial 4711\n# rate 1000 Hz\n")
        vendor.to_csv(fh, index=False, float_format="%.17g")
    out = tmp / "from-preamble"
    done = CliRunner().invoke(app, [
        "calibrate", str(path), "--steps", str(tmp / "steps.toml"), "--out", str(out),
        "--no-record", "--skip-rows", "3", "--gyro-unit", "deg/s", "--accel-unit", "g",
        "--column-map", "t=Time,gx=GyroX,gy=GyroY,gz=GyroZ,ax=AccX,ay=AccY,az=AccZ,temp=Temp"])
    assert done.exit_code == status, done.output
    _agree(CalibrationResult.load(out / "vendor-preamble.imported.IMU-0001.p1.result.json"),
           reference)
    with open_recording(out / "vendor-preamble.imported.h5") as rec:
        temps = np.concatenate([c.columns["temperature_degc"]
                                for c in rec.iter_stream("imu", "IMU-0001")])
    assert temps[0] == pytest.approx(24.0) and temps[-1] == pytest.approx(vendor["Temp"].iloc[-1])
