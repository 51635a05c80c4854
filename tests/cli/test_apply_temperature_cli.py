"""`imucalib apply` with a result that carries temperature models (CSV and recording)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS
from imucalib.models.correct import correct_imu_frame
from imucalib.models.result import (
    CalibrationResult,
    ParameterTemperatureModel,
    triad_parameter_names,
)

runner = CliRunner()
NAMES = (*triad_parameter_names("accel", "triad"), *triad_parameter_names("gyro", "triad"))


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    from imucalib.cli import _app

    monkeypatch.setattr(_app.console, "width", 240)
    monkeypatch.setattr(_app.err_console, "width", 240)


def make_result(tmp_path: Path, sensor_id: str = "IMU-T") -> tuple[CalibrationResult, Path]:
    values = np.zeros(len(NAMES))
    values[NAMES.index("accel_bias_z")] = 0.05
    values[NAMES.index("accel_M_xx")] = 1e-3

    def record(name: str, coeffs: tuple[float, ...], **kw: object) -> ParameterTemperatureModel:
        q = len(coeffs) + sum(kw.get(k) is not None for k in ("rate_coefficient",
                                                                "leg_coefficient"))
        return ParameterTemperatureModel(
            name=name, reference_temperature_degc=25.0, coefficients=coeffs,
            covariance=np.eye(q) * 1e-12, chi2=3.0, dof=5, order_criterion="aicc",
            temperature_range_degc=(0.0, 40.0), **kw)  # type: ignore[arg-type]

    models = (record("accel_bias_z", (0.05, 1e-3, -2e-5, 1e-7), rate_coefficient=0.2,
                     leg_coefficient=2e-3),
              record("accel_M_xx", (1e-3, 1e-5)),
              record("gyro_bias_x", (0.0, 1e-5)))
    res = CalibrationResult(sensor_id=sensor_id, procedure="p2", model="triad",
                            param_names=NAMES, values=values,
                            covariance=np.eye(len(NAMES)) * 1e-12,
                            units=dict.fromkeys(NAMES, "1"), temperature_models=models)
    path = tmp_path / "r.json"
    path.write_text(res.to_json(), encoding="utf-8")
    return res, path


def columns(n: int, temp: np.ndarray, rate_hz: float = 100.0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(4)
    cols = {"time_s": np.arange(n) / rate_hz, "temperature_degc": temp}
    for c in GYRO_COLUMNS:
        cols[c] = rng.normal(size=n) * 0.1
    for c, g in zip(ACCEL_COLUMNS, (0.0, 0.0, 9.81), strict=True):
        cols[c] = g + rng.normal(size=n) * 0.01
    return cols


def expected(res: CalibrationResult, cols: dict[str, np.ndarray]) -> pd.DataFrame:
    df = pd.DataFrame({k: v for k, v in cols.items() if k != "time_s"},
                      index=pd.Index(cols["time_s"], name="time_s"))
    return correct_imu_frame(df, res)


def read_out(path: Path) -> pd.DataFrame:
    df = pd.read_csv(path)
    df.columns = [c.split(" [")[0] for c in df.columns]
    return df


def test_apply_a_temperature_model_to_a_csv(tmp_path):
    res, res_path = make_result(tmp_path)
    n = 20_000  # 200 s heating at 0.1 °C/s: the leg term switches on after half a window
    cols = columns(n, 10.0 + 0.1 * np.arange(n) / 100.0)
    data = tmp_path / "d.csv"
    pd.DataFrame(cols).to_csv(data, index=False)
    out = tmp_path / "o.csv"
    result = runner.invoke(app, ["apply", str(res_path), str(data), "--out", str(out)])
    assert result.exit_code == 0, (result.output, result.exception)
    assert "20,000 corrected samples" in result.stdout
    assert "temperature model applied at 10.0 … 30.0 °C" in result.stdout
    assert result.stderr == ""
    got, want = read_out(out), expected(res, cols)
    for c in (*GYRO_COLUMNS, *ACCEL_COLUMNS, "temperature_degc"):
        np.testing.assert_allclose(got[c].to_numpy(), want[c].to_numpy(), rtol=1e-12, atol=0)
    # the temperature model did change the data (bias at 30 °C and heating leg on z)
    raw_z = cols["accel_z_mps2"][-1]
    assert abs(got["accel_z_mps2"].iloc[-1] - raw_z) > 0.05


def test_apply_warns_once_when_extrapolating_and_refuses_without_temperature(tmp_path):
    _, res_path = make_result(tmp_path)
    cols = columns(1000, np.linspace(20.0, 60.0, 1000))
    data = tmp_path / "hot.csv"
    pd.DataFrame(cols).to_csv(data, index=False)
    result = runner.invoke(app, ["apply", str(res_path), str(data), "--out",
                                 str(tmp_path / "o.csv")])
    assert result.exit_code == 0, result.output
    assert result.stderr.count("warning:") == 1
    assert "beyond the temperature models' fitted range 0.0 … 40.0 °C by more than 5 °C" in \
        result.stderr
    del cols["temperature_degc"]
    pd.DataFrame(cols).to_csv(data, index=False)
    result = runner.invoke(app, ["apply", str(res_path), str(data), "--out",
                                 str(tmp_path / "o.csv")])
    assert result.exit_code == 2
    assert "has temperature models; the data have no 'temperature_degc' column" in result.stderr


def test_apply_a_temperature_model_to_a_recording_chunk_by_chunk(tmp_path, monkeypatch):
    from imucalib.io.reader import Recording
    from imucalib.io.recording import RecordingWriter
    from imucalib.io.streams import DEVICE_IMU, imu_stream_spec

    iter_stream = Recording.iter_stream
    chunks: list[int] = []

    def small_chunks(self, *args, **kw):  # chunks of 7000 samples (70 s, > the window)
        for chunk in iter_stream(self, *args, chunk_samples=7000, **kw):
            chunks.append(len(chunk.time_s))
            yield chunk

    monkeypatch.setattr(Recording, "iter_stream", small_chunks)
    res, res_path = make_result(tmp_path, sensor_id="IMU-9")
    n = 40_000  # six chunks
    t = np.arange(n) / 100.0
    cols = columns(n, 15.0 + 10.0 * np.sin(t / 60.0))
    path = tmp_path / "rec.h5"
    stream = {**cols, "device_time_s": cols["time_s"], "counter": np.arange(n),
              "saturated": np.zeros(n, dtype=bool)}
    with RecordingWriter(path, streams=[imu_stream_spec("IMU-9")]) as writer:
        writer.append(DEVICE_IMU, "IMU-9", stream)
        row = writer.begin_step("static", "warming", 0.0)
        writer.update_step(row, t_end_s=float(t[-1]), status="done", valid_start_s=0.0,
                           valid_end_s=float(t[-1]))
    out = tmp_path / "o.csv"
    result = runner.invoke(app, ["apply", str(res_path), str(path), "--out", str(out)])
    assert result.exit_code == 0, (result.output, result.exception)
    assert f"{n:,} corrected samples" in result.stdout and len(chunks) == 6
    lo, hi = cols["temperature_degc"].min(), cols["temperature_degc"].max()
    assert f"temperature model applied at {lo:.1f} … {hi:.1f} °C" in result.stdout
    got, want = read_out(out), expected(res, cols)
    for c in (*GYRO_COLUMNS, *ACCEL_COLUMNS):  # the rate window runs on across the chunks
        np.testing.assert_allclose(got[c].to_numpy(), want[c].to_numpy(), rtol=0, atol=1e-12)
