"""`imucalib inspect` without a terminal: names are shown whole, not cut at 80 columns."""

from __future__ import annotations

from typer.testing import CliRunner

from imucalib.cli import app

runner = CliRunner()

def test_inspect_shows_a_long_unit_name_whole_without_a_terminal(tmp_path):
    import numpy as np

    from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS
    from imucalib.io.recording import RecordingWriter
    from imucalib.io.streams import DEVICE_IMU, imu_stream_spec

    name = "IMU-0001-serial-SN-2024-000123456-left-wing-station-7"
    n = 50
    cols = {"time_s": np.arange(n) / 100.0, "device_time_s": np.arange(n) / 100.0,
            "counter": np.arange(n), "temperature_degc": np.full(n, 20.0),
            "saturated": np.zeros(n, dtype=bool)}
    for c in (*GYRO_COLUMNS, *ACCEL_COLUMNS):
        cols[c] = np.zeros(n)
    path = tmp_path / "long.h5"
    with RecordingWriter(path, streams=[imu_stream_spec(name)]) as writer:
        writer.append(DEVICE_IMU, name, cols)
        row = writer.begin_step("static", "a rather long label for the step at rest", 0.0)
        writer.update_step(row, t_end_s=0.5, status="done", valid_start_s=0.0, valid_end_s=0.5)
    result = runner.invoke(app, ["inspect", str(path)])
    assert result.exit_code == 0, result.output
    assert f"imu/{name}" in result.output, result.output
    assert "…" not in result.output, result.output
