"""Tests of imucalib.models.temperature: polynomial and rate terms, validation, round trips."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from imucalib.errors import InvalidInputError
from imucalib.models.temperature import TemperatureDependence, evaluate_parameter

BASE = np.array([0.1, -0.2, 0.3])


def test_no_dependence_returns_base_unchanged():
    dep = TemperatureDependence(coefficients={"other": [[1.0, 1.0, 1.0]]})
    for d in (None, dep):
        out = evaluate_parameter(BASE, "bias", d, 40.0, 1.0)
        assert out.shape == (3,)
        np.testing.assert_array_equal(out, BASE)
    # no temperature needed when the parameter does not depend on it
    np.testing.assert_array_equal(evaluate_parameter(BASE, "bias", dep, None, None), BASE)


def test_polynomial_hand_computed():
    c1 = np.array([1e-3, 2e-3, -3e-3])
    c2 = np.array([1e-5, 0.0, 2e-5])
    c3 = np.array([0.0, 1e-7, 0.0])
    dep = TemperatureDependence(20.0, {"bias": [c1, c2, c3]})
    temps = np.array([20.0, 30.0, -10.0])
    out = evaluate_parameter(BASE, "bias", dep, temps, None)
    assert out.shape == (3, 3)
    for row, temp in zip(out, temps, strict=True):
        dt = temp - 20.0
        np.testing.assert_allclose(row, BASE + c1 * dt + c2 * dt**2 + c3 * dt**3, rtol=1e-15)
    # at T0 exactly the base value
    np.testing.assert_array_equal(out[0], BASE)
    # a single value by hand: axis 0 at 30 °C is 0.1 + 1e-3·10 + 1e-5·100 = 0.111
    assert out[1, 0] == pytest.approx(0.111, rel=1e-14)


def test_rate_term_hand_computed():
    d = np.array([0.01, 0.0, -0.02])
    dep = TemperatureDependence(25.0, rate_coefficients={"bias": d})
    out = evaluate_parameter(BASE, "bias", dep, [25.0, 25.0], [0.5, -1.0])
    np.testing.assert_allclose(out, [BASE + 0.5 * d, BASE - d], rtol=1e-15)
    # dT/dt defaults to 0
    np.testing.assert_array_equal(evaluate_parameter(BASE, "bias", dep, 60.0, None), [BASE])


def test_polynomial_and_rate_together_on_a_matrix():
    base = np.eye(3) * 1e-3
    c1 = np.arange(9.0).reshape(3, 3) * 1e-5
    d = np.ones((3, 3)) * 1e-4
    dep = TemperatureDependence(0.0, {"m": [c1]}, {"m": d})
    out = evaluate_parameter(base, "m", dep, 10.0, 2.0)
    assert out.shape == (1, 3, 3)
    np.testing.assert_allclose(out[0], base + 10.0 * c1 + 2.0 * d, rtol=1e-15)


def test_scalar_rate_broadcasts_over_temperatures():
    dep = TemperatureDependence(0.0, {"b": [[1.0, 1.0, 1.0]]}, {"b": [1.0, 1.0, 1.0]})
    out = evaluate_parameter(np.zeros(3), "b", dep, [1.0, 2.0, 3.0], 10.0)
    np.testing.assert_array_equal(out[:, 0], [11.0, 12.0, 13.0])


def test_empty_temperature_vector():
    dep = TemperatureDependence(coefficients={"b": [[1.0, 1.0, 1.0]]})
    assert evaluate_parameter(np.zeros(3), "b", dep, np.zeros(0), None).shape == (0, 3)


def test_missing_temperature_is_an_error():
    dep = TemperatureDependence(coefficients={"bias": [[1e-3, 0.0, 0.0]]})
    with pytest.raises(InvalidInputError, match=r"`temperature_degc` is required.*'bias'"):
        evaluate_parameter(BASE, "bias", dep, None, None)


def test_bad_temperature_shapes():
    dep = TemperatureDependence(coefficients={"bias": [[1e-3, 0.0, 0.0]]})
    with pytest.raises(InvalidInputError, match=r"`temperature_degc` must be a scalar.*\(2, 2\)"):
        evaluate_parameter(BASE, "bias", dep, np.zeros((2, 2)), None)
    with pytest.raises(InvalidInputError, match=r"`temperature_rate_degc_ps` must be .*got \(2,\)"):
        evaluate_parameter(BASE, "bias", dep, [1.0, 2.0, 3.0], [0.0, 0.0])
    with pytest.raises(InvalidInputError, match=r"`temperature_degc` must be finite"):
        evaluate_parameter(BASE, "bias", dep, [1.0, np.nan], None)


def test_coefficient_shape_must_match_parameter():
    dep = TemperatureDependence(coefficients={"bias": [[1.0, 2.0]]}, rate_coefficients={"k": [1.0]})
    with pytest.raises(InvalidInputError, match=r"`coefficients\['bias'\]` must have shape \(K, 3"):
        evaluate_parameter(BASE, "bias", dep, 1.0, None)
    with pytest.raises(InvalidInputError, match=r"`rate_coefficients\['k'\]` must have shape \(3,"):
        evaluate_parameter(BASE, "k", dep, 1.0, None)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"coefficients": {"bias": []}}, r"`coefficients\['bias'\]` must have shape \(K, \*para"),
        ({"coefficients": {"bias": 1.0}}, r"with K ≥ 1.*got \(\)"),
        ({"coefficients": {"bias": [[np.nan, 0, 0]]}}, r"`coefficients\['bias'\]` must be finite"),
        ({"rate_coefficients": {"bias": [np.inf, 0, 0]}}, r"`rate_coefficients\['bias'\]` must"),
        ({"coefficients": [1.0]}, r"`coefficients` must be a mapping .*got list"),
        ({"coefficients": {3: [[1.0]]}}, r"`coefficients` keys must be parameter names; got 3"),
        ({"reference_temperature_degc": float("nan")}, r"`reference_temperature_degc` must be"),
    ],
)
def test_constructor_rejects(kwargs, match):
    with pytest.raises(InvalidInputError, match=match):
        TemperatureDependence(**kwargs)


def test_arrays_and_mappings_are_read_only_and_copied():
    src = np.array([[1.0, 2.0, 3.0]])
    dep = TemperatureDependence(coefficients={"bias": src})
    src[0, 0] = 99.0
    assert dep.coefficients["bias"][0, 0] == 1.0
    with pytest.raises(ValueError, match="read-only"):
        dep.coefficients["bias"][0, 0] = 5.0
    with pytest.raises(TypeError):
        dep.coefficients["k2"] = np.zeros((1, 3))  # type: ignore[index]
    assert dep.parameter_names == ("bias",)
    assert dep.depends_on("bias") and not dep.depends_on("k2")


def test_pickle_round_trip():
    dep = TemperatureDependence(10.0, {"bias": [[1.0, 2.0, 3.0]]}, {"bias": [4.0, 5.0, 6.0]})
    assert pickle.loads(pickle.dumps(dep)).isclose(dep, atol=0.0)


def test_isclose_rules():
    a = TemperatureDependence(25.0, {"bias": [[1e-3, 0.0, 0.0]]})
    padded = TemperatureDependence(25.0, {"bias": [[1e-3, 0.0, 0.0], [0.0, 0.0, 0.0]]})
    assert a.isclose(padded, atol=0.0) and padded.isclose(a, atol=0.0)
    with_zero_extra = TemperatureDependence(25.0, {"bias": [[1e-3, 0, 0]], "k2": [[0.0, 0, 0]]})
    assert a.isclose(with_zero_extra, atol=0.0)
    near = TemperatureDependence(25.0, {"bias": [[1e-3 + 1e-9, 0.0, 0.0]]})
    assert not a.isclose(near, atol=0.0)
    assert a.isclose(near, atol=1e-8)
    assert not a.isclose(TemperatureDependence(30.0, {"bias": [[1e-3, 0, 0]]}), atol=1e-6)
    assert not a.isclose(TemperatureDependence(25.0, {"bias": [[1e-3, 0, 0]]}, {"k3": [1, 0, 0]}),
                         atol=1e-6)
    assert not a.isclose("not a dependence", atol=1.0)  # type: ignore[arg-type]


def test_from_dict_rejects_unknown_keys():
    with pytest.raises(InvalidInputError, match=r"unknown key\(s\) \['degree'\]"):
        TemperatureDependence.from_dict({"degree": 2})
    with pytest.raises(InvalidInputError, match=r"`data` must be a mapping; got list"):
        TemperatureDependence.from_dict([])  # type: ignore[arg-type]


finite = st.floats(allow_nan=False, allow_infinity=False)


@st.composite
def dependences(draw):
    coeffs = {}
    rates = {}
    for name, shape in (("bias", (3,)), ("scale_misalignment", (3, 3)), ("g2", (3, 6))):
        if draw(st.booleans()):
            k = draw(st.integers(1, 3))
            coeffs[name] = draw(hnp.arrays(np.float64, (k, *shape), elements=finite))
        if draw(st.booleans()):
            rates[name] = draw(hnp.arrays(np.float64, shape, elements=finite))
    return TemperatureDependence(draw(finite), coeffs, rates)


@settings(max_examples=40, deadline=None)
@given(dependences())
def test_json_round_trip_is_exact(dep):
    text = json.dumps(dep.to_dict())
    back = TemperatureDependence.from_dict(json.loads(text))
    assert back.isclose(dep, atol=0.0)
    assert back.reference_temperature_degc == dep.reference_temperature_degc
    for mine, theirs in ((dep.coefficients, back.coefficients),
                         (dep.rate_coefficients, back.rate_coefficients)):
        assert set(mine) == set(theirs)
        for name in mine:
            assert mine[name].tobytes() == theirs[name].tobytes()  # bit for bit, -0.0 included
