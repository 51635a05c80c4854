"""Intrinsics exports: MATLAB v5 / v7.3, ROS YAML, OpenVINS (docs/exports.md).

Each format is read back with an independent reader (scipy.io.loadmat, h5py, yaml.safe_load)
and compared with the result; the OpenVINS file is applied the way OpenVINS' loader and
propagator do (Eqs. (X2), (X3) of :mod:`imucalib.exports.intrinsics`, re-implemented here
from its documentation) to samples made by imucalib's forward model.
"""

from __future__ import annotations

import dataclasses
from dataclasses import replace
from pathlib import Path

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
from imucalib.models.result_document import stored_from_calibration
from imucalib.models.temperature_record import HeldOutOutcome, ParameterTemperatureModel
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
    wrapped = stored_from_calibration(cal)
    for fmt in _NEW:
        (path,) = OUTPUT_FORMATS[fmt](wrapped, tmp_path, "n.U.p1")
        assert path.is_file() and path.stat().st_size > 0
    without = dataclasses.replace(wrapped, calibration=None, procedure="allan")
    with pytest.raises(InvalidInputError, match="'mat' needs a whole triad model; this allan"):
        OUTPUT_FORMATS["mat"](without, tmp_path, "x")


def test_cli_exports_a_result_as_ros_yaml(tmp_path: Path) -> None:
    cal = replace(_result(), sensor_id="IMU-7")  # the id names the file: no "/" in it
    src = tmp_path / "run.result.json"
    src.write_text(cal.to_json(), encoding="utf-8")
    out = CliRunner().invoke(app, ["export", str(src), "--format", "ros-yaml",
                                   "--out", str(tmp_path / "o")])
    assert out.exit_code == 0, out.output
    (written,) = (tmp_path / "o").glob("*.ros.yaml")
    assert yaml.safe_load(written.read_text(encoding="utf-8"))["values"] == list(cal.values)


# --- temperature models (Eq. (T1)) -----------------------------------------------------------

T0 = 25.0
#: parameter → (c_1 … c_m, rate d or None, leg h or None, fitted range or None, held out?)
_MODELS = {
    "gyro_bias_x": ((2e-4, -3e-6), 4e-3, 1e-4, (-20.0, 60.0), True),
    "gyro_M_zz": ((1e-5,), 2e-4, None, (-30.0, 80.0), False),
    "gyro_G_yz": ((), None, None, (-30.0, 80.0), False),
    "accel_bias_z": ((-5e-4, 1e-6, -2e-8), None, 3e-4, None, False),
    "accel_M_xy": ((4e-6,), None, None, (-10.0, 70.0), False),
}
#: the intersection of the ranges above
_RANGE = (-10.0, 60.0)


def _temperature_result(*, k2: bool = False, model: str = "triad",
                        models: dict[str, tuple] | None = None) -> CalibrationResult:
    """:func:`_result` with temperature models, each with a full random covariance."""
    base = _result(k2=k2, model=model)
    rng = np.random.default_rng(21)
    records = []
    for name, (cs, d, h, span, held) in (models or _MODELS).items():
        q = 1 + len(cs) + (d is not None) + (h is not None)
        a = rng.normal(size=(q, q)) * 1e-5
        records.append(ParameterTemperatureModel(
            name=name, reference_temperature_degc=T0, coefficients=(base.value(name), *cs),
            rate_coefficient=d, leg_coefficient=h, covariance=a @ a.T,
            chi2=float(rng.uniform(1, 9)), dof=7, order_criterion="aicc",
            temperature_range_degc=span,
            held_out=HeldOutOutcome(1.25, 3.5, 4, 0.47, True) if held else None))
    return replace(base, temperature_models=tuple(records))


def _terms(tm: ParameterTemperatureModel) -> list[str]:
    return ([f"c_{j}" for j in range(len(tm.coefficients))]
            + (["d"] if tm.rate_coefficient is not None else [])
            + (["h"] if tm.leg_coefficient is not None else []))


def _nan_or(value: float | None) -> float:
    return float("nan") if value is None else value


def test_mat_v5_carries_the_temperature_models(tmp_path: Path) -> None:
    cal = _temperature_result()
    m = loadmat(write_mat(cal, tmp_path / "t.mat"))["imucal"][0, 0]
    tms = m["temperature_models"][0, 0]
    assert sorted(tms.dtype.names) == sorted(_MODELS)
    for tm in cal.temperature_models:
        s = tms[tm.name][0, 0]
        assert str(s["name"][0]) == tm.name
        assert s["reference_temperature_degc"][0, 0] == T0
        assert s["coefficients"].shape == (len(tm.coefficients), 1)  # a column
        np.testing.assert_array_equal(s["coefficients"].ravel(), tm.coefficients)
        np.testing.assert_array_equal(s["covariance"], np.atleast_2d(tm.covariance))
        np.testing.assert_array_equal(s["rate_coefficient"][0, 0], _nan_or(tm.rate_coefficient))
        np.testing.assert_array_equal(s["leg_coefficient"][0, 0], _nan_or(tm.leg_coefficient))
        assert [str(t).rstrip() for t in s["covariance_terms"]] == _terms(tm)
        assert s["temperature_range_degc"].shape == (1, 2)
        np.testing.assert_array_equal(s["temperature_range_degc"][0],
                                      tm.temperature_range_degc or (np.nan, np.nan))
        assert s["chi2"][0, 0] == tm.chi2 and s["dof"][0, 0] == tm.dof
        assert str(s["order_criterion"][0]) == "aicc"
        ho = tm.held_out
        np.testing.assert_array_equal(
            [s[f"held_out_{k}"][0, 0] for k in ("max_abs_z", "chi2", "dof", "p_value",
                                                "consistent")],
            [np.nan] * 5 if ho is None else [ho.max_abs_z, ho.chi2, ho.dof, ho.p_value, 1.0])
    # the values hold at T0 (c_0), and a result without models has no such field
    np.testing.assert_array_equal(m["values"].ravel(), cal.values)
    plain = loadmat(write_mat(_result(), tmp_path / "p.mat"))["imucal"][0, 0]
    assert "temperature_models" not in plain.dtype.names


def test_mat73_carries_the_temperature_models(tmp_path: Path) -> None:
    cal = _temperature_result()
    path = write_mat73(cal, tmp_path / "t73.mat")
    with h5py.File(path, "r") as fh:
        g = fh["imucal"]
        assert b"".join(g.attrs["MATLAB_fields"][-1]).decode() == "temperature_models"
        tms = g["temperature_models"]
        assert tms.attrs["MATLAB_class"] == b"struct"
        assert sorted(b"".join(f).decode() for f in tms.attrs["MATLAB_fields"]) == sorted(_MODELS)
        for tm in cal.temperature_models:
            s = tms[tm.name]
            assert s.attrs["MATLAB_class"] == b"struct"
            assert "".join(chr(c) for c in s["name"][()].T.ravel()) == tm.name
            assert s["coefficients"].shape == (1, len(tm.coefficients))  # a column, transposed
            np.testing.assert_array_equal(s["coefficients"][()].ravel(), tm.coefficients)
            np.testing.assert_array_equal(s["covariance"][()].T, np.atleast_2d(tm.covariance))
            np.testing.assert_array_equal(s["rate_coefficient"][()].item(),
                                          _nan_or(tm.rate_coefficient))
            np.testing.assert_array_equal(s["leg_coefficient"][()].item(),
                                          _nan_or(tm.leg_coefficient))
            np.testing.assert_array_equal(s["temperature_range_degc"][()].T,
                                          [tm.temperature_range_degc or (np.nan, np.nan)])
            assert s["reference_temperature_degc"][()].item() == T0
            assert s["chi2"][()].item() == tm.chi2 and s["dof"][()].item() == tm.dof
            terms = ["".join(chr(c) for c in row).rstrip() for row in s["covariance_terms"][()].T]
            assert terms == _terms(tm)
            assert "".join(chr(c) for c in s["order_criterion"][()].T.ravel()) == "aicc"
            held = s["held_out_p_value"][()].item()
            assert held == 0.47 if tm.held_out else np.isnan(held)


def test_ros_yaml_carries_the_temperature_models() -> None:
    cal = _temperature_result()
    doc = yaml.safe_load(format_ros_yaml(cal))
    tms = doc["temperature_models"]
    assert sorted(tms) == sorted(_MODELS)
    for tm in cal.temperature_models:
        d = tms[tm.name]
        assert d["reference_temperature_degc"] == T0
        assert d["coefficients"] == list(tm.coefficients)  # exact: repr floats
        assert d["rate_coefficient"] == tm.rate_coefficient  # None ↔ null
        assert d["leg_coefficient"] == tm.leg_coefficient
        q = tm.n_terms
        np.testing.assert_array_equal(np.reshape(d["covariance"], (q, q)), tm.covariance)
        assert d["covariance_terms"] == _terms(tm)
        rng = d["temperature_range_degc"]
        assert (rng is None and tm.temperature_range_degc is None) \
            or tuple(rng) == tm.temperature_range_degc
        assert (d["chi2"], d["dof"], d["order_criterion"]) == (tm.chi2, tm.dof, "aicc")
        ho = tm.held_out
        assert d["held_out"] == (None if ho is None else {
            "max_abs_z": ho.max_abs_z, "chi2": ho.chi2, "dof": ho.dof, "p_value": ho.p_value,
            "consistent": True})
    assert "temperature_models" not in yaml.safe_load(format_ros_yaml(_result()))


def test_a_per_axis_result_with_temperature_models_exports_to_mat(tmp_path: Path) -> None:
    models = {"accel_K_x": ((1e-5,), None, None, None, False),
              "gyro_b_y": ((2e-4,), None, 5e-5, None, False)}
    cal = _temperature_result(model="per-axis", models=models)
    m = loadmat(write_mat(cal, tmp_path / "pa.mat"))["imucal"][0, 0]
    assert m["M_a"][0, 0] == cal.value("accel_K_x") - 1.0  # at T0
    assert m["temperature_models"][0, 0]["gyro_b_y"][0, 0]["leg_coefficient"][0, 0] == 5e-5


def _at(cal: CalibrationResult, t_degc: float) -> CalibrationResult:
    """The forward model's parameters at `t_degc` (rate 0, mean leg), without the models."""
    values, _ = cal.values_at(t_degc, 0.0, 0.0)
    return replace(cal, values=values[0], temperature_models=())


def _samples(cal: CalibrationResult, seed: int) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    f_true = rng.normal(size=(200, 3)) * 9.81
    w_true = rng.normal(size=(200, 3)) * 2.0
    accel_m = apply_triad(cal.triad_model("accel"), f_true)
    gyro_m = apply_triad(cal.triad_model("gyro"), w_true, specific_force_b_mps2=f_true)
    return f_true, w_true, accel_m, gyro_m


def test_openvins_with_temperature_models_inverts_the_model_at_that_temperature(
        tmp_path: Path) -> None:
    cal, t = _temperature_result(), 55.0
    doc = yaml.safe_load(write_openvins_intrinsics(cal, tmp_path / "o.yaml",
                                                   temperature_degc=t).read_text("utf-8"))
    assert doc["imu0"]["imucalib_temperature_degc"] == t
    f_true, w_true, accel_m, gyro_m = _samples(_at(cal, t), 31)
    w_hat, a_hat = _openvins_correct(doc, gyro_m, accel_m)
    assert np.max(np.abs(a_hat - f_true)) < 1e-9
    assert np.max(np.abs(w_hat - w_true)) < 1e-9
    # the values at T0 would not do: the temperature dependence is in the file
    at_t0 = yaml.safe_load(write_openvins_intrinsics(cal, tmp_path / "o0.yaml",
                                                     temperature_degc=T0).read_text("utf-8"))
    w_0, a_0 = _openvins_correct(at_t0, gyro_m, accel_m)
    assert np.max(np.abs(a_0 - f_true)) > 1e-4 and np.max(np.abs(w_0 - w_true)) > 1e-4
    assert at_t0["imu0"]["imucalib_bias_gyro"] == list(cal.triad_model("gyro").bias)


def test_kalibr_with_temperature_models_inverts_the_model_at_that_temperature(
        tmp_path: Path) -> None:
    cal, t = _temperature_result(), -5.5
    doc = yaml.safe_load(write_kalibr_intrinsics(cal, tmp_path / "k.yaml",
                                                 temperature_degc=t).read_text("utf-8"))
    assert doc["imucalib_temperature_degc"] == t
    f_true, w_true, accel_m, gyro_m = _samples(_at(cal, t), 32)
    m_a, m_g = np.array(doc["accelerometers"]["M"]), np.array(doc["gyroscopes"]["M"])
    a, c_gyro_i = np.array(doc["gyroscopes"]["A"]), np.array(doc["gyroscopes"]["C_gyro_i"])
    c_i_s = np.array(doc["imucalib_C_i_sensor"])
    b_a, b_g = np.array(doc["imucalib_bias_accel"]), np.array(doc["imucalib_bias_gyro"])
    a_i = np.linalg.solve(m_a, (accel_m - b_a).T).T
    w_i = (c_gyro_i.T @ np.linalg.solve(m_g, (gyro_m - b_g - (a @ c_gyro_i @ a_i.T).T).T)).T
    assert np.max(np.abs(a_i - f_true @ c_i_s.T)) < 1e-9
    assert np.max(np.abs(w_i - w_true @ c_i_s.T)) < 1e-9


def test_kalibr_and_openvins_refuse_temperature_models_without_a_temperature(
        tmp_path: Path) -> None:
    cal = _temperature_result()
    for write in (write_kalibr_intrinsics, write_openvins_intrinsics):
        with pytest.raises(InvalidInputError, match="--temperature") as err:
            write(cal, tmp_path / "x.yaml")
        assert all(name in str(err.value) for name in _MODELS)
        for t in (_RANGE[0] - 0.5, _RANGE[1] + 0.5):
            with pytest.raises(InvalidInputError, match="outside the range"):
                write(cal, tmp_path / "x.yaml", temperature_degc=t)
        with pytest.raises(InvalidInputError, match="finite"):
            write(cal, tmp_path / "x.yaml", temperature_degc=float("nan"))
        write(cal, tmp_path / "x.yaml", temperature_degc=_RANGE[1])  # the ends are inside
    with pytest.raises(InvalidInputError, match="--temperature"):
        kalibr_intrinsics(cal)
    with pytest.raises(InvalidInputError, match="--temperature"):
        openvins_intrinsics(cal)


def test_a_result_without_temperature_models_is_written_as_before(tmp_path: Path) -> None:
    cal = _result(k2=False)
    for write in (write_kalibr_intrinsics, write_openvins_intrinsics):
        plain = write(cal, tmp_path / "a.yaml").read_text("utf-8")
        assert "imucalib_temperature_degc" not in plain
        assert write(cal, tmp_path / "b.yaml", temperature_degc=40.0).read_text("utf-8") == plain


def test_openvins_file_names_the_estimator_config_keys(tmp_path: Path) -> None:
    text = write_openvins_intrinsics(_result(k2=False), tmp_path / "o.yaml").read_text("utf-8")
    head = [line for line in text.splitlines() if line.startswith("#")]
    assert any("calib_imu_intrinsics" in line for line in head)
    assert any("calib_imu_g_sensitivity" in line for line in head)
    assert any("relative_config_imu" in line for line in head)
    imu = yaml.safe_load(text)["imu0"]
    assert imu["model"] == "kalibr"  # OpenVINS' imu model key is in this file, not the config
    for key in ("Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"):  # what its loader reads
        assert np.shape(imu[key]) == (3, 3)
    for line in text.splitlines():  # cv::FileStorage splits a trailing comment at ':'
        if "#" in line and not line.lstrip().startswith("#"):
            assert ":" not in line.split("#", 1)[1], line


def _cli_result(tmp_path: Path) -> Path:
    cal = replace(_temperature_result(), sensor_id="IMU-7")
    src = tmp_path / "run.result.json"
    src.write_text(cal.to_json(), encoding="utf-8")
    return src


@pytest.mark.parametrize("fmt", ["kalibr-imu", "openvins-imu"])
def test_cli_needs_a_temperature_for_a_result_with_models(tmp_path: Path, fmt: str) -> None:
    src = _cli_result(tmp_path)
    out = CliRunner().invoke(app, ["export", str(src), "--format", fmt,
                                   "--out", str(tmp_path / "o")])
    assert out.exit_code != 0
    assert "--temperature" in out.output and "gyro_bias_x" in out.output
    assert "Traceback" not in out.output and isinstance(out.exception, SystemExit)
    out = CliRunner().invoke(app, ["export", str(src), "--format", fmt, "--temperature", "30",
                                   "--out", str(tmp_path / "o")])
    assert out.exit_code == 0, out.output
    (written,) = (tmp_path / "o").glob(f"*.{fmt}.yaml")
    doc = yaml.safe_load(written.read_text(encoding="utf-8"))
    stated = doc["imucalib_temperature_degc"] if fmt == "kalibr-imu" \
        else doc["imu0"]["imucalib_temperature_degc"]
    assert stated == 30.0
    out = CliRunner().invoke(app, ["export", str(src), "--format", fmt, "--temperature", "99",
                                   "--out", str(tmp_path / "o")])
    assert out.exit_code != 0 and "outside the range" in out.output


def test_cli_refuses_a_temperature_for_other_formats(tmp_path: Path) -> None:
    src = _cli_result(tmp_path)
    out = CliRunner().invoke(app, ["export", str(src), "--format", "mat", "--temperature", "30",
                                   "--out", str(tmp_path / "o")])
    assert out.exit_code != 0 and "--temperature applies to" in out.output
    out = CliRunner().invoke(app, ["export", str(src), "--format", "ros-yaml",
                                   "--out", str(tmp_path / "o")])
    assert out.exit_code == 0, out.output
    (written,) = (tmp_path / "o").glob("*.ros.yaml")
    assert "gyro_bias_x" in yaml.safe_load(written.read_text("utf-8"))["temperature_models"]


def test_yaml_floats_without_a_point_load_as_numbers() -> None:
    """repr(1e-05) is '1e-05', a string to YAML 1.1 (PyYAML); it is written as 1.0e-05."""
    base = _result(k2=False)
    values = base.values.copy()
    values[:3] = (1e-05, -3e-20, 1e+22)
    cal = replace(base, values=values)
    doc = yaml.safe_load(format_ros_yaml(cal))
    assert doc["values"] == list(values)
    assert doc["gyro"]["bias"] == [1e-05, -3e-20, 1e+22]


def test_write_outputs_passes_a_temperature_to_kalibr_and_openvins_only(tmp_path: Path) -> None:
    from imucalib.exports.outputs import write_outputs

    wrapped = stored_from_calibration(_temperature_result())
    (path,) = write_outputs(wrapped, tmp_path, ("openvins-imu",), name="n",  # type: ignore[arg-type]
                            temperature_degc=40.0)
    assert yaml.safe_load(path.read_text("utf-8"))["imu0"]["imucalib_temperature_degc"] == 40.0
    with pytest.raises(InvalidInputError, match="a temperature applies to"):
        write_outputs(wrapped, tmp_path, ("kalibr-imu", "mat"), name="n",  # type: ignore[arg-type]
                      temperature_degc=40.0)
    with pytest.raises(InvalidInputError, match="--temperature"):
        write_outputs(wrapped, tmp_path, ("kalibr-imu",), name="n")  # type: ignore[arg-type]


def test_a_mat73_write_that_fails_leaves_no_file_and_one_error(tmp_path: Path, monkeypatch
                                                               ) -> None:
    """A write HDF5 fails (a full disk) gives the temporary copy up and removes it; the export
    raises one RecordingWriteError and leaves neither a half-written file nor the copy."""
    from imucalib.errors import RecordingWriteError
    from imucalib.exports import intrinsics
    from imucalib.io import _abandon

    monkeypatch.setattr(_abandon, "_ABANDONED", [])   # this process must not end by os._exit
    monkeypatch.setattr(_abandon, "_KEEP_ALIVE", [])

    def full(group, struct):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(intrinsics, "_h5_struct", full)
    out = tmp_path / "r.mat"
    with pytest.raises(RecordingWriteError, match=r"cannot write .*No space left on device"):
        write_mat73(_result(), out)
    assert list(tmp_path.iterdir()) == []
    assert _abandon.abandoned_files() == (tmp_path / ".r.mat.partial",)
