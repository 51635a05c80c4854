"""A result with K2 to Kalibr and OpenVINS, whose models lack it (Eq. (X6) of
imucalib.exports.intrinsics): refused with what leaving it out errs by, written without it only
when asked, the file saying so, and read back the way the tools read it (yaml.safe_load)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from imucalib.errors import InvalidInputError
from imucalib.exports.intrinsics import (
    kalibr_intrinsics,
    openvins_intrinsics,
    write_kalibr_intrinsics,
    write_openvins_intrinsics,
)
from imucalib.exports.outputs import write_outputs
from imucalib.models.result_document import stored_from_calibration
from imucalib.units import G0_MPS2, MG

from .test_intrinsics import _result


def test_the_refusal_states_the_error_leaving_k2_out_causes():
    cal = _result(k2=True)
    k2 = np.array([cal.value(f"accel_K2_{a}") for a in "xyz"])
    worst = int(np.argmax(np.abs(k2)))
    at_1g = abs(k2[worst]) * G0_MPS2**2 / MG
    for export in (kalibr_intrinsics, openvins_intrinsics):
        with pytest.raises(InvalidInputError) as err:
            export(cal)
        msg = str(err.value)
        assert f"{at_1g:.3g} mg at 1 g" in msg and f"{4 * at_1g:.3g} mg at 2 g" in msg
        assert f"K2_{'xyz'[worst]}" in msg and "--drop-terms" in msg and "terms=-k2" in msg


def test_drop_terms_writes_the_rest_and_says_so(tmp_path: Path):
    cal = _result(k2=True)
    same = _result(k2=False, seed=3)
    k_drop = kalibr_intrinsics(cal, drop_terms=True)
    # the rest of the model is the result's own (the same M, G, biases as written without K2)
    kalibr = yaml.safe_load(write_kalibr_intrinsics(cal, tmp_path / "k.yaml", drop_terms=True)
                            .read_text(encoding="utf-8"))
    assert kalibr["model"] == "scale-misalignment"
    np.testing.assert_array_equal(np.array(kalibr["accelerometers"]["M"]), k_drop["M_accel"])
    text = (tmp_path / "k.yaml").read_text(encoding="utf-8")
    assert "# K2 LEFT OUT (--drop-terms):" in text and "mg at 1 g" in text
    ov_text = write_openvins_intrinsics(cal, tmp_path / "o.yaml", drop_terms=True).read_text(
        encoding="utf-8")
    assert "# K2 LEFT OUT (--drop-terms):" in ov_text
    ov = yaml.safe_load(ov_text)
    assert ov["imu0"]["model"] == "kalibr" and len(ov["imu0"]["Ta"]) == 3
    # a result without K2 writes no such line, with or without the flag
    plain = write_kalibr_intrinsics(same, tmp_path / "p.yaml", drop_terms=True).read_text(
        encoding="utf-8")
    assert "LEFT OUT" not in plain


def test_write_outputs_passes_the_flag_and_refuses_without_it(tmp_path: Path):
    stored = stored_from_calibration(_result(k2=True))
    with pytest.raises(InvalidInputError, match="drop-terms"):
        write_outputs(stored, tmp_path, formats=("kalibr-imu",), name="run")
    written = write_outputs(stored, tmp_path, formats=("kalibr-imu", "openvins-imu"),
                            name="run", drop_terms=True)
    assert len(written) == 2
    assert all("K2 LEFT OUT" in p.read_text(encoding="utf-8") for p in written)


def test_the_cli_refuses_then_writes_with_drop_terms(tmp_path: Path):
    from typer.testing import CliRunner

    from imucalib.cli import app

    runner = CliRunner()
    result_file = tmp_path / "r.result.json"
    result_file.write_text(replace(_result(k2=True), sensor_id="IMU-7").to_json(),
                           encoding="utf-8")
    res = runner.invoke(app, ["export", str(result_file), "--format", "kalibr-imu", "-o",
                              str(tmp_path / "k")])
    assert res.exit_code == 2 and "mg at 1 g" in res.output and "--drop-terms" in res.output
    res = runner.invoke(app, ["export", str(result_file), "--format", "kalibr-imu", "-o",
                              str(tmp_path / "k"), "--drop-terms"])
    assert res.exit_code == 0, res.output
    (written,) = (tmp_path / "k").glob("*.yaml")
    assert "K2 LEFT OUT" in written.read_text(encoding="utf-8")
    res = runner.invoke(app, ["export", str(result_file), "--format", "mat", "-o",
                              str(tmp_path / "m"), "--drop-terms"])
    assert res.exit_code == 2 and "--drop-terms applies to --format" in res.output


def _with_k3(*, k2: bool, k3: float = 2e-5, seed: int = 5):
    """_result plus accelerometer K3 terms (after K2), K3_y the largest."""
    from imucalib.models.result import CalibrationResult

    base = _result(k2=k2, seed=seed)
    names = (*base.param_names, "accel_K3_x", "accel_K3_y", "accel_K3_z")
    values = np.concatenate([base.values, [0.3 * k3, -k3, 0.1 * k3]])
    cov = np.zeros((len(names), len(names)))
    cov[:-3, :-3] = base.covariance
    cov[-3:, -3:] = np.eye(3) * 1e-14
    return CalibrationResult(sensor_id=base.sensor_id, procedure=base.procedure, model="triad",
                             param_names=names, values=values, covariance=cov,
                             units={**base.units, **dict.fromkeys(names[-3:], "1/(m/s^2)^2")})


def test_the_refusal_states_the_error_leaving_k3_out_causes():
    cal = _with_k3(k2=False)
    at_1g = 2e-5 * G0_MPS2**3 / MG  # K3_y's error |K3|·f³ at 1 g [mg]
    for export in (kalibr_intrinsics, openvins_intrinsics):
        with pytest.raises(InvalidInputError) as err:
            export(cal)
        msg = str(err.value)
        assert f"{at_1g:.3g} mg at 1 g" in msg and f"{8 * at_1g:.3g} mg at 2 g" in msg
        assert "accelerometer K3 is not 0" in msg and "no cubic scale factor" in msg
        assert "K3_y = -2e-05 1/(m/s²)²" in msg and "terms=-k3" in msg and "K2" not in msg


def test_k2_and_k3_together_add_up_and_are_left_out_together(tmp_path: Path):
    cal = _with_k3(k2=True)
    k2 = np.abs([cal.value(f"accel_K2_{a}") for a in "xyz"])
    k3 = np.abs([cal.value(f"accel_K3_{a}") for a in "xyz"])
    at_1g = np.max(k2 * G0_MPS2**2 + k3 * G0_MPS2**3) / MG
    at_2g = np.max(4 * k2 * G0_MPS2**2 + 8 * k3 * G0_MPS2**3) / MG
    with pytest.raises(InvalidInputError) as err:
        kalibr_intrinsics(cal)
    msg = str(err.value)
    assert f"{at_1g:.3g} mg at 1 g and {at_2g:.3g} mg at 2 g" in msg
    assert "K2 and K3 are not 0" in msg and "terms=-k2,-k3" in msg
    text = write_openvins_intrinsics(cal, tmp_path / "o.yaml", drop_terms=True).read_text(
        encoding="utf-8")
    assert "# K2 AND K3 LEFT OUT (--drop-terms):" in text
    # the rest is what the result without K2 and K3 gives
    np.testing.assert_array_equal(openvins_intrinsics(cal, drop_terms=True)["Ta"],
                                  openvins_intrinsics(_result(k2=False, seed=5))["Ta"])


def test_struct_ros_yaml_and_mat_carry_k3(tmp_path: Path):
    from scipy.io import loadmat

    from imucalib.exports.intrinsics import format_ros_yaml, intrinsics_struct, write_mat

    cal = _with_k3(k2=True)
    k3 = np.array([cal.value(f"accel_K3_{a}") for a in "xyz"])
    s = intrinsics_struct(cal)
    np.testing.assert_array_equal(s["K3_a"], k3)
    np.testing.assert_array_equal(intrinsics_struct(_result(k2=True))["K3_a"], np.zeros(3))
    doc = yaml.safe_load(format_ros_yaml(cal))
    np.testing.assert_array_equal(doc["accel"]["k3"], k3)
    assert "k3" not in yaml.safe_load(format_ros_yaml(_result(k2=True)))["accel"]
    mat = loadmat(write_mat(cal, tmp_path / "c.mat"))["imucal"][0, 0]
    np.testing.assert_array_equal(mat["K3_a"].ravel(), k3)
