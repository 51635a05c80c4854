"""read_imu_csv: every defect of a CSV file refused with a message naming file, column and row."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from imucalib.errors import InvalidInputError, UnitError
from imucalib.io.csv_import import read_imu_csv

GYRO = "gyro_x_rps,gyro_y_rps,gyro_z_rps"


def write(tmp_path: Path, content: str | bytes, name: str = "data.csv") -> Path:
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")
    return path


@pytest.mark.parametrize(("content", "error", "message"), [
    ("", InvalidInputError,
     "{p} is empty: expected a header line (e.g. `time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps`) "
     "and rows of numbers"),
    (f"time_s,{GYRO}\n", InvalidInputError,
     "{p}: no data rows after the header; expected at least one row of numbers"),
    (f"time_s,{GYRO}\n\n\n", InvalidInputError,
     "{p}: no data rows after the header; expected at least one row of numbers"),
    ("\n\ntime_s\n0\n", InvalidInputError,
     "{p}: line 1 is blank; expected the header (e.g. `time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps`)"),
    (b"time_s,gyro\x00_x\n0,1\n", InvalidInputError,
     "{p} is not CSV text: it holds NUL bytes (the first at offset 11), as a binary file does"),
    (b"\xff\xfetime_s\n0\n", InvalidInputError,
     "{p} is not UTF-8 text: byte 0xff at offset 0 cannot be decoded (a binary file, or text in "
     "another encoding: save it as UTF-8)"),
    (b"time_s,gyro_x_rps\n0,1\n1,\xe9\n", InvalidInputError,
     "{p} is not UTF-8 text: byte 0xe9 after the header cannot be decoded (a binary file, or "
     "text in another encoding: save it as UTF-8)"),
    ("time_s,time_s [furlong],gyro_x_rps\n0,0,1\n", UnitError,
     "{p}: column 'time_s [furlong]' has an unknown unit 'furlong'; time_s is a time, expected "
     "one of s, ms, us, ns, min, h"),
    ("time_s,gyro_x_rps,gyro_x_rps [deg/h]\n0,1,1\n", InvalidInputError,
     "{p}: columns 'gyro_x_rps' and 'gyro_x_rps [deg/h]' (header fields 2 and 3) both hold "
     "gyro_x_rps; expected one column per quantity"),
    ("time_s [s],time_s [ms]\n0,0\n", InvalidInputError,
     "{p}: columns 'time_s [s]' and 'time_s [ms]' (header fields 1 and 2) both hold time_s; "
     "expected one column per quantity"),
    ("time_s,gyro_x_rps [m/s^2]\n0,1\n", UnitError,
     "{p}: column 'gyro_x_rps [m/s^2]' has a unit of another quantity, 'm/s^2'; gyro_x_rps is "
     "an angular rate, expected one of rad/s, deg/s, °/s, dps, deg/h, °/h, dph, rpm"),
    ("time_s,pressure [bananas]\n0,1\n", UnitError,
     "{p}: column 'pressure [bananas]' has an unknown unit 'bananas'; expected a unit such as "
     "rad/s, deg/s, deg/h, m/s^2, g, s, ms, degC, counts or 1 (imucalib.units.parse_unit lists "
     "them all)"),
    ("time_s;gyro_x_rps\n0;1\n", InvalidInputError,
     "{p}: header field 1 'time_s;gyro_x_rps' is not `name` or `name [unit]` (a name starts "
     "with a letter) (fields are separated by commas: give `--delimiter`)"),
    ("time_s,gyro_x_rps,\n0,1,2\n", InvalidInputError,
     "{p}: header field 3 is empty; expected `name` or `name [unit]` (a trailing comma?)"),
    (f"{GYRO}\n0,0,0\n", InvalidInputError,
     "{p}: no time column among the columns found ['gyro_x_rps', 'gyro_y_rps', 'gyro_z_rps']; "
     "name it with `--time-column NAME` (or `column_map` to 'time_s'), or give "
     "`--sample-rate-hz`; map the others with `--column-map gx=NAME,...` or an `--import` file "
     "(docs/import.md)"),
    ("time_s,a,b\n0,1,2\n1,2\n2,3,4\n", InvalidInputError,
     "{p}: line 3 has 2 fields; the header has 3 (a ragged row)"),
    ("time_s,a,b\n0,1,2\n1,2,3,4\n", InvalidInputError,
     "{p}: line 3 has 4 fields; the header has 3 (a ragged row)"),
    ("time_s,a,b\n0,1,2,9\n1,2,3\n", InvalidInputError,
     "{p}: line 2 has 4 fields; the header has 3 (a ragged row)"),
    ("time_s,a\n0,1\n\n1,\n", InvalidInputError,
     "{p}: column 'a' is empty at data row 2 (line 4) (a number expected; a missing value is "
     "written NaN)"),
    ("time_s,gyro_x_rps\n0,1\n0.01,x1\n", InvalidInputError,
     "{p}: column 'gyro_x_rps' holds a non-numeric value 'x1' at data row 2 (line 3) (numbers "
     "expected; a missing value is written NaN)"),
    ("time_s,gyro_x_rps\n0,1\nNaN,1\n", InvalidInputError,
     "{p}: column 'time_s' holds NaN at data row 2 (line 3); time_s and the gyro and "
     "accelerometer columns must be finite (1 such cell(s))"),
    ("time_s,accel_z_mps2\n0,1\n1,-inf\n2,inf\n", InvalidInputError,
     "{p}: column 'accel_z_mps2' holds -inf at data row 2 (line 3); time_s and the gyro and "
     "accelerometer columns must be finite (2 such cell(s))"),
    ("time_s,gyro_x_rps [deg/s]\n0,1\n1,1e999\n", InvalidInputError,
     "{p}: column 'gyro_x_rps' holds inf at data row 2 (line 3); time_s and the gyro and "
     "accelerometer columns must be finite (1 such cell(s))"),
    ("time_s,temperature_degc\n0,inf\n1,1\n", InvalidInputError,
     "{p}: column 'temperature_degc' holds inf at data row 1 (line 2); values must be finite "
     "numbers or NaN (missing) (1 such cell(s))"),
    ("time_s,gyro_x_rps\n0,1\n2,1\n1,1\n", InvalidInputError,
     "{p}: time_s decreases at data row 3 (line 4): 1.0 s after 2.0 s; times must not decrease "
     "(1 such step(s))"),
    ("time_s,gyro_x_rps\n0,1\n1e300,1\n", InvalidInputError,
     "{p}: time_s 1e+300 s at data row 2 (line 3) is beyond ±1e+10 s; expected seconds (give "
     "another unit in the header, e.g. `time_s [ms]`)"),
    ("time_s [h],gyro_x_rps\n0,1\n1e4,1\n", InvalidInputError,
     "{p}: time_s spans 3.6e+07 s (from 0.0 to 36000000.0); expected at most 3.16224e+07 s "
     "(366 days) in one file"),
])
def test_defects_are_named(tmp_path, content, error, message):
    path = write(tmp_path, content)
    with pytest.raises(error, match="^" + re.escape(message.format(p=path)) + "$"):
        read_imu_csv(path)


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(InvalidInputError, match=re.escape(
            f"cannot read CSV {tmp_path / 'no.csv'}: No such file or directory")):
        read_imu_csv(tmp_path / "no.csv")
    with pytest.raises(InvalidInputError, match=re.escape(
            f"cannot read CSV {tmp_path}: Is a directory")):
        read_imu_csv(tmp_path)


def test_a_header_line_without_end_is_refused(tmp_path):
    path = write(tmp_path, "x" * 70000)
    with pytest.raises(InvalidInputError, match="the first line is longer than 65536 bytes"):
        read_imu_csv(path)


def test_column_map_collisions_name_both_columns(tmp_path):
    path = write(tmp_path, "t,GyrX,gyro_x_rps\n0,1,1\n")
    with pytest.raises(InvalidInputError, match=re.escape(
            "columns 'GyrX' and 'gyro_x_rps' (header fields 2 and 3) both map to gyro_x_rps")):
        read_imu_csv(path, column_map={"t": "time_s", "GyrX": "gyro_x_rps"})
    with pytest.raises(UnitError, match=re.escape(
            "column 'GyrX' has an unknown unit 'furlong/s'; gyro_x_rps is an angular rate")):
        read_imu_csv(path, column_map={"t": "time_s", "GyrX": "gyro_x_rps", "gyro_x_rps": "b"},
                     units={"gyro_x_rps": "furlong/s"})


def test_valid_files_read_as_before(tmp_path):
    text = ("\ufefftime_s [s],device_time_s [s],counter [counts],gyro_x_rps [deg/s],"
            "gyro_y_rps,gyro_z_rps [deg/h],accel_x_mps2 [g],accel_y_mps2,accel_z_mps2 [m/s^2],"
            "temperature_degc [°C],saturated [bool]\r\n"
            "0.0,NaN,0,1,0,3600,1,0,9.8,NaN,False\r\n"
            "\r\n"
            "0.0,0.001,1,2,0,0,0,0,9.8,20.5,True\r\n"
            "0.002,nan,2,-1,0.5,0,0,0,9.8,20.5,False\r\n")
    df = read_imu_csv(write(tmp_path, text))
    assert df.index.name == "time_s" and df.index.tolist() == [0.0, 0.0, 0.002]
    np.testing.assert_allclose(df["gyro_x_rps"], np.radians([1, 2, -1]))
    np.testing.assert_allclose(df["gyro_z_rps"], [np.radians(1.0), 0, 0])
    np.testing.assert_allclose(df["accel_x_mps2"], [9.80665, 0, 0])
    assert np.isnan(df["device_time_s"].iloc[0]) and np.isnan(df["temperature_degc"].iloc[0])
    assert df["saturated"].tolist() == [False, True, False]
    assert df.attrs["units"] == {
        "device_time_s": "s", "counter": "counts", "gyro_x_rps": "rad/s",
        "gyro_y_rps": "rad/s", "gyro_z_rps": "rad/s", "accel_x_mps2": "m/s^2",
        "accel_y_mps2": "m/s^2", "accel_z_mps2": "m/s^2", "temperature_degc": "°C",
        "saturated": "bool"}


def test_an_export_reads_back_exactly(tmp_path):
    rng = np.random.default_rng(3)
    n = 20000
    frame = pd.DataFrame({"time_s": np.arange(n) / 1000.0,
                          **{f"gyro_{a}_rps": rng.normal(0, 1e-3, n) for a in "xyz"},
                          **{f"accel_{a}_mps2": rng.normal(0, 1e-2, n) for a in "xyz"}})
    path = tmp_path / "export.csv"
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(",".join(f"{c} [{'s' if c == 'time_s' else 'rad/s' if 'gyro' in c else 'm/s^2'}]"
                          for c in frame.columns) + "\n")
        frame.to_csv(fh, header=False, index=False, na_rep="NaN", lineterminator="\n")
    df = read_imu_csv(path)
    np.testing.assert_array_equal(df.index.to_numpy(), frame["time_s"].to_numpy())
    np.testing.assert_array_equal(df.to_numpy(), frame.drop(columns="time_s").to_numpy())
