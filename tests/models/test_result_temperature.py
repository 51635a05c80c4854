"""A calibration result's temperature models: the record, the JSON (format v3), the reader."""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.models.result import (
    RESULT_FORMAT_VERSION,
    CalibrationResult,
    HeldOutOutcome,
    ParameterTemperatureModel,
    triad_parameter_names,
)
from imucalib.models.temperature import TemperatureDependence
from imucalib.models.triad import TriadModel

T0 = 25.0
NAMES = (*triad_parameter_names("accel", "triad"), *triad_parameter_names("gyro", "triad"))


def record(name: str, c: tuple[float, ...], *, rate: float | None = None,
           leg: float | None = None, seed: int = 0, **kw: object) -> ParameterTemperatureModel:
    q = len(c) + (rate is not None) + (leg is not None)
    a = np.random.default_rng(seed).normal(size=(q, q)) * 1e-4
    defaults: dict[str, object] = {"chi2": 7.5, "dof": 8, "order_criterion": "aicc",
                                   "temperature_range_degc": (-40.0, 85.0),
                                   "held_out": HeldOutOutcome(1.2, 3.4, 4, 0.49, True)}
    return ParameterTemperatureModel(name=name, reference_temperature_degc=T0, coefficients=c,
                                     covariance=a @ a.T, rate_coefficient=rate,
                                     leg_coefficient=leg, **{**defaults, **kw})


def make_result(models: tuple[ParameterTemperatureModel, ...] | None = None,
                **kw: object) -> CalibrationResult:
    values = np.zeros(len(NAMES))
    values[NAMES.index("accel_bias_x")] = 0.02
    values[NAMES.index("gyro_M_xy")] = 1e-3
    if models is None:
        models = (record("accel_bias_x", (0.02, 1e-4, -2e-6, 3e-8), rate=0.5, leg=1e-3),
                  record("gyro_M_xy", (1e-3, 2e-6), seed=1, order_criterion="cv",
                         temperature_range_degc=None, held_out=None),
                  record("gyro_bias_z", (0.0, 1e-6, 0.0, 1e-10), rate=-1e-4, seed=2))
    return CalibrationResult(sensor_id="IMU-7", procedure="p2", model="triad", param_names=NAMES,
                             values=values, covariance=np.eye(len(NAMES)) * 1e-10,
                             units=dict.fromkeys(NAMES, "1"), temperature_models=models, **kw)


def test_json_round_trip_is_exact():
    res = make_result()
    text = res.to_json()
    back = CalibrationResult.from_json(text)
    assert back.to_json() == text and back.format_version == RESULT_FORMAT_VERSION == 3
    assert len(back.temperature_models) == 3
    for a, b in zip(res.temperature_models, back.temperature_models, strict=True):
        for key in ("name", "reference_temperature_degc", "coefficients", "rate_coefficient",
                    "leg_coefficient", "chi2", "dof", "order_criterion",
                    "temperature_range_degc", "held_out"):
            assert getattr(a, key) == getattr(b, key), key
        np.testing.assert_array_equal(a.covariance, b.covariance)
    assert back.reference_temperature_degc == T0
    assert back.temperature_range_degc == (-40.0, 85.0)
    assert json.loads(text)["temperature_models"][1]["held_out"] is None


def test_a_result_without_models_and_old_versions_read():
    res = make_result(models=())
    doc = json.loads(res.to_json())
    assert doc["temperature_models"] == []
    assert CalibrationResult.from_dict(doc).temperature_models == ()
    doc["format_version"] = 2
    del doc["temperature_models"]
    old = CalibrationResult.from_dict(doc, "v2.json")
    assert old.temperature_models == () and old.format_version == 2
    assert old.reference_temperature_degc is None and old.temperature_range_degc is None
    assert "temperature_models" not in old.to_dict()
    doc["temperature_models"] = []
    with pytest.raises(InvalidInputError, match=r"unknown field\(s\) \['temperature_models'\]"):
        CalibrationResult.from_dict(doc, "v2.json")


def _set(doc: dict, path: str, value: object) -> dict:
    out = copy.deepcopy(doc)
    node: object = out
    keys = path.replace("[", ".").replace("]", "").split(".")
    for key in keys[:-1]:
        node = node[int(key)] if isinstance(node, list) else node[key]  # type: ignore[index]
    last = keys[-1]
    if value is ...:
        del node[last]  # type: ignore[union-attr]
    elif isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value  # type: ignore[index]
    return out


TM = "temperature_models"


@pytest.mark.parametrize(("path", "value", "field"), [
    (TM, {}, f"'{TM}': expected an array"),
    (f"{TM}[0]", 3, f"'{TM}[0]': expected an object"),
    (f"{TM}[0].chi2", ..., f"'{TM}[0]': missing field(s) ['chi2']"),
    (f"{TM}[0].extra", 1, f"'{TM}[0]': unknown field(s) ['extra']"),
    (f"{TM}[0].name", "", f"'{TM}[0].name': expected a non-empty string"),
    (f"{TM}[0].name", "accel_bias_q", f"'{TM}[0].name': 'accel_bias_q' is not a parameter"),
    (f"{TM}[2].name", "accel_bias_x", f"'{TM}[2].name': 'accel_bias_x' has a temperature "
                                      "model already"),
    (f"{TM}[1].reference_temperature_degc", 20.0,
     f"'{TM}[1].reference_temperature_degc': 20.0 differs from 25.0"),
    (f"{TM}[0].reference_temperature_degc", "25", f"'{TM}[0].reference_temperature_degc': "
                                                  "expected a number"),
    (f"{TM}[0].coefficients", [], f"'{TM}[0].coefficients': expected c_0"),
    (f"{TM}[0].coefficients[1]", float("nan"), f"'{TM}[0].coefficients[1]': expected a "
                                               "finite number"),
    (f"{TM}[0].coefficients[0]", 0.03, f"'{TM}[0].coefficients[0]': c_0 = 0.03 differs"),
    (f"{TM}[0].rate_coefficient", True, f"'{TM}[0].rate_coefficient': expected a number"),
    (f"{TM}[0].leg_coefficient", None, f"'{TM}[0].covariance': expected 5 elements"),
    (f"{TM}[0].covariance[1]", [0.0], f"'{TM}[0].covariance[1]': expected 6 elements"),
    (f"{TM}[0].covariance[1][1]", -1.0, f"'{TM}[0].covariance': temperature model of "
                                        "'accel_bias_x': `covariance[1][1]` must be ≥ 0"),
    (f"{TM}[0].covariance[0][1]", 1.0, f"'{TM}[0].covariance': temperature model of "
                                       "'accel_bias_x': `covariance` must be symmetric"),
    (f"{TM}[0].chi2", -1.0, f"'{TM}[0].chi2': expected a number ≥ 0"),
    (f"{TM}[0].dof", 2.5, f"'{TM}[0].dof': expected an integer ≥ 0"),
    (f"{TM}[0].order_criterion", "bic", f"'{TM}[0].order_criterion': expected one of"),
    (f"{TM}[0].temperature_range_degc", [1.0], f"'{TM}[0].temperature_range_degc': expected 2"),
    (f"{TM}[0].temperature_range_degc", [50.0, 10.0],
     f"'{TM}[0].temperature_range_degc': expected [T_min, T_max]"),
    (f"{TM}[0].held_out.p_value", 1.5, f"'{TM}[0].held_out.p_value': expected a probability"),
    (f"{TM}[0].held_out.dof", 0, f"'{TM}[0].held_out.dof': expected an integer ≥ 1"),
    (f"{TM}[0].held_out.consistent", 1, f"'{TM}[0].held_out.consistent': expected true or"),
    (f"{TM}[0].held_out.max_abs_z", ..., f"'{TM}[0].held_out': missing field"),
])
def test_every_reader_defect_names_its_field(path, value, field):
    doc = json.loads(make_result().to_json())
    with pytest.raises(InvalidInputError) as info:
        CalibrationResult.from_dict(_set(doc, path, value), "r.json")
    assert str(info.value).startswith(f"calibration result r.json: field {field}"), info.value


def test_a_non_psd_covariance_is_refused():
    doc = json.loads(make_result().to_json())
    doc[TM][1]["covariance"] = [[1.0, 2.0], [2.0, 1.0]]
    with pytest.raises(InvalidInputError, match="positive semi-definite"):
        CalibrationResult.from_dict(doc, "r.json")


def test_the_constructor_checks_the_models():
    good = record("accel_bias_x", (0.02, 1e-4))
    with pytest.raises(InvalidInputError, match="not a parameter of this result"):
        make_result((record("accel_bias_q", (0.0,)),))
    with pytest.raises(InvalidInputError, match="a second time"):
        make_result((good, good))
    with pytest.raises(InvalidInputError, match=r"T0 = 20\.0 °C differs"):
        make_result((good, ParameterTemperatureModel(
            name="gyro_M_xy", reference_temperature_degc=20.0, coefficients=(1e-3,),
            covariance=[[0.0]], chi2=0.0, dof=0, order_criterion="fixed")))
    with pytest.raises(InvalidInputError, match=r"c_0 = 0\.0 of 'gyro_M_xy' differs"):
        make_result((record("gyro_M_xy", (0.0, 1.0)),))
    with pytest.raises(InvalidInputError, match="need result format version 3"):
        make_result((good,), format_version=2)
    with pytest.raises(InvalidInputError, match="must be a ParameterTemperatureModel"):
        make_result(("accel_bias_x",))  # type: ignore[arg-type]


@pytest.mark.parametrize(("kw", "message"), [
    ({"name": " "}, "`name` must be a non-empty string"),
    ({"reference_temperature_degc": math.inf}, "`reference_temperature_degc` must be finite"),
    ({"coefficients": ()}, "`coefficients` must hold c_0"),
    ({"coefficients": (0.0, math.nan)}, r"`coefficients\[1\]` must be finite"),
    ({"covariance": np.eye(3)}, r"`covariance` must have shape \(2, 2\)"),
    ({"covariance": [[1.0, 0.5], [0.4, 1.0]]}, "`covariance` must be symmetric"),
    ({"covariance": [[1.0, 2.0], [2.0, 1.0]]}, "positive semi-definite"),
    ({"covariance": [[0.0, 1.0], [1.0, 1.0]]}, "zero variance"),
    ({"chi2": -1.0}, "`chi2` must be ≥ 0"),
    ({"dof": -1}, "`dof` must be an integer ≥ 0"),
    ({"order_criterion": "bic"}, "`order_criterion` must be one of"),
    ({"temperature_range_degc": (5.0, 1.0)}, "T_min ≤ T_max"),
    ({"rate_coefficient": math.nan}, "`rate_coefficient` must be finite"),
])
def test_the_record_checks_its_fields(kw, message):
    args: dict[str, object] = {"name": "accel_bias_x", "reference_temperature_degc": 25.0,
                               "coefficients": (0.0, 1.0), "covariance": np.eye(2),
                               "chi2": 1.0, "dof": 3, "order_criterion": "aicc"}
    with pytest.raises(InvalidInputError, match=message):
        ParameterTemperatureModel(**{**args, **kw})  # type: ignore[arg-type]


@pytest.mark.parametrize(("kw", "message"), [
    ({"max_abs_z": -1.0}, "max_abs_z` must be ≥ 0"),
    ({"dof": 0}, "dof` must be ≥ 1"),
    ({"p_value": 2.0}, r"p_value` must be in \[0, 1\]"),
    ({"consistent": "yes"}, "consistent` must be a boolean"),
])
def test_the_held_out_outcome_checks_its_fields(kw, message):
    args = {"max_abs_z": 1.0, "chi2": 2.0, "dof": 3, "p_value": 0.5, "consistent": True}
    with pytest.raises(InvalidInputError, match=message):
        HeldOutOutcome(**{**args, **kw})  # type: ignore[arg-type]


def test_values_at_and_their_propagated_sigma():
    res = make_result()
    temp = np.array([-40.0, 25.0, 85.0])
    rate = np.array([0.01, 0.0, -0.02])
    leg = np.array([1.0, 0.0, -1.0])
    values, std = res.values_at(temp, rate, leg)
    assert values.shape == std.shape == (3, len(NAMES))
    tm = res.temperature_model("accel_bias_x")
    assert tm is not None and res.temperature_model("accel_M_zz") is None
    i = NAMES.index("accel_bias_x")
    for n in range(3):
        x = temp[n] - T0
        a = np.array([1.0, x, x**2, x**3, rate[n], leg[n]])
        assert values[n, i] == pytest.approx(a @ tm.coefficient_vector, rel=1e-14)
        assert std[n, i] == pytest.approx(math.sqrt(a @ tm.covariance @ a), rel=1e-12)
    # at T0, steady, the mean leg: the result's values; without a model: value and σ as listed
    np.testing.assert_allclose(values[1], res.values, rtol=1e-15, atol=0)
    j = NAMES.index("accel_M_zz")
    assert np.all(values[:, j] == res.values[j]) and np.all(std[:, j] == res.sigma("accel_M_zz"))
    with pytest.raises(InvalidInputError, match="temperature_degc"):
        res.values_at([np.nan])


def test_triad_model_carries_the_temperature_dependence():
    res = make_result()
    accel = res.triad_model("accel")
    assert accel.temperature is not None
    expected = TemperatureDependence(
        T0, {"bias": [[1e-4, 0, 0], [-2e-6, 0, 0], [3e-8, 0, 0]]},
        {"bias": [0.5, 0.0, 0.0]})
    assert accel.temperature.isclose(expected, atol=0.0)
    assert accel.bias[0] == 0.02
    assert res.triad_model("accel", leg=1).bias[0] == pytest.approx(0.021, rel=1e-15)
    assert res.triad_model("accel", leg=-1).bias[0] == pytest.approx(0.019, rel=1e-15)
    gyro = res.triad_model("gyro")
    m_poly = np.zeros((3, 3, 3))
    m_poly[0, 0, 1] = 2e-6
    b_poly = np.zeros((3, 3))
    b_poly[0, 2], b_poly[2, 2] = 1e-6, 1e-10
    assert gyro.temperature is not None and gyro.temperature.isclose(TemperatureDependence(
        T0, {"bias": b_poly, "scale_misalignment": m_poly}, {"bias": [0.0, 0.0, -1e-4]}),
        atol=0.0)
    assert make_result(models=()).triad_model("gyro").temperature is None
    with pytest.raises(InvalidInputError, match="`leg` must be -1, 0 or 1"):
        res.triad_model("gyro", leg=2)
    assert isinstance(gyro, TriadModel)


def test_a_per_axis_result_with_models_has_no_triad_model_form():
    names = (*triad_parameter_names("accel", "per-axis"),)
    values = np.r_[np.ones(3), np.zeros(3)]
    res = CalibrationResult(
        sensor_id="u", procedure="p2", model="per-axis", param_names=names, values=values,
        covariance=np.zeros((6, 6)), units=dict.fromkeys(names, "1"),
        temperature_models=(ParameterTemperatureModel(
            name="accel_K_x", reference_temperature_degc=20.0, coefficients=(1.0, 1e-5),
            covariance=np.zeros((2, 2)), chi2=1.0, dof=2, order_criterion="fixed"),))
    with pytest.raises(InvalidInputError, match="per-axis result's temperature models"):
        res.triad_model("accel")
    assert CalibrationResult.from_json(res.to_json()).to_json() == res.to_json()
