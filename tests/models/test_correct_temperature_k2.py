"""A result with temperature models and an accelerometer K2: correct_imu inverts K2 per sample."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.conventions import AXES
from imucalib.errors import InvalidInputError
from imucalib.models.correct import correct_imu
from imucalib.models.result import (
    CalibrationResult,
    ParameterTemperatureModel,
    triad_parameter_names,
)
from imucalib.models.temperature import TemperatureDependence
from imucalib.models.triad import TriadModel, apply_triad

T0 = 20.0


def _result(model: TriadModel, *, with_temperature: bool) -> CalibrationResult:
    names = triad_parameter_names("accel", "triad", k2=True)
    values = np.concatenate([model.bias, model.scale_misalignment.ravel(), model.k2])
    records = ()
    if with_temperature:
        assert model.temperature is not None
        slope = model.temperature.coefficients["bias"][0]
        records = tuple(ParameterTemperatureModel(
            name=f"accel_bias_{a}", reference_temperature_degc=T0,
            coefficients=(float(model.bias[i]), float(slope[i])), covariance=np.eye(2) * 1e-20,
            chi2=1.0, dof=3, order_criterion="fixed") for i, a in enumerate(AXES))
    return CalibrationResult(sensor_id="K2", procedure="p2", model="triad", param_names=names,
                             values=values, covariance=np.eye(len(names)) * 1e-20,
                             units=dict.fromkeys(names, "1"), temperature_models=records)


def _truth(rng: np.random.Generator, k2: float = 2e-3) -> TriadModel:
    dep = TemperatureDependence(T0, {"bias": rng.normal(size=(1, 3)) * 1e-3}, {})
    return TriadModel("accel", bias=rng.normal(size=3) * 0.05,
                      scale_misalignment=rng.normal(size=(3, 3)) * 2e-3,
                      k2=rng.normal(size=3) * k2, temperature=dep)


def test_k2_with_temperature_models_recovers_truth() -> None:
    rng = np.random.default_rng(0)
    truth = _truth(rng)
    x = rng.uniform(-20.0, 20.0, (500, 3))
    temp = rng.uniform(-40.0, 85.0, 500)
    y = apply_triad(truth, x, temperature_degc=temp)
    _, accel = correct_imu(None, y, _result(truth, with_temperature=True), temperature_degc=temp)
    assert accel is not None
    np.testing.assert_allclose(accel, x, rtol=0.0, atol=1e-12)
    # at T0 it is the correction of the result without temperature models (correct_triad)
    _, plain = correct_imu(None, y, _result(truth, with_temperature=False))
    _, at_t0 = correct_imu(None, y, _result(truth, with_temperature=True), temperature_degc=T0)
    assert plain is not None and at_t0 is not None
    np.testing.assert_allclose(at_t0, plain, rtol=1e-14, atol=1e-14)
    assert np.max(np.abs(plain - x)) > 1e-3  # the temperature term matters


def test_k2_outside_its_range_is_refused() -> None:
    truth = _truth(np.random.default_rng(1)).replace(k2=np.array([-0.1, 0.0, 0.0]))
    with pytest.raises(InvalidInputError, match="cannot invert the accel K2 model"):
        correct_imu(None, [[100.0, 0.0, 0.0]], _result(truth, with_temperature=True),
                    temperature_degc=T0)
