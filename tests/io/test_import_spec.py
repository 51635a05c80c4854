"""Real-format logs read without rewriting: vendor names and units, raw counts, imu_tk's two files,
a ROS export, imucal and plain layouts, a TOML import file; defects named by column and row."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imucalib.errors import InvalidInputError, UnitError
from imucalib.io.import_spec import ImportSpec, load_import_spec, read_imu_table

G0 = 9.80665
D2R = np.pi / 180
VENDOR_MAP = {"gx": "GyroX", "gy": "GyroY", "gz": "GyroZ",
              "ax": "AccX", "ay": "AccY", "az": "AccZ"}
GYRO = ["gyro_x_rps", "gyro_y_rps", "gyro_z_rps"]
ACCEL = ["accel_x_mps2", "accel_y_mps2", "accel_z_mps2"]


def vendor_csv(path: Path, n: int = 100) -> Path:
    rows = "".join(f"{1 + k * 0.01:.2f},-2.5,0.25,0.01,-0.02,1.0,{25 + k * 0.001:.3f}\n"
                   for k in range(n))
    path.write_text("# SensorLog v3 export\n# device IMU-42\n"
                    "GyroX,GyroY,GyroZ,AccX,AccY,AccZ,Temp (C)\n" + rows, encoding="utf-8")
    return path


def test_vendor_names_in_deg_s_and_g_with_a_sample_rate_come_in_as_si(tmp_path):
    spec = ImportSpec(column_map=VENDOR_MAP, gyro_unit="deg/s", accel_unit="g",
                      sample_rate_hz=200.0, skip_rows=2)
    df = read_imu_table(vendor_csv(tmp_path / "v.csv"), spec)
    assert list(df.columns) == GYRO + ACCEL
    assert np.allclose(df.index[:3], [0.0, 0.005, 0.010])
    assert df["gyro_x_rps"].iloc[10] == pytest.approx(1.1 * D2R)
    assert df["gyro_y_rps"].iloc[0] == pytest.approx(-2.5 * D2R)
    assert df["accel_z_mps2"].iloc[0] == pytest.approx(G0)
    assert df.attrs["units"]["gyro_x_rps"] == "rad/s"


def test_raw_counts_with_scale_and_offset(tmp_path):
    # an MPU-6050 style log: 131 counts per °/s, 16384 counts per g, a semicolon separator
    p = tmp_path / "raw.csv"
    p.write_text("t;ax;ay;az;gx;gy;gz\n" + "".join(
        f"{k * 0.01:.2f};120;-100;{16384 + 20};{131 * 3.7 + 12:.1f};12;-119\n" for k in range(50)),
        encoding="utf-8")
    spec = ImportSpec(gyro_unit="counts", gyro_scale=131.0, gyro_offset=12.0,
                      accel_unit="counts", accel_scale=16384.0, accel_offset=20.0, delimiter=";")
    df = read_imu_table(p, spec)
    assert df.attrs["layout"] == "plain"
    assert df["gyro_x_rps"].iloc[0] == pytest.approx(3.7 * D2R)
    assert df["gyro_y_rps"].iloc[0] == pytest.approx(0.0)
    assert df["gyro_z_rps"].iloc[0] == pytest.approx(-1.0 * D2R)
    assert df["accel_x_mps2"].iloc[0] == pytest.approx(100 / 16384 * G0)
    assert df["accel_z_mps2"].iloc[0] == pytest.approx(G0)
    assert df.index[1] == pytest.approx(0.01)


def test_counts_without_a_scale_are_refused(tmp_path):
    with pytest.raises(InvalidInputError, match="--gyro-scale"):
        read_imu_table(tmp_path / "x.csv", ImportSpec(gyro_unit="counts"))


def test_plain_layout_without_units_is_refused_naming_the_option(tmp_path):
    p = tmp_path / "p.csv"
    p.write_text("time,ax,ay,az,gx,gy,gz\n0,0,0,1,0,0,0\n", encoding="utf-8")
    with pytest.raises(InvalidInputError, match="--gyro-unit"):
        read_imu_table(p)


def test_imu_tk_two_files(tmp_path):
    gyro = tmp_path / "xsens_gyro.mat"
    acc = tmp_path / "xsens_acc.mat"
    gyro.write_text("".join(f"  {1000 + k * 0.01:.2f}   0.01 -0.02 0.03\n" for k in range(80)),
                    encoding="utf-8")
    acc.write_text("".join(f"{1000 + k * 0.01:.2f} 0.1 0.2 9.7\n" for k in range(80)),
                   encoding="utf-8")
    df = read_imu_table(gyro, ImportSpec(accel_file=acc))
    assert df.attrs["layout"] == "imu_tk"
    assert list(df.columns) == GYRO + ACCEL
    assert df.index[0] == pytest.approx(1000.0)
    assert df.iloc[5].to_numpy() == pytest.approx([0.01, -0.02, 0.03, 0.1, 0.2, 9.7])


def test_ros_bag_csv_export_with_percent_time_in_ns(tmp_path):
    p = tmp_path / "imu.csv"
    head = ("%time,field.header.seq,field.header.frame_id,field.orientation.x,"
            "field.angular_velocity.x,field.angular_velocity.y,field.angular_velocity.z,"
            "field.linear_acceleration.x,field.linear_acceleration.y,field.linear_acceleration.z")
    p.write_text(head + "\n" + "".join(
        f"{1_700_000_000_000_000_000 + k * 5_000_000},{k},imu_link,0,0.1,0.2,0.3,0.0,0.1,9.8\n"
        for k in range(40)), encoding="utf-8")
    df = read_imu_table(p)
    assert df.attrs["layout"] == "ros-imu"
    assert df.index[1] - df.index[0] == pytest.approx(0.005, abs=1e-6)
    assert df["gyro_z_rps"].iloc[0] == pytest.approx(0.3)
    assert df["accel_z_mps2"].iloc[0] == pytest.approx(9.8)


def test_imucal_layout_is_m_s2_and_deg_s(tmp_path):
    p = tmp_path / "imucal.csv"
    p.write_text("acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n" + "0,0,9.81,90,0,0\n" * 10,
                 encoding="utf-8")
    df = read_imu_table(p, ImportSpec(sample_rate_hz=100.0))
    assert df.attrs["layout"] == "imucal"
    assert df["gyro_x_rps"].iloc[0] == pytest.approx(np.pi / 2)
    assert df["accel_z_mps2"].iloc[0] == pytest.approx(9.81)


def test_toml_import_file_and_command_line_override(tmp_path):
    spec_path = tmp_path / "spec.toml"
    spec_path.write_text('skip_rows = 2\nsample_rate_hz = 100.0\ngyro_unit = "deg/s"\n'
                         'accel_unit = "g"\n[columns]\n'
                         + "".join(f'{k} = "{v}"\n' for k, v in VENDOR_MAP.items()),
                         encoding="utf-8")
    spec = load_import_spec(spec_path).merged(sample_rate_hz=200.0)
    assert spec.sample_rate_hz == 200.0 and spec.column_map["gx"] == "GyroX"
    df = read_imu_table(vendor_csv(tmp_path / "v.csv"), spec)
    assert df.index[1] == pytest.approx(0.005)
    bad = tmp_path / "bad.toml"
    bad.write_text('gyro_units = "deg/s"\n', encoding="utf-8")
    with pytest.raises(InvalidInputError, match=r"unknown key\(s\) \['gyro_units'\]"):
        load_import_spec(bad)


def _write(tmp_path: Path, lines: list[str]) -> Path:
    p = tmp_path / "broken.csv"
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return p


def test_a_non_numeric_cell_at_row_57_names_column_and_row(tmp_path):
    rows = [f"{k * 0.005:.3f},1,2,3" for k in range(100)]
    rows[56] = "0.280,1,oops,3"
    p = _write(tmp_path, ["Time,GyroX,GyroY,GyroZ", *rows])
    spec = ImportSpec(column_map={"t": "Time", "gx": "GyroX", "gy": "GyroY", "gz": "GyroZ"},
                      gyro_unit="deg/s")
    with pytest.raises(InvalidInputError,
                       match=r"column 'gyro_y_rps' holds a non-numeric value 'oops' at data row "
                             r"57 \(line 58\)"):
        read_imu_table(p, spec)


def test_nan_in_a_gyro_column_names_column_and_row(tmp_path):
    rows = [f"{k * 0.005:.3f},1,2,3" for k in range(20)]
    rows[9] = "0.045,1,2,NaN"
    p = _write(tmp_path, ["t,gx,gy,gz", *rows])
    with pytest.raises(InvalidInputError,
                       match=r"column 'gyro_z_rps' holds NaN at data row 10 \(line 11\)"):
        read_imu_table(p, ImportSpec(gyro_unit="rad/s", accel_unit="g"))


def test_time_going_backwards_names_the_row(tmp_path):
    rows = [f"{k * 0.005:.3f},1,2,3" for k in range(20)]
    rows[12] = "0.010,1,2,3"
    p = _write(tmp_path, ["t,gx,gy,gz", *rows])
    with pytest.raises(InvalidInputError, match=r"time_s decreases at data row 13 \(line 14\)"):
        read_imu_table(p, ImportSpec(gyro_unit="deg/s", accel_unit="g"))


def test_a_missing_column_lists_the_columns_found_and_the_options(tmp_path):
    p = _write(tmp_path, ["GyroX,GyroY,GyroZ", "1,2,3", "1,2,3"])
    with pytest.raises(InvalidInputError) as err:
        read_imu_table(p)
    msg = str(err.value)
    assert "['GyroX', 'GyroY', 'GyroZ']" in msg and "--column-map" in msg
    assert "--sample-rate-hz" in msg and "\n" not in msg
    with pytest.raises(InvalidInputError, match="--time-column 'Stamp' is not in the header"):
        read_imu_table(p, ImportSpec(time_column="Stamp"))


def test_an_unknown_unit_is_a_unit_error_naming_the_column(tmp_path):
    p = _write(tmp_path, ["t,gx,gy,gz", "0,1,2,3", "1,1,2,3"])
    with pytest.raises(UnitError, match="column 'gx' has an unknown unit 'furlong/s'"):
        read_imu_table(p, ImportSpec(gyro_unit="furlong/s", accel_unit="g"))


def test_vendor_columns_mapped_without_a_unit_are_refused_unless_their_names_carry_one(tmp_path):
    # issue 27: `--column-map gx=GyrX,…` alone read °/s as rad/s and g as m/s² without a word
    rows = [f"{k * 10},1.0,-2.0,0.5,0.0,0.0,1.0" for k in range(20)]
    bare = _write(tmp_path, ["Time,GyrX,GyrY,GyrZ,AccX,AccY,AccZ", *rows])
    cmap = {"t": "Time", "gx": "GyrX", "gy": "GyrY", "gz": "GyrZ", "ax": "AccX", "ay": "AccY",
            "az": "AccZ"}
    with pytest.raises(UnitError, match=r"the gyro column\(s\) \['GyrX', 'GyrY', 'GyrZ'\] are "
                                        r"mapped by the column map without a unit.*--gyro-unit"):
        read_imu_table(bare, ImportSpec(column_map=cmap, time_unit="ms"))
    with pytest.raises(UnitError, match=r"the accelerometer column\(s\).*--accel-unit"):
        read_imu_table(bare, ImportSpec(column_map=cmap, time_unit="ms", gyro_unit="deg/s"))
    named = tmp_path / "named.csv"
    named.write_text("Time,gyr_x_dps,gyr_y_dps,gyr_z_dps,acc_x[g],acc_y[g],acc_z[g]\n"
                     + "\n".join(rows) + "\n", encoding="utf-8")
    df = read_imu_table(named, ImportSpec(column_map={
        "t": "Time", "gx": "gyr_x_dps", "gy": "gyr_y_dps", "gz": "gyr_z_dps", "ax": "acc_x[g]",
        "ay": "acc_y[g]", "az": "acc_z[g]"}, time_unit="ms"))
    assert df["gyro_x_rps"].iloc[0] == pytest.approx(np.radians(1.0))
    assert df["accel_z_mps2"].iloc[0] == pytest.approx(9.80665)


@pytest.mark.parametrize(("delimiter", "message"), [
    ("", "--delimiter must be one character, 'tab' or 'whitespace'; got ''"),
    (";;", "got ';;'"),
    ("1", "--delimiter '1' cannot separate fields"),
    ("\"", "cannot separate fields"),
])
def test_a_delimiter_that_cannot_separate_fields_is_refused(tmp_path, delimiter, message):
    p = _write(tmp_path, ["t,gx,gy,gz", "0,1,2,3", "0.01,1,2,3"])
    with pytest.raises(InvalidInputError, match=message.replace("(", r"\(")):
        read_imu_table(p, ImportSpec(delimiter=delimiter, gyro_unit="deg/s"))


def test_gyro_and_accelerometer_values_beyond_any_sensor_are_refused(tmp_path):
    rows = [f"{k * 0.01:.2f},1,2,3,0,0,9.8" for k in range(10)]
    rows[4] = "0.04,1,2,3,0,0,2e7"
    p = _write(tmp_path, ["time_s,gyro_x_rps,gyro_y_rps,gyro_z_rps,accel_x_mps2,accel_y_mps2,"
                          "accel_z_mps2", *rows])
    with pytest.raises(InvalidInputError, match=r"column 'accel_z_mps2' holds 20000000.0 m/s\^2 "
                                                r"at data row 5 \(line 6\); an accelerometer reads "
                                                r"at most ±1e\+07 m/s\^2"):
        read_imu_table(p)
