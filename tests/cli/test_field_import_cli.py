"""End to end on the command line: a vendor log of a hand-held session, read through the import
options, segmented by the variance detector, with the figure; bad input exits 2 with one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import app

runner = CliRunner()
G0 = 9.80665
MAP = "gx=GyroX,gy=GyroY,gz=GyroZ,ax=AccX,ay=AccY,az=AccZ"


@pytest.fixture(scope="module")
def vendor(hand_held_log, tmp_path_factory) -> tuple[Path, list, list]:
    """The hand-held log as a vendor CSV: °/s and g, no time column (200 Hz)."""
    _, gyro, accel, still, rots = hand_held_log
    path = tmp_path_factory.mktemp("field") / "vendor.csv"
    data = np.column_stack([np.rad2deg(gyro), accel / G0])
    lines = ["GyroX,GyroY,GyroZ,AccX,AccY,AccZ"] + [",".join(f"{v:.6f}" for v in row)
                                                     for row in data]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path, still, rots


def test_segments_of_a_vendor_log_with_the_figure(vendor, tmp_path):
    path, still, rots = vendor
    fig, doc = tmp_path / "f.png", tmp_path / "s.json"
    res = runner.invoke(app, ["segments", str(path), "--column-map", MAP, "--sample-rate-hz",
                              "200", "--gyro-unit", "deg/s", "--accel-unit", "g", "--detector",
                              "variance", "--figure", str(fig), "--json", str(doc)])
    assert res.exit_code == 0, res.output
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and fig.stat().st_size > 10_000
    segs = json.loads(doc.read_text())["segments"]
    assert [s["kind"] for s in segs] == ["static", "rotating"] * len(rots) + ["static"]
    for seg, (a, b) in zip([s for s in segs if s["kind"] == "static"], still, strict=True):
        assert a - 1e-6 <= seg["start_time_s"] < seg["end_time_s"] <= b + 1e-6
        assert seg["end_time_s"] - seg["start_time_s"] > 0.6 * (b - a)
    angles = [s["angle_deg"] for s in segs if s["kind"] == "rotating"]
    truth = [np.rad2deg(np.linalg.norm(r[2])) for r in rots]
    assert angles == pytest.approx(truth, rel=0.02)


def test_the_same_options_from_an_import_file(vendor, tmp_path):
    path, _, rots = vendor
    spec = tmp_path / "spec.toml"
    spec.write_text('sample_rate_hz = 200\ngyro_unit = "deg/s"\naccel_unit = "g"\n'
                    '[columns]\ngx = "GyroX"\ngy = "GyroY"\ngz = "GyroZ"\nax = "AccX"\n'
                    'ay = "AccY"\naz = "AccZ"\n', encoding="utf-8")
    doc = tmp_path / "s.json"
    res = runner.invoke(app, ["segments", str(path), "--import", str(spec), "--detector",
                              "variance", "--json", str(doc)])
    assert res.exit_code == 0, res.output
    assert sum(s["kind"] == "rotating" for s in json.loads(doc.read_text())["segments"]) == \
        len(rots)


def test_allan_takes_the_same_import_options(tmp_path):
    rng = np.random.default_rng(3)
    path = tmp_path / "static.csv"
    rows = rng.normal(0, 0.1, (4000, 3)) + 3.7
    path.write_text("GyroX,GyroY,GyroZ\n" + "\n".join(",".join(f"{v:.5f}" for v in r)
                                                      for r in rows) + "\n", encoding="utf-8")
    res = runner.invoke(app, ["allan", str(path), "--column-map", "gx=GyroX,gy=GyroY,gz=GyroZ",
                              "--gyro-unit", "deg/s", "--sample-rate-hz", "100", "--out",
                              str(tmp_path / "o")])
    assert res.exit_code == 0, res.output


@pytest.mark.parametrize(("args", "message"), [
    ([], "no time column among the columns found ['GyroX', 'GyroY', 'GyroZ', 'AccX', 'AccY', "
         "'AccZ']"),
    (["--sample-rate-hz", "200"], "segmentation needs the gyro columns"),
    (["--column-map", MAP, "--sample-rate-hz", "200", "--gyro-unit", "furlong"],
     "unknown unit 'furlong'"),
    (["--column-map", MAP, "--sample-rate-hz", "200", "--gyro-unit", "counts"],
     "--gyro-scale"),
    (["--column-map", "gx=NoSuch", "--sample-rate-hz", "200"], "segmentation needs"),
    (["--column-map", "foo=bar"], "neither side is a quantity"),
    (["--column-map", MAP, "--sample-rate-hz", "200", "--gyro-unit", "deg/s", "--accel-unit",
      "g", "--detector", "variance", "--static-threshold", "0.5"], "must be > 1"),
])
def test_bad_input_exits_2_with_one_line(vendor, args, message):
    path, _, _ = vendor
    res = runner.invoke(app, ["segments", str(path), *args])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:"), res.output
    assert message in " ".join(res.output.split()), res.output
    assert "Traceback" not in res.output


def test_a_non_numeric_cell_on_the_command_line(tmp_path):
    path = tmp_path / "bad.csv"
    rows = ["1,2,3"] * 100
    rows[56] = "1,x,3"
    path.write_text("GyroX,GyroY,GyroZ\n" + "\n".join(rows) + "\n", encoding="utf-8")
    res = runner.invoke(app, ["segments", str(path), "--column-map", "gx=GyroX,gy=GyroY,gz=GyroZ",
                              "--sample-rate-hz", "200", "--gyro-unit", "deg/s"])
    assert res.exit_code == 2
    assert "column 'gyro_y_rps' holds a non-numeric value 'x' at data row 57 (line 58)" in \
        " ".join(res.output.split())


def test_import_reads_a_vendor_log_through_the_same_options(vendor, tmp_path):
    path, _, _ = vendor
    steps = tmp_path / "steps.toml"
    steps.write_text('latitude_deg = 45.0\ntable_axes = ["pitch", "roll"]\n[[steps]]\n'
                     'start_s = 0.5\nend_s = 2.5\nrole = "p1.accel-position"\nlabel = "z-up"\n'
                     'angles_deg = [0.0, 0.0]\n', encoding="utf-8")
    out = tmp_path / "r.h5"
    res = runner.invoke(app, ["import", str(path), "--steps", str(steps), "--out", str(out),
                              "--column-map", MAP, "--sample-rate-hz", "200", "--gyro-unit",
                              "deg/s", "--accel-unit", "g"])
    assert res.exit_code == 0, res.output
    from imucalib.io.opening import open_recording

    with open_recording(out) as rec:
        unit = next(s.unit for s in rec.streams if s.device == "imu")
        data = rec.read_stream("imu", unit)
    assert np.allclose(np.diff(data.time_s[:3]), 0.005)
    assert np.rad2deg(np.mean(data.columns["gyro_x_rps"][:400])) == pytest.approx(3.7, abs=0.05)


def test_the_table_detector_points_to_the_variance_detector_on_a_biased_hand_log(vendor):
    path, _, _ = vendor
    res = runner.invoke(app, ["segments", str(path), "--column-map", MAP, "--sample-rate-hz",
                              "200", "--gyro-unit", "deg/s", "--accel-unit", "g"])
    assert res.exit_code == 0, res.output
    assert "--detector variance" in " ".join(res.output.split())


def test_a_raw_count_log_with_preamble_ms_time_and_semicolons(hand_held_log, tmp_path):
    t, gyro, accel, _, rots = hand_held_log
    counts = np.column_stack([np.round(t * 1000), np.round(np.rad2deg(gyro) * 131 + 12),
                              np.round(accel / G0 * 16384 + 20)]).astype(int)
    path = tmp_path / "raw.txt"
    path.write_text("MPU-6050 logger\nfirmware 1.2\nms;gx;gy;gz;ax;ay;az\n"
                    + "\n".join(";".join(map(str, r)) for r in counts) + "\n", encoding="utf-8")
    doc = tmp_path / "s.json"
    res = runner.invoke(app, ["segments", str(path), "--skip-rows", "2", "--delimiter", ";",
                              "--time-column", "ms", "--time-unit", "ms", "--gyro-unit",
                              "counts", "--gyro-scale", "131", "--gyro-offset", "12",
                              "--accel-unit", "counts", "--accel-scale", "16384",
                              "--accel-offset", "20", "--detector", "variance", "--json",
                              str(doc)])
    assert res.exit_code == 0, res.output
    segs = json.loads(doc.read_text())["segments"]
    static = [s for s in segs if s["kind"] == "static"]
    assert np.rad2deg(static[0]["mean_rate_rps"]) == pytest.approx([3.7, -3.7, 3.7], abs=0.05)
    assert np.linalg.norm(static[0]["mean_specific_force_mps2"]) == pytest.approx(G0, rel=0.01)
    angles = [s["angle_deg"] for s in segs if s["kind"] == "rotating"]
    assert angles == pytest.approx([np.rad2deg(np.linalg.norm(r[2])) for r in rots], rel=0.02)
