"""An accelerometer K3 in a triad-model result: named, read, carried and inverted by correct_imu.

y_i = b_i + u_i + K2_i·u_i² + K3_i·u_i³ with u = (I + M)·x (the TriadModel's convention); the
correction is the forward model's inverse with and without temperature models.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from imucalib.conventions import AXES
from imucalib.errors import InvalidInputError
from imucalib.models.correct import correct_imu
from imucalib.models.result import (
    CalibrationResult,
    ParameterTemperatureModel,
    triad_parameter_names,
    triad_parameter_unit,
)
from imucalib.models.temperature import TemperatureDependence
from imucalib.models.triad import TriadModel, apply_triad

T0 = 20.0


def _result(model: TriadModel, *, k2: bool = True, k3: bool = True,
            temperature: bool = False) -> CalibrationResult:
    """The accelerometer triad of `model` as a result; with `temperature`, linear bias and K3."""
    names = triad_parameter_names("accel", "triad", k2=k2, k3=k3)
    values = np.concatenate([model.bias, model.scale_misalignment.ravel(),
                             *([model.k2] if k2 else []), *([model.k3] if k3 else [])])
    records: tuple[ParameterTemperatureModel, ...] = ()
    if temperature:
        assert model.temperature is not None
        coeffs = model.temperature.coefficients
        records = tuple(ParameterTemperatureModel(
            name=f"accel_{symbol}_{a}", reference_temperature_degc=T0,
            coefficients=(float(getattr(model, field)[i]), float(coeffs[field][0][i])),
            covariance=np.eye(2) * 1e-20, chi2=1.0, dof=3, order_criterion="fixed")
            for symbol, field in (("bias", "bias"), ("K3", "k3")) if field in coeffs
            for i, a in enumerate(AXES))
    return CalibrationResult(sensor_id="K3", procedure="field", model="triad",
                             param_names=names, values=values,
                             covariance=np.eye(len(names)) * 1e-20,
                             units={n: triad_parameter_unit(n) for n in names},
                             temperature_models=records)


def _truth(rng: np.random.Generator, *, k2: float = 2e-3, k3: float = 5e-5,
           temperature: bool = False) -> TriadModel:
    """A triad with large K2 and K3 (K3·u³ up to ≈ 0.4 m/s² at 20 m/s²), monotonic on ±20 m/s²."""
    dep = TemperatureDependence(T0, {"bias": rng.normal(size=(1, 3)) * 1e-3,
                                     "k3": rng.normal(size=(1, 3)) * k3 / 100.0}, {}) \
        if temperature else None
    return TriadModel("accel", bias=rng.normal(size=3) * 0.05,
                      scale_misalignment=rng.normal(size=(3, 3)) * 2e-3,
                      k2=rng.normal(size=3) * k2, k3=rng.normal(size=3) * k3, temperature=dep)


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    """max |a − b| per sample over the sample's largest |b| component."""
    return float(np.max(np.abs(a - b) / np.max(np.abs(b), axis=1, keepdims=True)))


def test_names_units_and_order() -> None:
    base = triad_parameter_names("accel", "triad", k2=True)
    both = triad_parameter_names("accel", "triad", k2=True, k3=True)
    assert both == (*base, "accel_K3_x", "accel_K3_y", "accel_K3_z")
    assert triad_parameter_names("accel", "triad", k3=True)[-4:] == (
        "accel_M_zz", "accel_K3_x", "accel_K3_y", "accel_K3_z")
    assert triad_parameter_names("accel", "per-axis", k3=True) == \
        triad_parameter_names("accel", "per-axis")
    assert triad_parameter_unit("accel_K3_y") == "1/(m/s^2)^2"


@pytest.mark.parametrize("k2", [True, False])
def test_json_round_trip_and_triad_model_carry_k3(k2: bool) -> None:
    truth = _truth(np.random.default_rng(0))
    result = _result(truth, k2=k2)
    back = CalibrationResult.from_json(result.to_json())
    assert back.param_names == result.param_names
    model = back.triad_model("accel")
    np.testing.assert_array_equal(model.k3, truth.k3)
    np.testing.assert_array_equal(model.k2, truth.k2 if k2 else np.zeros(3))


def test_reader_refuses_k3_on_some_axes_or_on_the_gyro() -> None:
    doc = json.loads(_result(_truth(np.random.default_rng(1))).to_json())
    partial = {**doc, "parameters": doc["parameters"][:-1],
               "covariance": [row[:-1] for row in doc["covariance"][:-1]]}
    with pytest.raises(InvalidInputError, match=r"the K2 terms, the K3 terms or both.*"
                                                r"missing \['accel_K3_z'\]"):
        CalibrationResult.from_json(json.dumps(partial))
    gyro = json.loads(json.dumps(doc).replace('"accel_', '"gyro_'))
    with pytest.raises(InvalidInputError, match=r"unexpected \['gyro_K2_x'"):
        CalibrationResult.from_json(json.dumps(gyro))


def test_temperature_model_of_k3_reaches_the_triad_model() -> None:
    truth = _truth(np.random.default_rng(2), temperature=True)
    model = _result(truth, temperature=True).triad_model("accel")
    assert model.temperature is not None
    np.testing.assert_array_equal(model.temperature.coefficients["k3"],
                                  truth.temperature.coefficients["k3"])  # type: ignore[union-attr]


def test_constant_correction_inverts_k3() -> None:
    rng = np.random.default_rng(3)
    truth = _truth(rng)
    x = rng.uniform(-20.0, 20.0, (2000, 3))
    y = apply_triad(truth, x)
    _, accel = correct_imu(None, y, _result(truth))
    _, without = correct_imu(None, y, _result(truth.replace(k3=np.zeros(3)), k3=False))
    assert accel is not None and without is not None
    assert _relative(accel, x) <= 1e-12
    assert np.max(np.abs(without - x)) > 0.05  # K3 is not ignored: it matters this much


@pytest.mark.parametrize("k2", [True, False])
def test_per_sample_correction_inverts_k3(k2: bool) -> None:
    rng = np.random.default_rng(4)
    truth = _truth(rng, temperature=True)
    if not k2:
        truth = truth.replace(k2=np.zeros(3))
    x = rng.uniform(-20.0, 20.0, (2000, 3))
    temp = rng.uniform(-40.0, 85.0, 2000)
    y = apply_triad(truth, x, temperature_degc=temp)
    result = _result(truth, k2=k2, temperature=True)
    _, accel = correct_imu(None, y, result, temperature_degc=temp)
    assert accel is not None
    assert _relative(accel, x) <= 1e-12
    # at T0 the per-sample path (_k3_inverse) agrees with the constant one (correct_triad)
    _, at_t0 = correct_imu(None, y, result, temperature_degc=T0)
    plain = _result(truth.replace(temperature=None), k2=k2)
    _, constant = correct_imu(None, y, plain)
    assert at_t0 is not None and constant is not None
    assert _relative(at_t0, constant) <= 1e-13
    # without the K3 terms the correction is off by K3·u³
    no_k3 = CalibrationResult(
        sensor_id="K3", procedure="field", model="triad",
        param_names=result.param_names[:-3], values=result.values[:-3],
        covariance=result.covariance[:-3, :-3], units=result.units,
        temperature_models=tuple(tm for tm in result.temperature_models
                                 if "_K3_" not in tm.name))
    _, without = correct_imu(None, y, no_k3, temperature_degc=temp)
    assert without is not None and np.max(np.abs(without - x)) > 0.05


def test_zero_k3_is_bit_for_bit_the_k2_path() -> None:
    rng = np.random.default_rng(5)
    truth = _truth(rng, temperature=True).replace(k3=np.zeros(3))
    dep = truth.temperature
    assert dep is not None
    truth = truth.replace(temperature=TemperatureDependence(
        T0, {"bias": dep.coefficients["bias"]}, {}))
    y = rng.uniform(-20.0, 20.0, (500, 3))
    temp = rng.uniform(-40.0, 85.0, 500)
    with_zero = _result(truth, temperature=True)
    no_k3 = _result(truth, k3=False, temperature=True)
    _, a = correct_imu(None, y, with_zero, temperature_degc=temp)
    _, b = correct_imu(None, y, no_k3, temperature_degc=temp)
    assert a is not None and b is not None
    np.testing.assert_array_equal(a, b)


def test_k3_outside_the_branch_through_zero_is_refused() -> None:
    rng = np.random.default_rng(6)
    truth = _truth(rng, temperature=True).replace(k2=np.zeros(3),
                                                  k3=np.array([-1e-3, 0.0, 0.0]))
    # 1 + 3·K3·u² = 0 at |u| ≈ 18: u + K3·u³ peaks at ≈ 12 m/s², so 15 has no root on the branch
    with pytest.raises(InvalidInputError, match="cannot invert the accel K2/K3 model"):
        correct_imu(None, [[15.0, 0.0, 0.0]], _result(truth, temperature=True),
                    temperature_degc=T0)
    with pytest.raises(InvalidInputError, match="cannot invert"):
        correct_imu(None, [[15.0, 0.0, 0.0]], _result(truth.replace(temperature=None)))


def test_frame_correction_and_the_applicable_calibration_carry_k3() -> None:
    """correct_imu_frame (``imucalib apply``) and a part-result's completed model apply K3."""
    from dataclasses import replace

    import pandas as pd

    from imucalib.conventions import ACCEL_COLUMNS
    from imucalib.models.correct import correct_imu_frame
    from imucalib.models.result_document import applicable_calibration, stored_from_calibration

    rng = np.random.default_rng(7)
    truth = _truth(rng)
    x = rng.uniform(-20.0, 20.0, (300, 3))
    frame = pd.DataFrame(apply_triad(truth, x), columns=list(ACCEL_COLUMNS))
    result = _result(truth)
    assert _relative(correct_imu_frame(frame, result)[list(ACCEL_COLUMNS)].to_numpy(), x) <= 1e-12
    part = replace(stored_from_calibration(result), calibration=None)
    completed, _ = applicable_calibration(part)
    assert completed.param_names == result.param_names
    np.testing.assert_array_equal(completed.triad_model("accel").k3, truth.k3)


def test_combined_tests_keep_k3() -> None:
    from imucalib.estimation.combine import TriadPart, combine_triad_parameters

    truth = _truth(np.random.default_rng(8))
    result = _result(truth)
    k = len(result.param_names)
    core = TriadPart("tumble", result.param_names[:-3], result.values[:-3],
                     np.eye(k - 3) * 1e-12)
    cubic = TriadPart("field", result.param_names[-3:], result.values[-3:], np.eye(3) * 1e-16)
    combined = combine_triad_parameters([core, cubic], sensor_id="K3")
    assert combined.param_names == result.param_names
    np.testing.assert_allclose(combined.triad_model("accel").k3, truth.k3, rtol=1e-12)
    # a part with K3 on one axis only is no whole term
    with pytest.raises(Exception, match="accel_K3_y"):
        combine_triad_parameters([core, TriadPart("field", ("accel_K3_x",), result.values[-3:-2],
                                                  np.eye(1) * 1e-16)], sensor_id="K3")
