"""A log read in chunks: the same frame as the whole-file read for every layout, defects named by
their row and line over the whole file, the time checked across chunk boundaries, a chunked
import, and ``imucalib apply`` correcting a vendor log through the import options."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import InvalidInputError
from imucalib.io.csv_import import iter_imu_csv, read_imu_csv
from imucalib.io.csv_recording import recording_from_csv
from imucalib.io.import_spec import ImportSpec, iter_imu_table, read_imu_table
from imucalib.io.opening import open_recording
from imucalib.io.step_file import parse_step_file
from imucalib.models.correct import correct_imu
from imucalib.models.result import CalibrationResult, triad_parameter_names

G0 = 9.80665
D2R = math.pi / 180
N = 50  # rows of each file: 8 chunks of 7 rows (the last one 1)
CHUNK = 7
GYRO = ["gyro_x_rps", "gyro_y_rps", "gyro_z_rps"]
ACCEL = ["accel_x_mps2", "accel_y_mps2", "accel_z_mps2"]
VENDOR_MAP = "gx=GyroX,gy=GyroY,gz=GyroZ,ax=AccX,ay=AccY,az=AccZ,t=Stamp"
CANONICAL = ("time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps,accel_x_mps2,accel_y_mps2,"
             "accel_z_mps2")
runner = CliRunner()


def _signal(k: int) -> tuple[float, float, float, float, float, float]:
    """A distinct value in every cell (°/s and g)."""
    return (0.5 + 0.01 * k, -0.2 * math.sin(k), 0.03 * k, 0.001 * k, -0.002, 1.0 - 1e-4 * k)


def _rows(fmt, n: int = N) -> str:
    return "".join(fmt(k, *_signal(k)) + "\n" for k in range(n))


# ----------------------------------------------------------------- the layouts, each as a file
def _canonical(p: Path) -> ImportSpec | None:
    head = ",".join(f"{c} [deg/s]" if c.startswith("gyro") else f"{c} [g]" if c.startswith(
        "accel") else c for c in CANONICAL.split(","))
    p.write_text(head + "\n" + _rows(
        lambda k, a, b, c, d, e, f: f"{1e3 + 0.005 * k!r},{a!r},{b!r},{c!r},{d},{e},{f}"),
        encoding="utf-8")
    return None


def _imucal(p: Path) -> ImportSpec | None:
    p.write_text("acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n" + _rows(
        lambda k, a, b, c, d, e, f: f"{d * G0!r},{e * G0!r},{f * G0!r},{a!r},{b!r},{c!r}"),
        encoding="utf-8")
    return ImportSpec(sample_rate_hz=100.0)


def _ros(p: Path) -> ImportSpec | None:
    head = ("%time,field.header.seq,field.header.stamp,field.header.frame_id,"
            "field.angular_velocity.x,field.angular_velocity.y,field.angular_velocity.z,"
            "field.linear_acceleration.x,field.linear_acceleration.y,field.linear_acceleration.z")
    p.write_text(head + "\n" + _rows(
        lambda k, a, b, c, d, e, f: f"{1_700_000_000_000_000_000 + k * 5_000_123},{k},"
                                    f"{1_700_000_000_000_000_000 + k * 5_000_000},imu_link,"
                                    f"{a * D2R!r},{b * D2R!r},{c * D2R!r},{d * G0!r},{e * G0!r},"
                                    f"{f * G0!r}"), encoding="utf-8")
    return None


def _plain_units(p: Path) -> ImportSpec | None:
    p.write_text("Stamp,GyroX,GyroY,GyroZ,AccX,AccY,AccZ,Temp\n" + _rows(
        lambda k, a, b, c, d, e, f: f"{10 * k},{a!r},{b!r},{c!r},{d!r},{e!r},{f!r},25.5"),
        encoding="utf-8")
    return ImportSpec(column_map=dict(item.split("=") for item in VENDOR_MAP.split(",")),
                      gyro_unit="deg/s", accel_unit="g", time_unit="ms")


def _counts(p: Path) -> ImportSpec | None:
    # 131 counts per °/s and 16384 per g (an MPU-6050), offsets, a sample counter as time
    p.write_text("n,gx,gy,gz,ax,ay,az\n" + _rows(
        lambda k, a, b, c, d, e, f: f"{500 + k},{a * 131 + 12!r},{b * 131 + 12!r},"
                                    f"{c * 131 + 12!r},{d * 16384 - 20!r},"
                                    f"{e * 16384 - 20!r},{f * 16384 - 20!r}"),
        encoding="utf-8")
    return ImportSpec(column_map={"t": "n"}, gyro_unit="counts", gyro_scale=131.0,
                      gyro_offset=12.0, accel_unit="counts", accel_scale=16384.0,
                      accel_offset=-20.0, sample_rate_hz=200.0)


def _preamble_semicolons(p: Path) -> ImportSpec | None:
    p.write_text("# SensorLog v3\n# device IMU-42\n# rate 200 Hz\n"
                 "GyroX;GyroY;GyroZ;AccX;AccY;AccZ\n" + _rows(
                     lambda k, a, b, c, d, e, f: f"{a!r};{b!r};{c!r};{d!r};{e!r};{f!r}"),
                 encoding="utf-8")
    return ImportSpec(column_map=dict(item.split("=") for item in VENDOR_MAP.split(",")[:6]),
                      gyro_unit="deg/s", accel_unit="g", sample_rate_hz=200.0, skip_rows=3,
                      delimiter=";")


LAYOUTS = {"canonical": _canonical, "imucal": _imucal, "ros-imu": _ros, "plain": _plain_units,
           "counts": _counts, "preamble;": _preamble_semicolons}


@pytest.mark.parametrize("name", list(LAYOUTS))
def test_chunks_join_to_the_whole_file_read_for_every_layout(tmp_path, name):
    path = tmp_path / f"{name}.csv"
    spec = LAYOUTS[name](path)
    whole = read_imu_table(path, spec)
    chunks = list(iter_imu_table(path, spec, chunk_rows=CHUNK))
    assert [len(c) for c in chunks] == [CHUNK] * (N // CHUNK) + [N % CHUNK]
    assert all(c.attrs == whole.attrs for c in chunks)
    joined = pd.concat(chunks)
    pd.testing.assert_frame_equal(joined, whole, check_exact=True)
    # and the values are the truth, in SI: the time base runs on across the chunks
    truth = np.array([_signal(k) for k in range(N)])
    assert np.allclose(whole[GYRO].to_numpy(), truth[:, :3] * D2R, rtol=1e-12, atol=1e-12)
    assert np.allclose(whole[ACCEL].to_numpy(), truth[:, 3:] * G0, rtol=1e-12, atol=1e-12)
    step = np.diff(whole.index.to_numpy())
    assert np.all(step > 0) and np.ptp(step) < 1e-3 * step.mean()  # ROS: ns on 1.7e9 s


def test_read_imu_table_does_not_depend_on_chunk_rows(tmp_path):
    path = tmp_path / "c.csv"
    spec = _counts(path)
    pd.testing.assert_frame_equal(read_imu_table(path, spec, chunk_rows=3),
                                  read_imu_table(path, spec), check_exact=True)
    assert read_imu_table(path, spec).index[0] == 0.0  # the counter counted from its first


# --------------------------------------------------------------- defects: rows over the file
def _canonical_with(tmp_path: Path, row: int, text: str) -> Path:
    """A canonical log whose data row `row` (0-based) is `text`."""
    lines = [f"{0.01 * k:.2f},0.1,0.2,0.3,0.0,0.0,9.8" for k in range(N)]
    lines[row] = text
    path = tmp_path / "bad.csv"
    path.write_text(CANONICAL + "\n" + "\n".join(lines) + "\n", encoding="utf-8")
    return path


@pytest.mark.parametrize(("text", "message"), [
    ("0.16,0.1,abc,0.3,0.0,0.0,9.8",
     "column 'gyro_y_rps' holds a non-numeric value 'abc' at data row 17 (line 18) (numbers "
     "expected; a missing value is written NaN)"),
    ("0.16,0.1,0.2,0.3,0.0,,9.8", "column 'accel_y_mps2' is empty at data row 17 (line 18) (a "
     "number expected; a missing value is written NaN)"),
    ("0.16,0.1,0.2,inf,0.0,0.0,9.8",
     "column 'gyro_z_rps' holds inf at data row 17 (line 18); time_s and the gyro and "
     "accelerometer columns must be finite (1 such cell(s) in the first 21 data rows)"),
    ("0.16,0.1,0.2,0.3,0.0,0.0,9.8,7", "line 18 has 8 fields; the header has 7 (a ragged row)"),
    ("0.16,0.1,0.2", "line 18 has 3 fields; the header has 7 (a ragged row)"),
    ("0.02,0.1,0.2,0.3,0.0,0.0,9.8",
     "time_s decreases at data row 17 (line 18): 0.02 s after 0.15 s; times must not "
     "decrease (1 such step(s) in the first 21 data rows)"),
])
def test_a_defect_in_the_third_chunk_names_its_row_and_line_over_the_file(tmp_path, text,
                                                                           message):
    path = _canonical_with(tmp_path, 16, text)  # the third chunk holds data rows 15 … 21
    chunks = iter_imu_table(path, chunk_rows=CHUNK)
    assert len(next(chunks)) == CHUNK and len(next(chunks)) == CHUNK  # two clean chunks first
    with pytest.raises(InvalidInputError) as err:
        next(chunks)
    assert str(err.value) == f"{path}: {message}"
    # the whole-file read says the same of the same row (its counts cover the whole file)
    with pytest.raises(InvalidInputError) as whole:
        read_imu_table(path)
    assert str(whole.value) == f"{path}: {message.replace(' in the first 21 data rows', '')}"


@pytest.mark.parametrize("row", [14, 21])  # the first row of the third chunk, and of the fourth
def test_time_going_back_across_a_chunk_boundary_is_caught(tmp_path, row):
    path = _canonical_with(tmp_path, row, "0.05,0.1,0.2,0.3,0.0,0.0,9.8")
    before = repr(float(f"{0.01 * (row - 1):.2f}"))
    with pytest.raises(InvalidInputError, match=rf"time_s decreases at data row {row + 1} "
                                                rf"\(line {row + 2}\): 0\.05 s after {before} s"):
        list(iter_imu_csv(path, chunk_rows=CHUNK))


def test_the_span_is_counted_from_the_files_first_time(tmp_path):
    lines = [f"{k * 4e6:.1f},0,0,0,0,0,9.8" for k in range(20)]  # 20 rows over 76e6 s
    path = tmp_path / "long.csv"
    path.write_text(CANONICAL + "\n" + "\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(InvalidInputError, match=r"time_s spans 3\.6e\+07 s \(from 0\.0 to "
                                                r"36000000\.0\)"):
        list(iter_imu_csv(path, chunk_rows=5))  # no chunk alone spans 366 days


def test_a_bad_chunk_size_is_refused(tmp_path):
    path = tmp_path / "c.csv"
    _canonical(path)
    for bad in (0, -3, 2.5, True):
        with pytest.raises(InvalidInputError, match="`chunk_rows` must be an integer ≥ 1"):
            iter_imu_table(path, chunk_rows=bad)  # type: ignore[arg-type]


def test_read_imu_csv_joins_the_same_chunks(tmp_path):
    path = tmp_path / "c.csv"
    _canonical(path)
    pd.testing.assert_frame_equal(pd.concat(list(iter_imu_csv(path, chunk_rows=4))),
                                  read_imu_csv(path), check_exact=True)


# ----------------------------------------------------------------------- import, chunk by chunk
def test_the_import_written_chunk_by_chunk_equals_the_whole_file_import(tmp_path):
    t = np.arange(0.0, 9.0, 0.01)
    t = np.delete(t, [150, 151])  # a gap: the counter must run on across chunks
    with open(tmp_path / "log.csv", "w", encoding="utf-8") as fh:
        fh.write(CANONICAL + "\n")
        for k, x in enumerate(t):
            fh.write(f"{float(x)!r},{1e-3 * k!r},0.0,0.0,0.0,0.0,9.8\n")
    steps = parse_step_file('latitude_deg = 45.0\ntable_axes = ["pitch", "roll"]\n'
                            '[[steps]]\nstart_s = 1.0\nend_s = 3.0\nrole = "p1.accel-position"\n'
                            'label = "z-up"\nangles_deg = [0.0, 0.0]\n')
    whole = recording_from_csv(tmp_path / "log.csv", steps, tmp_path / "whole.h5")
    chunked = recording_from_csv(tmp_path / "log.csv", steps, tmp_path / "chunked.h5",
                                 chunk_rows=64)
    with open_recording(whole) as a, open_recording(chunked) as b:
        sa, sb = a.read_stream("imu", "log"), b.read_stream("imu", "log")
        assert np.array_equal(sa.time_s, t) and np.array_equal(sb.time_s, t)
        assert set(sa.columns) == set(sb.columns)
        for col in sa.columns:
            assert np.array_equal(sa.columns[col], sb.columns[col], equal_nan=True), col
        assert int(np.max(np.diff(sb.columns["counter"]))) == 3
        assert np.array_equal(a.read_step(0, "table", "commanded").time_s,
                              b.read_step(0, "table", "commanded").time_s)


def test_a_counter_column_of_the_file_is_kept_across_chunks(tmp_path):
    t = np.arange(0.0, 5.0, 0.01)
    counter = 1000 + 3 * np.arange(t.size)  # the IMU's own counter, not the one from the times
    with open(tmp_path / "log.csv", "w", encoding="utf-8") as fh:
        fh.write(CANONICAL + ",counter\n")
        for x, c in zip(t, counter, strict=True):
            fh.write(f"{float(x)!r},0.0,0.0,0.0,0.0,0.0,9.8,{c}\n")
    steps = parse_step_file('latitude_deg = 45.0\ntable_axes = ["pitch", "roll"]\n'
                            '[[steps]]\nstart_s = 1.0\nend_s = 3.0\nrole = "p1.accel-position"\n'
                            'label = "z-up"\nangles_deg = [0.0, 0.0]\n')
    out = recording_from_csv(tmp_path / "log.csv", steps, tmp_path / "log.h5", chunk_rows=64)
    with open_recording(out) as rec:
        assert np.array_equal(rec.read_stream("imu", "log").columns["counter"], counter)


# ------------------------------------------------------------------- apply with import options
def _result(tmp_path: Path) -> tuple[Path, CalibrationResult]:
    names = (*triad_parameter_names("accel", "triad"), *triad_parameter_names("gyro", "triad"))
    k = len(names)
    values = np.random.default_rng(3).normal(0.0, 2e-3, k)
    res = CalibrationResult(sensor_id="IMU-42", procedure="p1", model="triad",
                            param_names=names, values=values, covariance=np.eye(k) * 1e-12,
                            units=dict.fromkeys(names, "1"))
    path = tmp_path / "r.json"
    path.write_text(res.to_json(), encoding="utf-8")
    return path, res


def test_apply_corrects_a_vendor_log_in_its_own_layout(tmp_path, monkeypatch):
    import imucalib.io.import_spec as import_spec

    real = import_spec.iter_imu_table
    monkeypatch.setattr(import_spec, "iter_imu_table",  # small chunks: several of them
                        lambda path, spec=None, **kw: real(path, spec, chunk_rows=CHUNK))
    data = tmp_path / "vendor.csv"
    _preamble_semicolons(data)
    res_path, res = _result(tmp_path)
    out = tmp_path / "fixed.csv"
    done = runner.invoke(app, ["apply", str(res_path), str(data), "--out", str(out),
                               "--column-map", VENDOR_MAP.rsplit(",", 1)[0], "--gyro-unit",
                               "deg/s", "--accel-unit", "g", "--sample-rate-hz", "200",
                               "--skip-rows", "3", "--delimiter", ";"])
    assert done.exit_code == 0, done.output
    assert f"wrote{out}:{N}correctedsamples" in "".join(done.stdout.split())
    fixed = pd.read_csv(out)
    assert list(fixed.columns) == ["time_s [s]", *(f"{c} [rad/s]" for c in GYRO),
                                   *(f"{c} [m/s^2]" for c in ACCEL)]
    truth = np.array([_signal(k) for k in range(N)])
    gyro, accel = correct_imu(truth[:, :3] * D2R, truth[:, 3:] * G0, res)
    assert gyro is not None and accel is not None
    assert np.allclose(fixed.iloc[:, 0], np.arange(N) / 200.0, rtol=0, atol=1e-12)
    assert np.allclose(fixed.iloc[:, 1:4], gyro, rtol=1e-12, atol=1e-15)
    assert np.allclose(fixed.iloc[:, 4:7], accel, rtol=1e-12, atol=1e-12)
    assert not np.allclose(gyro, truth[:, :3] * D2R, rtol=1e-6)  # the result changes them
    assert not (tmp_path / "fixed.csv.part").exists()


@pytest.mark.parametrize(("options", "message"), [
    (["--gyro-unit", "counts"], "`gyro_unit` is counts: give `--gyro-scale`"),
    (["--column-map", "gx"], "--column-map"),
    (["--sample-rate-hz", "-5"], "`sample_rate_hz` must be > 0; got -5.0"),
    (["--import", "missing.toml"], "cannot read the import file missing.toml"),
])
def test_apply_with_bad_import_options_exits_2_with_one_line(tmp_path, monkeypatch, options,
                                                             message):
    monkeypatch.chdir(tmp_path)
    data = tmp_path / "vendor.csv"
    _preamble_semicolons(data)
    res_path, _ = _result(tmp_path)
    done = runner.invoke(app, ["apply", str(res_path), str(data), "--out", "o.csv", *options])
    assert done.exit_code == 2, done.output
    assert "Traceback" not in done.output
    assert done.stderr.startswith("error: ") and done.stderr.count("\n") == 1
    assert message in done.stderr
    assert not (tmp_path / "o.csv").exists() and not (tmp_path / "o.csv.part").exists()


def test_apply_a_defect_in_a_later_chunk_leaves_no_output(tmp_path, monkeypatch):
    import imucalib.io.import_spec as import_spec

    real = import_spec.iter_imu_table
    monkeypatch.setattr(import_spec, "iter_imu_table",
                        lambda path, spec=None, **kw: real(path, spec, chunk_rows=CHUNK))
    data = _canonical_with(tmp_path, 30, "0.31,0.1,0.2,0.3,0.0,x,9.8")
    res_path, _ = _result(tmp_path)
    out = tmp_path / "o.csv"
    out.write_text("an earlier output\n", encoding="utf-8")
    done = runner.invoke(app, ["apply", str(res_path), str(data), "--out", str(out)])
    assert done.exit_code == 2, done.output
    assert done.stderr == (f"error: {data}: column 'accel_y_mps2' holds a non-numeric value "
                           "'x' at data row 31 (line 32) (numbers expected; a missing value is "
                           "written NaN)\n")
    assert out.read_text(encoding="utf-8") == "an earlier output\n"
    assert not (tmp_path / "o.csv.part").exists()


def test_apply_refuses_import_options_for_a_recording(tmp_path):
    res_path, _ = _result(tmp_path)
    rec = tmp_path / "run.h5"
    rec.write_bytes(b"")
    done = runner.invoke(app, ["apply", str(res_path), str(rec), "--out",
                               str(tmp_path / "o.csv"), "--gyro-unit", "deg/s"])
    assert done.exit_code == 2, done.output
    assert done.stderr == (f"error: {rec} is a Recording: the import options (--import, "
                           "--column-map, --gyro-unit …) apply to a CSV/text file\n")
