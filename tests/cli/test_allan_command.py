"""``imucalib allan DATA``: bare CSV, ROS ``rostopic echo -p`` CSV, and one-line errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app

RATE_HZ = 100.0
N = 1 << 14
ARW_DPS = 0.01  # two-sided N [(°/s)/√Hz] → ARW 0.6 °/√h
ROS_HEADER = ("%time,field.header.seq,field.header.stamp,field.header.frame_id,"
              "field.orientation.x,field.orientation.y,field.orientation.z,field.orientation.w,"
              "field.angular_velocity.x,field.angular_velocity.y,field.angular_velocity.z,"
              "field.linear_acceleration.x,field.linear_acceleration.y,"
              "field.linear_acceleration.z")


def _samples(seed: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.arange(N) / RATE_HZ
    gyro_dps = rng.standard_normal((N, 3)) * ARW_DPS * np.sqrt(RATE_HZ)
    accel = rng.standard_normal((N, 3)) * 1e-3 * np.sqrt(RATE_HZ)
    return t, gyro_dps, accel


def _write(path: Path, header: str, rows: list[str]) -> Path:
    path.write_text(header + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    return path


def _canonical(tmp: Path) -> Path:
    t, g, a = _samples()
    rows = [",".join(repr(float(v)) for v in (t[i], *g[i], *a[i])) for i in range(N)]
    return _write(tmp / "canon.csv", "time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps,accel_x_mps2,"
                  "accel_y_mps2,accel_z_mps2", rows)


def _ros(tmp: Path) -> Path:
    t, g, a = _samples()
    rows = []
    for i in range(N):
        ns = 1_700_000_000_000_000_000 + round(t[i] * 1e9)
        vals = ",".join(repr(float(v)) for v in (*np.radians(g[i]), *a[i]))
        rows.append(f"{ns + 7},{i},{ns},imu_link,0,0,0,1,{vals}")
    return _write(tmp / "ros.csv", ROS_HEADER, rows)


def _run(*args: str) -> object:
    return CliRunner().invoke(app, list(args))


def _fits(out: Path, stem: str) -> dict[str, dict]:
    doc = json.loads((out / f"{stem}.imu.allan.json").read_text(encoding="utf-8"))
    chans = doc["segments"][0]["channels"]
    return {c["channel"]: c["fit"] for c in chans}


def _term(fit: dict, name: str) -> dict:
    return next(t for t in fit["terms"] if t["name"] == name)


def test_canonical_csv_in_deg_s_recovers_the_arw(tmp_path: Path) -> None:
    res = _run("allan", str(_canonical(tmp_path)), "--gyro-unit", "deg/s",
               "--out", str(tmp_path / "o"))
    assert res.exit_code == 0, res.output
    assert "Angle random walk" in res.output
    for ch, fit in _fits(tmp_path / "o", "canon").items():
        if ch.startswith("gyro"):
            white = _term(fit, "white")
            arw = white["value_si"] / np.radians(1) * 60
            assert abs(arw - 60 * ARW_DPS) < 3 * white["std_si"] / np.radians(1) * 60, ch
    assert (tmp_path / "o" / "canon.imu.allan.kalibr.yaml").exists()


def test_ros_csv_is_detected_and_equals_the_canonical(tmp_path: Path) -> None:
    assert _run("allan", str(_canonical(tmp_path)), "--gyro-unit", "deg/s",
                "--out", str(tmp_path / "a")).exit_code == 0
    res = _run("allan", str(_ros(tmp_path)), "--out", str(tmp_path / "b"))
    assert res.exit_code == 0, res.output
    a, b = _fits(tmp_path / "a", "canon"), _fits(tmp_path / "b", "ros")
    assert sorted(a) == sorted(b)
    for ch in a:
        for name in ("white", "bias_instability"):
            assert _term(b[ch], name)["value_si"] == pytest.approx(
                _term(a[ch], name)["value_si"], rel=1e-6), (ch, name)


@pytest.mark.parametrize(("header", "rows", "args", "expected"), [
    ("time_s,foo", ["0,1", "0.01,2", "0.02,3"], [], "none of the columns"),
    ("time_s,gyro_x_rps", ["0,1", "0.01,2"], ["--gyro-unit", "furlong/s"], "furlong/s"),
    ("time_s,gyro_x_rps", ["0,1", "0.02,2", "0.01,3"], [], "decreases"),
    ("time_s,gyro_x_rps", ["0,1", "0.01,2"], [], "need at least 3"),
    ("GyrX", ["1", "2"], ["--column-map", "GyrX=gyro_x_rps"],
     "no time column among the columns found"),
])
def test_errors_are_one_line_exit_2(tmp_path: Path, header: str, rows: list[str],
                                    args: list[str], expected: str) -> None:
    path = _write(tmp_path / "bad.csv", header, rows)
    res = _run("allan", str(path), "--out", str(tmp_path / "o"), *args)
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "error:" in lines[0] and "Traceback" not in res.output
    assert expected in " ".join(res.output.split()), res.output


def test_sample_rate_builds_the_time(tmp_path: Path) -> None:
    _, g, _ = _samples()
    path = _write(tmp_path / "idx.csv", "GyrX", [repr(float(v)) for v in g[:, 0]])
    res = _run("allan", str(path), "--column-map", "GyrX=gyro_x_rps", "--units",
               "gyro_x_rps=deg/s", "--sample-rate", "100", "--out", str(tmp_path / "o"))
    assert res.exit_code == 0, res.output
    fit = _fits(tmp_path / "o", "idx")["gyro_x_rps"]
    assert _term(fit, "white")["value_si"] == pytest.approx(np.radians(ARW_DPS), rel=0.05)
