"""Tests of export_csv / export_mat: contents read back with pandas and scipy.io.loadmat."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import scipy.io

from imucalib.errors import InvalidInputError
from imucalib.exports import streams as export_module
from imucalib.exports.streams import export_csv, export_mat
from imucalib.io import ColumnSpec, RecordingWriter, StreamSpec, open_recording


def test_csv_whole_stream_exact_with_units(recording, tmp_path):
    path, data = recording
    out = tmp_path / "imu.csv"
    with open_recording(path) as rec:
        n = export_csv(rec, "imu", "IMU-0001", out, chunk_samples=3001)
    assert n == len(data["imu"]["time_s"])
    header = out.read_text().splitlines()[0]
    assert header == ("time_s [s],gyro_x_rps [rad/s],gyro_y_rps [rad/s],accel_z_mps2 [m/s^2],"
                      "temperature_degc [degC],counter [counts]")
    df = pd.read_csv(out)
    assert len(df) == n and df["counter [counts]"].dtype.kind == "i"
    values = np.loadtxt(out, delimiter=",", skiprows=1)  # exact decimal -> binary parsing
    for j, (k, v) in enumerate(data["imu"].items()):
        assert np.array_equal(values[:, j].astype(v.dtype), v), k


def test_csv_chunking_does_not_change_the_file(recording, tmp_path):
    path, _ = recording
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    export_csv(path, "table", "main", a, chunk_samples=7)
    export_csv(path, "table", "main", b)
    assert a.read_bytes() == b.read_bytes()


def test_csv_step_window_columns_and_nan(tmp_path):
    spec = StreamSpec("chamber", "main", {"temperature_degc": ColumnSpec("degC"),
                                          "setpoint_degc": ColumnSpec("degC")})
    path = tmp_path / "c.h5"
    t = np.arange(100) * 0.1
    temp = np.sin(t)
    temp[55] = np.nan
    with RecordingWriter(path, streams=[spec]) as w:
        w.append("chamber", "main", {"time_s": t, "temperature_degc": temp,
                                     "setpoint_degc": np.full(100, 25.0)})
        s = w.begin_step("thermal_soak", "soak 25", 0.0)
        w.update_step(s, t_end_s=9.9, valid_start_s=5.0, valid_end_s=6.0, status="done")
    out = tmp_path / "step.csv"
    assert export_csv(path, "chamber", "main", out, step=0, columns=["temperature_degc"]) == 10
    lines = out.read_text().splitlines()
    assert lines[0] == "time_s [s],temperature_degc [degC]"
    assert lines[6].endswith(",NaN")
    values = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.array_equal(values[:, 0], t[50:60])
    assert np.array_equal(values[:, 1], temp[50:60], equal_nan=True)
    with pytest.raises(InvalidInputError, match="either `step` or `t_start_s`"):
        export_csv(path, "chamber", "main", out, step=0, t_start_s=1.0)


def test_mat_whole_stream_and_meta(recording, tmp_path):
    path, data = recording
    out = tmp_path / "imu.mat"
    with open_recording(path) as rec:
        assert export_mat(rec, "imu", "IMU-0001", out) == len(data["imu"]["time_s"])
    m = scipy.io.loadmat(out, squeeze_me=True, struct_as_record=False)
    for k, v in data["imu"].items():
        assert m[k].dtype == v.dtype and np.array_equal(m[k], v), k
    meta = m["meta"]
    assert (meta.device, meta.unit, meta.source, meta.step) == ("imu", "IMU-0001", "run.h5", -1)
    assert meta.units.gyro_x_rps == "rad/s" and meta.units.time_s == "s"
    assert np.isnan(meta.t_start_s)
    raw = scipy.io.loadmat(out)
    assert raw["time_s"].shape == (len(data["imu"]["time_s"]), 1)  # column vectors


def test_mat_step(recording, tmp_path):
    path, data = recording
    out = tmp_path / "step1.mat"
    n = export_mat(path, "table", "main", out, step=1)
    m = scipy.io.loadmat(out, squeeze_me=True, struct_as_record=False)
    t = data["table"]["time_s"]
    keep = (t >= 10.0) & (t < 14.0)
    assert n == keep.sum() and np.array_equal(m["angle_rad"], data["table"]["angle_rad"][keep])
    assert (m["meta"].step, m["meta"].t_start_s, m["meta"].t_end_s) == (1, 10.0, 14.0)


def test_mat_v5_size_limit(recording, tmp_path, monkeypatch):
    path, _ = recording
    monkeypatch.setattr(export_module, "MAT_V5_MAX_BYTES", 1000)
    out = tmp_path / "big.mat"
    with pytest.raises(InvalidInputError, match=r"column 'time_s' of imu/IMU-0001 would be "
                                                r"160,000 bytes \(20,000 rows\); MAT v5 holds at "
                                                r"most 1,000 bytes per variable"):
        export_mat(path, "imu", "IMU-0001", out)
    assert not out.exists()
    export_mat(path, "imu", "IMU-0001", out, t_start_s=0.0, t_end_s=0.1)  # 100 rows fit


def test_mat_refuses_column_named_meta(tmp_path):
    spec = StreamSpec("x", "y", {"meta": ColumnSpec("1")})
    path = tmp_path / "m.h5"
    with RecordingWriter(path, streams=[spec]) as w:
        w.append("x", "y", {"time_s": [0.0], "meta": [1.0]})
    with pytest.raises(InvalidInputError, match="column named 'meta'"):
        export_mat(path, "x", "y", tmp_path / "m.mat")


def test_export_unknown_stream(recording, tmp_path):
    path, _ = recording
    with pytest.raises(InvalidInputError, match="no stream imu/nope"):
        export_csv(path, "imu", "nope", tmp_path / "x.csv")
    with pytest.raises(InvalidInputError, match="no stream imu/nope"):
        export_mat(path, "imu", "nope", tmp_path / "x.mat")
