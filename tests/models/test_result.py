"""CalibrationResult: exact JSON round trip, version and unit checks; correct_imu inverts apply."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imucalib.errors import InvalidInputError, UnitError
from imucalib.models import apply_triad, sample_imu_model
from imucalib.models.correct import correct_imu, correct_imu_frame
from imucalib.models.result import (
    RESULT_FORMAT_VERSION,
    CalibrationResult,
    Provenance,
    ResidualStats,
    triad_parameter_names,
)

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False, width=64)


def make_result(values: np.ndarray, model: str = "triad") -> CalibrationResult:
    names = (*triad_parameter_names("accel", model),
             *triad_parameter_names("gyro", model, g_sensitivity=model == "triad"))
    k = len(names)
    a = np.random.default_rng(0).normal(size=(k, k))
    return CalibrationResult(
        sensor_id="IMU-7", procedure="p1", model=model, param_names=names,
        values=values[:k], covariance=a @ a.T * 1e-8, units=dict.fromkeys(names, "1"),
        residuals={"accel: Z up": ResidualStats((1e-4, -2e-4, 3.5e-5), (1e-3,) * 3, 2000,
                                                "m/s^2")},
        provenance=Provenance(plan_hash="ab" * 32, recording_sha256="cd" * 32,
                              recording="run.h5", software_version="0.1.0",
                              created_utc="2026-11-23T00:00:00Z", details={"n": 3}),
        notes=("gyro bias excludes Earth rate",))


@settings(max_examples=60, deadline=None)
@given(st.lists(finite, min_size=33, max_size=33))
def test_json_round_trip_is_exact(values):
    res = make_result(np.array(values))
    back = CalibrationResult.from_json(res.to_json())
    np.testing.assert_array_equal(back.values, res.values)
    np.testing.assert_array_equal(back.covariance, res.covariance)
    assert back.param_names == res.param_names and back.units == res.units
    assert back.residuals == res.residuals and back.provenance == res.provenance
    assert back.notes == res.notes and back.to_json() == res.to_json()


def test_newer_format_and_foreign_documents_are_refused():
    data = json.loads(make_result(np.zeros(33)).to_json())
    data["format_version"] = RESULT_FORMAT_VERSION + 2  # 4 is the result document's
    with pytest.raises(InvalidInputError,
                       match=f"format_version {RESULT_FORMAT_VERSION + 2} is not supported"):
        CalibrationResult.from_dict(data)
    data["format_version"] = RESULT_FORMAT_VERSION + 1
    with pytest.raises(InvalidInputError, match="without a whole triad model"):
        CalibrationResult.from_dict(data)
    with pytest.raises(InvalidInputError, match="not an imucalib calibration result"):
        CalibrationResult.from_json('{"format": "something-else"}')
    with pytest.raises(InvalidInputError, match="not valid JSON"):
        CalibrationResult.from_json("{")


@pytest.mark.parametrize(("change", "match"), [
    ({"values": np.full(33, np.nan)}, "`values` must be finite"),
    ({"covariance": np.ones((3, 3))}, r"`covariance` must have shape \(33, 33\)"),
    ({"model": "magic"}, "`model` must be one of"),
    ({"units": {}}, "`units` lacks the parameter"),
])
def test_malformed_results_are_refused(change, match):
    base = make_result(np.zeros(33))
    kwargs = {f: getattr(base, f) for f in ("sensor_id", "procedure", "model", "param_names",
                                            "values", "covariance", "units")}
    kwargs.update(change)
    with pytest.raises(InvalidInputError, match=match):
        CalibrationResult(**kwargs)


def triad_result_from_truth(seed: int) -> tuple[CalibrationResult, object]:
    truth = sample_imu_model("consumer", rng=seed, nonlinear=False)
    names = (*triad_parameter_names("accel", "triad"),
             *triad_parameter_names("gyro", "triad", g_sensitivity=True))
    values = np.r_[truth.accel.bias, truth.accel.scale_misalignment.ravel(), truth.gyro.bias,
                   truth.gyro.scale_misalignment.ravel(), truth.gyro.g_sensitivity.ravel()]
    res = CalibrationResult(sensor_id="u", procedure="p1", model="triad", param_names=names,
                            values=values, covariance=np.eye(33) * 1e-12,
                            units=dict.fromkeys(names, "1"))
    return res, truth


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_correct_imu_inverts_the_triad_model(seed):
    res, truth = triad_result_from_truth(seed)
    rng = np.random.default_rng(seed)
    rate = rng.normal(0, 1.0, (50, 3))
    force = rng.normal(0, 9.8, (50, 3))
    z = np.zeros_like(force)
    acc = apply_triad(truth.accel, force, rate_b_rps=z, angular_accel_b_rps2=z)
    gyr = apply_triad(truth.gyro, rate, specific_force_b_mps2=force)
    g_hat, a_hat = correct_imu(gyr, acc, res)
    np.testing.assert_allclose(a_hat, force, atol=1e-9)
    np.testing.assert_allclose(g_hat, rate, atol=1e-12)
    frame = pd.DataFrame(np.c_[gyr, acc], columns=["gyro_x_rps", "gyro_y_rps", "gyro_z_rps",
                                                    "accel_x_mps2", "accel_y_mps2",
                                                    "accel_z_mps2"])
    fixed = correct_imu_frame(frame, res)
    np.testing.assert_allclose(fixed[["accel_x_mps2", "accel_y_mps2", "accel_z_mps2"]], force,
                               atol=1e-9)
    frame.attrs["units"] = {"gyro_x_rps": "deg/s"}
    with pytest.raises(UnitError, match="gyro data in 'rad/s'; the data given are in 'deg/s'"):
        correct_imu_frame(frame, res)


def test_per_axis_result_applies_k_and_b():
    names = (*triad_parameter_names("accel", "per-axis"),
             *triad_parameter_names("gyro", "per-axis"))
    values = np.r_[1.01, 0.99, 1.0, 0.1, -0.2, 0.0, 1.0, 1.0, 1.02, 0.0, 0.0, 1e-3]
    res = CalibrationResult(sensor_id="u", procedure="p1", model="per-axis", param_names=names,
                            values=values, covariance=np.eye(12) * 1e-10,
                            units=dict.fromkeys(names, "1"))
    true_f = np.array([[1.0, 2.0, 3.0]])
    measured = np.array([1.01, 0.99, 1.0]) * (true_f + np.array([0.1, -0.2, 0.0]))  # K·(a + b)
    _, a_hat = correct_imu(None, measured, res)
    np.testing.assert_allclose(a_hat, true_f, atol=1e-12)
    assert res.triad_model("accel").bias.tolist() == pytest.approx([0.101, -0.198, 0.0])
