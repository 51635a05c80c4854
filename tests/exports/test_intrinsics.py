"""Intrinsics exports: MATLAB v5 / v7.3, ROS YAML, OpenVINS (docs/exports.md).

Each format is read back with an independent reader (scipy.io.loadmat, h5py, yaml.safe_load)
and compared with the result; the OpenVINS file is applied the way OpenVINS' loader and
propagator do (Eqs. (X2), (X3) of :mod:`imucalib.exports.intrinsics`, re-implemented here
from its documentation) to samples made by imucalib's forward model.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pytest
import yaml
from scipy.io import loadmat
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import InvalidInputError
from imucalib.exports.intrinsics import (
    format_ros_yaml,
    intrinsics_struct,
    kalibr_intrinsics,
    openvins_intrinsics,
    write_kalibr_intrinsics,
    write_mat,
    write_mat73,
    write_openvins_intrinsics,
)
from imucalib.exports.outputs import OUTPUT_FORMATS
from imucalib.models.result import CalibrationResult, triad_parameter_names
from imucalib.models.triad import apply_triad

_NEW = ("mat", "mat73", "ros-yaml", "kalibr-imu", "openvins-imu")


def _result(*, k2: bool = True, model: str = "triad", seed: int = 3) -> CalibrationResult:
    rng = np.random.default_rng(seed)
    if model == "triad":
        names = [*triad_parameter_names("gyro", "triad", g_sensitivity=True),
                 *triad_parameter_names("accel", "triad", k2=k2)]
        scale = {"bias": 0.05, "M": 3e-3, "G": 2e-4, "K2": 1e-4}
        values = np.array([rng.normal() * scale[n.split("_")[1]] for n in names])
    else:
        names = [*triad_parameter_names("gyro", "per-axis"),
                 *triad_parameter_names("accel", "per-axis")]
        values = np.array([(1.0 + rng.normal() * 2e-3) if n.split("_")[1] == "K"
                           else rng.normal() * 0.05 for n in names])
    k = len(names)
    a = rng.normal(size=(k, k)) * 1e-4
    return CalibrationResult(sensor_id='IMU "7"/ü*/', procedure="p1", model=model,
                             param_names=tuple(names), values=values, covariance=a @ a.T,
                             units={n: f"u{i}" for i, n in enumerate(names)})


def test_struct_matrices_follow_the_parameter_names() -> None:
    cal = _result()
    s = intrinsics_struct(cal)
    assert s["M_a"][0, 1] == cal.value("accel_M_xy")  # row sensor axis, column input axis
    assert s["M_g"][2, 0] == cal.value("gyro_M_zx")
    assert s["G_g"][1, 2] == cal.value("gyro_G_yz")
    assert s["b_g"][1] == cal.value("gyro_bias_y")
    assert s["K2_a"][2] == cal.value("accel_K2_z")
    per_axis = _result(model="per-axis")
    p = intrinsics_struct(per_axis)
    k, b = per_axis.value("accel_K_y"), per_axis.value("accel_b_y")
    assert p["M_a"][1, 1] == k - 1.0 and p["M_a"][0, 1] == 0.0
    assert p["b_a"][1] == pytest.approx(k * b, rel=1e-15)


def test_mat_v5_round_trip_is_exact(tmp_path: Path) -> None:
    cal = _result()
    path = write_mat(cal, tmp_path / "r.mat")
    m = loadmat(path)["imucal"][0, 0]
    s = intrinsics_struct(cal)
    for key in ("M_a", "M_g", "G_g", "covariance"):
        np.testing.assert_array_equal(m[key], s[key])
    for key in ("b_a", "b_g", "K2_a", "values"):
        np.testing.assert_array_equal(m[key].ravel(), s[key])
    assert [str(n).rstrip() for n in m["param_names"]] == list(cal.param_names)
    assert [str(u).rstrip() for u in m["units"]][3] == "u3"
    assert str(m["sensor_id"][0]) == cal.sensor_id
    assert str(m["procedure"][0]) == "p1"


def test_mat73_is_hdf5_with_the_matlab_header_and_round_trips(tmp_path: Path) -> None:
    cal = _result()
    path = write_mat73(cal, tmp_path / "r73.mat")
    head = path.read_bytes()[:128]
    assert head.startswith(b"MATLAB 7.3 MAT-file")
    assert head[124:128] == b"\x00\x02IM"
    s = intrinsics_struct(cal)
    with h5py.File(path, "r") as fh:
        g = fh["imucal"]
        assert g.attrs["MATLAB_class"] == b"struct"
        assert [b"".join(f).decode() for f in g.attrs["MATLAB_fields"]] == list(s)
        assert g["M_a"].attrs["MATLAB_class"] == b"double"
        for key in ("M_a", "M_g", "G_g", "covariance"):
            np.testing.assert_array_equal(g[key][()].T, s[key])
        for key in ("b_a", "b_g", "K2_a", "values"):
            assert g[key].shape == (1, len(s[key]))  # a MATLAB column, stored transposed
            np.testing.assert_array_equal(g[key][()].ravel(), s[key])
        assert g["sensor_id"].attrs["MATLAB_class"] == b"char"
        sensor = "".join(chr(c) for c in g["sensor_id"][()].T.ravel())
        assert sensor == cal.sensor_id
        names = ["".join(chr(c) for c in row).rstrip() for row in g["param_names"][()].T]
        assert names == list(cal.param_names)


def test_ros_yaml_round_trip_is_exact() -> None:
    cal = _result()
    doc = yaml.safe_load(format_ros_yaml(cal))
    s = intrinsics_struct(cal)
    assert doc["sensor_id"] == cal.sensor_id
    np.testing.assert_array_equal(doc["accel"]["bias"], s["b_a"])
    np.testing.assert_array_equal(np.reshape(doc["gyro"]["scale_misalignment"], (3, 3)),
                                  np.eye(3) + s["M_g"])
    np.testing.assert_array_equal(np.reshape(doc["gyro"]["g_sensitivity"], (3, 3)), s["G_g"])
    np.testing.assert_array_equal(doc["accel"]["k2"], s["K2_a"])
    k = len(cal.param_names)
    np.testing.assert_array_equal(np.reshape(doc["covariance"], (k, k)), cal.covariance)
    np.testing.assert_array_equal(doc["values"], cal.values)
    assert doc["parameters"] == list(cal.param_names)
    assert doc["units"][5] == "u5"


def _openvins_correct(doc: dict, gyro_m: np.ndarray, accel_m: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """OpenVINS' loader (D = T⁻¹, lower triangle kept, R_xtoIMU = R_IMUtox ᵀ) and propagator."""
    imu = doc["imu0"]
    d_w = np.tril(np.linalg.inv(np.array(imu["Tw"])))
    d_a = np.tril(np.linalg.inv(np.array(imu["Ta"])))
    r_gyro_to_imu = np.array(imu["R_IMUtoGYRO"]).T
    r_acc_to_imu = np.array(imu["R_IMUtoACC"]).T
    t_g = np.array(imu["Tg"])
    b_g, b_a = np.array(imu["imucalib_bias_gyro"]), np.array(imu["imucalib_bias_accel"])
    a_hat = (r_acc_to_imu @ d_a @ (accel_m - b_a).T).T
    w_hat = (r_gyro_to_imu @ d_w @ (gyro_m - b_g - (t_g @ a_hat.T).T).T).T
    return w_hat, a_hat


def test_openvins_intrinsics_invert_the_forward_model(tmp_path: Path) -> None:
    cal = _result(k2=False)
    path = write_openvins_intrinsics(cal, tmp_path / "imu.yaml")
    doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    imu = doc["imu0"]
    for key in ("Tw", "Ta"):  # the kalibr model: lower triangular, positive diagonal
        t = np.array(imu[key])
        assert np.all(np.triu(t, 1) == 0.0) and np.all(np.diag(t) > 0)
    for key in ("R_IMUtoGYRO", "R_IMUtoACC"):
        r = np.array(imu[key])
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-14)
        assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-14)
        assert np.max(np.abs(r - np.eye(3))) > 1e-4  # a real rotation: M is not triangular
    rng = np.random.default_rng(8)
    f_true = rng.normal(size=(200, 3)) * 9.81
    w_true = rng.normal(size=(200, 3)) * 2.0
    accel_m = apply_triad(cal.triad_model("accel"), f_true)
    gyro_m = apply_triad(cal.triad_model("gyro"), w_true, specific_force_b_mps2=f_true)
    w_hat, a_hat = _openvins_correct(doc, gyro_m, accel_m)
    assert np.max(np.abs(a_hat - f_true)) < 1e-9
    assert np.max(np.abs(w_hat - w_true)) < 1e-9
    # without the rotations (the file misread) the correction is visibly wrong
    imu["R_IMUtoGYRO"] = np.eye(3).tolist()
    w_bad, _ = _openvins_correct(doc, gyro_m, accel_m)
    assert np.max(np.abs(w_bad - w_true)) > 1e-4


def test_kalibr_intrinsics_invert_the_forward_model(tmp_path: Path) -> None:
    """Kalibr's IccScaledMisalignedImu (X4), inverted: a_i = M⁻¹(a_m − b_a), then ω_i."""
    cal = _result(k2=False)
    doc = yaml.safe_load(write_kalibr_intrinsics(cal, tmp_path / "k.yaml").read_text("utf-8"))
    assert doc["model"] == "scale-misalignment"
    m_a, m_g = np.array(doc["accelerometers"]["M"]), np.array(doc["gyroscopes"]["M"])
    a, c_gyro_i = np.array(doc["gyroscopes"]["A"]), np.array(doc["gyroscopes"]["C_gyro_i"])
    c_i_s = np.array(doc["imucalib_C_i_sensor"])
    for m in (m_a, m_g):  # Kalibr's design variables: lower triangular
        assert np.all(np.triu(m, 1) == 0.0) and np.all(np.diag(m) > 0)
    for r in (c_gyro_i, c_i_s):
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-14)
        assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-14)
    rng = np.random.default_rng(9)
    f_true = rng.normal(size=(200, 3)) * 9.81
    w_true = rng.normal(size=(200, 3)) * 2.0
    accel_m = apply_triad(cal.triad_model("accel"), f_true)
    gyro_m = apply_triad(cal.triad_model("gyro"), w_true, specific_force_b_mps2=f_true)
    b_a, b_g = np.array(doc["imucalib_bias_accel"]), np.array(doc["imucalib_bias_gyro"])
    a_i = np.linalg.solve(m_a, (accel_m - b_a).T).T
    w_i = (c_gyro_i.T @ np.linalg.solve(m_g, (gyro_m - b_g - (a @ c_gyro_i @ a_i.T).T).T)).T
    assert np.max(np.abs(a_i - f_true @ c_i_s.T)) < 1e-9  # the input, in Kalibr's frame i
    assert np.max(np.abs(w_i - w_true @ c_i_s.T)) < 1e-9
    assert np.max(np.abs(c_i_s - np.eye(3))) > 1e-4  # i is not S: the rotation matters


def test_a_gyro_only_result(tmp_path: Path) -> None:
    full = _result(k2=False)
    names = [n for n in full.param_names if n.startswith("gyro_")]
    idx = [full.param_names.index(n) for n in names]
    cal = CalibrationResult(sensor_id="G", procedure="p1", model="triad",
                            param_names=tuple(names), values=full.values[idx],
                            covariance=full.covariance[np.ix_(idx, idx)],
                            units={n: "1" for n in names})
    s = intrinsics_struct(cal)
    assert "M_a" not in s and "b_a" not in s and s["G_g"][0, 1] == cal.value("gyro_G_xy")
    ov = openvins_intrinsics(cal)
    np.testing.assert_array_equal(ov["Ta"], np.eye(3))
    np.testing.assert_array_equal(ov["R_IMUtoACC"], np.eye(3))
    with pytest.raises(InvalidInputError, match="both the gyro and the accelerometer"):
        kalibr_intrinsics(cal)
    m = loadmat(write_mat(cal, tmp_path / "g.mat"))["imucal"][0, 0]
    assert "M_a" not in m.dtype.names and m["M_g"].shape == (3, 3)


def test_openvins_and_kalibr_refuse_k2() -> None:
    with pytest.raises(InvalidInputError, match="K2"):
        openvins_intrinsics(_result(k2=True))
    with pytest.raises(InvalidInputError, match="K2"):
        kalibr_intrinsics(_result(k2=True))


def test_formats_are_registered_and_need_a_calibration(tmp_path: Path) -> None:
    cal = _result(k2=False)
    wrapped = SimpleNamespace(result=cal, procedure="p1", unit="U")
    for fmt in _NEW:
        (path,) = OUTPUT_FORMATS[fmt](wrapped, tmp_path, "n.U.p1")
        assert path.is_file() and path.stat().st_size > 0
    with pytest.raises(InvalidInputError, match="needs a calibration result"):
        OUTPUT_FORMATS["mat"](SimpleNamespace(result=None, procedure="allan"), tmp_path, "x")


def test_cli_exports_a_result_as_ros_yaml(tmp_path: Path) -> None:
    cal = replace(_result(), sensor_id="IMU-7")  # the id names the file: no "/" in it
    src = tmp_path / "run.result.json"
    src.write_text(cal.to_json(), encoding="utf-8")
    out = CliRunner().invoke(app, ["export", str(src), "--format", "ros-yaml",
                                   "--out", str(tmp_path / "o")])
    assert out.exit_code == 0, out.output
    (written,) = (tmp_path / "o").glob("*.ros.yaml")
    assert yaml.safe_load(written.read_text(encoding="utf-8"))["values"] == list(cal.values)
