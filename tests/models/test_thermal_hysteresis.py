"""Thermal hysteresis (Duhem state) in the temperature model and in apply/correct_triad."""

from __future__ import annotations

import json

import numpy as np
import pytest

from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.temperature import (
    TemperatureDependence,
    evaluate_parameter,
    hysteresis_state,
)
from imucalib.models.triad import TriadModel, apply_triad, correct_triad


def _reference(temp: np.ndarray, s0: float, width: float) -> np.ndarray:
    """The exact step-by-step recurrence, one sample at a time."""
    out = [s0]
    for k in range(1, temp.size):
        d = temp[k] - temp[k - 1]
        sgn = float(np.sign(d))
        out.append(sgn + (out[-1] - sgn) * float(np.exp(-abs(d) / width)))
    return np.array(out)


def test_exact_formula_for_a_linear_ramp():
    t = np.linspace(25.0, 35.0, 101)  # heating by 10 °C = 2 widths from s = 0
    s, final = hysteresis_state(t, 0.0, 5.0)
    assert final == pytest.approx(1.0 - np.exp(-2.0), abs=1e-14)
    np.testing.assert_allclose(s, 1.0 - np.exp(-(t - 25.0) / 5.0), rtol=0, atol=1e-14)
    # cooling from s = 0.5 by 3 °C
    s, final = hysteresis_state([40.0, 38.5, 37.0], 0.5, 2.0)
    assert final == pytest.approx(-1.0 + 1.5 * np.exp(-1.5), abs=1e-14)
    assert s[0] == 0.5


def test_limits_and_persistence_at_a_constant_temperature():
    heat = np.concatenate([np.linspace(-20.0, 60.0, 801), np.full(500, 60.0)])
    s, final = hysteresis_state(heat, -1.0, 5.0)
    assert np.all(np.abs(s) <= 1.0)
    assert final == pytest.approx(1.0, abs=1e-6)  # 16 widths of heating
    assert np.all(s[800:] == s[800])  # a soak leaves the state exactly as it was
    cool = np.concatenate([np.linspace(60.0, 20.0, 401), np.full(300, 20.0)])
    s, final = hysteresis_state(cool, final, 5.0)
    assert final == pytest.approx(-1.0, abs=1e-3)
    assert np.all(s[400:] == s[400])
    # a huge single step saturates without overflow
    s, final = hysteresis_state([0.0, 1e6, -1e6], 0.0, 0.01)
    np.testing.assert_allclose(s, [0.0, 1.0, -1.0], rtol=0, atol=1e-15)


def test_matches_the_recurrence_on_a_rough_history():
    temp = np.cumsum(np.random.default_rng(4).normal(0.0, 1.0, 20000))
    s, final = hysteresis_state(temp, 0.3, 5.0)
    np.testing.assert_allclose(s, _reference(temp, 0.3, 5.0), rtol=0, atol=1e-12)
    assert final == s[-1]


def test_chunked_history_equals_the_whole():
    temp = 30.0 * np.sin(np.linspace(0.0, 40.0, 30001)) + np.random.default_rng(1).normal(
        0.0, 0.05, 30001)
    whole, final = hysteresis_state(temp, 0.0, 5.0)
    parts, state, last = [], 0.0, None
    for chunk in np.array_split(temp, 53):
        if last is None:
            s, state = hysteresis_state(chunk, state, 5.0)
        else:
            s, state = hysteresis_state(np.concatenate([[last], chunk]), state, 5.0)
            s = s[1:]
        parts.append(s)
        last = chunk[-1]
    np.testing.assert_allclose(np.concatenate(parts), whole, rtol=0, atol=1e-13)
    assert state == pytest.approx(final, abs=1e-13)


def test_hysteresis_state_rejects_bad_inputs():
    with pytest.raises(InvalidInputError, match="state0"):
        hysteresis_state([1.0, 2.0], 1.5)
    with pytest.raises(InvalidInputError, match="width_degc"):
        hysteresis_state([1.0, 2.0], 0.0, 0.0)
    with pytest.raises(InvalidInputError, match="temperature_degc"):
        hysteresis_state(np.zeros((2, 2)))
    s, final = hysteresis_state([], 0.25)
    assert s.size == 0 and final == 0.25


def _dep() -> TemperatureDependence:
    return TemperatureDependence(
        reference_temperature_degc=20.0,
        coefficients={"bias": [[1e-3, 0.0, 0.0]]},
        hysteresis={"bias": [2e-3, -1e-3, 0.0], "scale_misalignment": np.full((3, 3), 1e-4)},
        hysteresis_width_degc=3.0,
    )


def test_evaluate_parameter_adds_h_times_s():
    dep = _dep()
    base = np.array([0.1, 0.2, 0.3])
    v = evaluate_parameter(base, "bias", dep, [20.0, 30.0], None, [1.0, -0.5])
    np.testing.assert_allclose(v, [[0.102, 0.199, 0.3], [0.1 + 0.01 - 0.001, 0.2005, 0.3]],
                               rtol=0, atol=1e-15)
    # no state: s = 0
    np.testing.assert_allclose(evaluate_parameter(base, "bias", dep, 30.0, None),
                               [[0.11, 0.2, 0.3]], rtol=0, atol=1e-15)
    # hysteresis only: no temperature needed
    m = evaluate_parameter(np.zeros((3, 3)), "scale_misalignment", dep, None, None, -1.0)
    np.testing.assert_allclose(m, np.full((1, 3, 3), -1e-4))
    assert evaluate_parameter(np.zeros((3, 3)), "scale_misalignment", dep, None, None).shape == (
        3, 3)
    with pytest.raises(InvalidInputError, match="hysteresis_state"):
        evaluate_parameter(base, "bias", dep, [20.0, 30.0], None, [1.0, 0.0, 1.0])


def test_dependence_round_trip_and_comparison():
    dep = _dep()
    back = TemperatureDependence.from_dict(json.loads(json.dumps(dep.to_dict())))
    assert back.isclose(dep, atol=0.0) and back.hysteresis_width_degc == 3.0
    assert "bias" in back.parameter_names and "scale_misalignment" in back.parameter_names
    assert back.has_hysteresis and back.depends_on("scale_misalignment")
    plain = TemperatureDependence(20.0, dep.coefficients)
    assert not plain.isclose(dep, atol=1e-6)
    assert "hysteresis" not in plain.to_dict()  # the former description is unchanged
    wider = TemperatureDependence(20.0, dep.coefficients, hysteresis=dep.hysteresis,
                                  hysteresis_width_degc=4.0)
    assert not wider.isclose(dep, atol=1e-6)
    with pytest.raises(InvalidInputError, match="hysteresis_width_degc"):
        TemperatureDependence(hysteresis_width_degc=-1.0)


def test_triad_apply_and_correct_with_a_state():
    model = TriadModel(kind="accel", bias=[0.01, 0.0, 0.0], temperature=_dep())
    f = np.tile([0.0, 0.0, 9.8], (3, 1))
    y = apply_triad(model, f, temperature_degc=[20.0, 20.0, 25.0],
                    hysteresis_state=[1.0, -1.0, 0.0])
    np.testing.assert_allclose(y[:, 0], [0.01 + 2e-3 + 1e-4 * 9.8, 0.01 - 2e-3 - 1e-4 * 9.8,
                                         0.01 + 5e-3], rtol=0, atol=1e-14)
    x = correct_triad(model, y, temperature_degc=[20.0, 20.0, 25.0],
                      hysteresis_state=[1.0, -1.0, 0.0])
    np.testing.assert_allclose(x, f, rtol=0, atol=1e-12)
    # backward compatible: without a state the hysteresis term is absent
    np.testing.assert_allclose(apply_triad(model, f[0], temperature_degc=20.0), [0.01, 0, 9.8])
    with pytest.raises(InvalidInputError, match="hysteresis_state"):
        apply_triad(model, f, temperature_degc=20.0, hysteresis_state=[1.0, 0.0])
    bad = TemperatureDependence(hysteresis={"bias": [1.0, 2.0]})
    with pytest.raises(InvalidInputError, match=r"hysteresis\['bias'\]"):
        TriadModel(kind="accel", temperature=bad)
    with pytest.raises(ConfigurationError, match="unknown parameter"):
        TriadModel(kind="accel", temperature=TemperatureDependence(hysteresis={"nope": [1.0]}))


def test_triad_with_hysteresis_differs_from_one_without():
    model = TriadModel(kind="accel", temperature=_dep())
    assert not model.isclose(TriadModel(kind="accel"), atol=1e-6)
    assert not TriadModel(kind="accel").isclose(model, atol=1e-6)
    back = TriadModel.from_dict(json.loads(json.dumps(model.to_dict())))
    assert back.isclose(model, atol=0.0)
