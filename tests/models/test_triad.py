"""Tests of imucalib.models.triad: hand-computed cases, inverse property, round trips, bad input."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models import triad
from imucalib.models.temperature import TemperatureDependence
from imucalib.models.triad import PARAMETER_NAMES, TriadModel, apply_triad, correct_triad
from imucalib.units import DEG, G0_MPS2

RNG_SEED = 20240611
SHAPES = {"bias": (3,), "scale_misalignment": (3, 3), "k2": (3,), "k3": (3,), "koq": (3,),
          "scale_asymmetry": (3,), "g_sensitivity": (3, 3), "g2_sensitivity": (3, 6),
          "lever_arms_b_m": (3, 3)}


def _inputs(n=50, scale=10.0, seed=RNG_SEED):
    return np.random.default_rng(seed).normal(0.0, scale, (n, 3))


# --- identity ------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["gyro", "accel"])
def test_ideal_model_changes_nothing(kind):
    model = TriadModel.ideal(kind)
    x = _inputs()
    extra = {"specific_force_b_mps2": _inputs(seed=1), "rate_b_rps": _inputs(seed=2),
             "angular_accel_b_rps2": _inputs(seed=3), "temperature_degc": 40.0}
    np.testing.assert_array_equal(apply_triad(model, x, **extra), x)
    np.testing.assert_array_equal(correct_triad(model, x, **extra), x)
    one = apply_triad(model, [1.0, 2.0, 3.0])
    assert one.shape == (3,)
    np.testing.assert_array_equal(one, [1.0, 2.0, 3.0])
    assert model.is_linear()


def test_apply_does_not_modify_its_input():
    model = TriadModel("accel", bias=1.0, k2=1e-4, lever_arms_b_m=np.full((3, 3), 0.01))
    x, w, a = _inputs(seed=1), _inputs(seed=2, scale=1.0), _inputs(seed=3)
    copies = [v.copy() for v in (x, w, a)]
    y = apply_triad(model, x, rate_b_rps=w, angular_accel_b_rps2=a)
    correct_triad(model, y, rate_b_rps=w, angular_accel_b_rps2=a)
    for v, c in zip((x, w, a), copies, strict=True):
        np.testing.assert_array_equal(v, c)


# --- hand-computed cases -------------------------------------------------------------------


def test_bias_only():
    model = TriadModel("gyro", bias=[0.01, -0.02, 0.03])
    y = apply_triad(model, [[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]])
    np.testing.assert_allclose(y, [[1.01, 1.98, 3.03], [0.01, -0.02, 0.03]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(correct_triad(model, y), [[1, 2, 3], [0, 0, 0]], atol=1e-15)


def test_scalar_bias_is_broadcast():
    np.testing.assert_array_equal(TriadModel("accel", bias=0.5).bias, [0.5, 0.5, 0.5])


def test_scale_only():
    model = TriadModel("accel", scale_misalignment=np.diag([0.01, -0.02, 0.0]))
    y = apply_triad(model, [2.0, 3.0, 4.0])
    np.testing.assert_allclose(y, [2.02, 2.94, 4.0], rtol=1e-15)


def test_misalignment_couples_the_other_axes():
    m = np.zeros((3, 3))
    m[0, 1] = 1e-3  # x sensor sees part of the body y input
    m[2, 0] = -2e-3
    model = TriadModel("gyro", scale_misalignment=m)
    y = apply_triad(model, [0.0, 5.0, 0.0])
    np.testing.assert_allclose(y, [5e-3, 5.0, 0.0], rtol=1e-15, atol=1e-18)
    y = apply_triad(model, [5.0, 0.0, 0.0])
    np.testing.assert_allclose(y, [5.0, 0.0, -1e-2], rtol=1e-15, atol=1e-18)


def test_k2_on_one_g():
    k2 = 100e-6 / G0_MPS2  # 100 µg/g² in SI [1/(m/s²)]
    model = TriadModel("accel", k2=[0.0, 0.0, k2])
    y = apply_triad(model, [0.0, 0.0, G0_MPS2])
    # K2·g² = 100 µg
    np.testing.assert_allclose(y, [0.0, 0.0, G0_MPS2 + 100e-6 * G0_MPS2], rtol=1e-15)
    y_down = apply_triad(model, [0.0, 0.0, -G0_MPS2])
    np.testing.assert_allclose(y_down[2], -G0_MPS2 + 100e-6 * G0_MPS2, rtol=1e-15)  # even term


def test_k3_and_odd_quadratic():
    model = TriadModel("accel", k3=[1e-6, 0, 0], koq=[0, 1e-4, 0])
    y = apply_triad(model, [[10.0, 10.0, 0.0], [-10.0, -10.0, 0.0]])
    np.testing.assert_allclose(y[:, 0], [10.0 + 1e-3, -10.0 - 1e-3], rtol=1e-15)
    np.testing.assert_allclose(y[:, 1], [10.0 + 1e-2, -10.0 - 1e-2], rtol=1e-15)  # odd: u|u|


def test_asymmetry_gives_different_slopes():
    s, asym = 0.01, 2e-3
    m = np.diag([s, 0.0, 0.0])
    model = TriadModel("gyro", scale_misalignment=m, scale_asymmetry=[asym, 0, 0])
    rate = 100 * DEG
    y_pos = apply_triad(model, [rate, 0, 0])[0]
    y_neg = apply_triad(model, [-rate, 0, 0])[0]
    np.testing.assert_allclose(y_pos / rate, (1 + s) * (1 + asym / 2), rtol=1e-14)
    np.testing.assert_allclose(y_neg / -rate, (1 + s) * (1 - asym / 2), rtol=1e-14)
    # (K+ − K−)/mean = asym
    k_pos, k_neg = y_pos / rate, y_neg / -rate
    np.testing.assert_allclose((k_pos - k_neg) / ((k_pos + k_neg) / 2), asym, rtol=1e-12)


def test_g_sensitivity_and_g2_columns():
    g = np.zeros((3, 3))
    g[0, 2] = 1e-4  # x gyro output per m/s² along z
    g2 = np.zeros((3, 6))
    g2[1, :] = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]  # columns fx², fy², fz², fx fy, fx fz, fy fz
    model = TriadModel("gyro", g_sensitivity=g, g2_sensitivity=g2 * 1e-7)
    f = np.array([1.0, 2.0, 3.0])
    y = apply_triad(model, [0.0, 0.0, 0.0], specific_force_b_mps2=f)
    q = np.array([1.0, 4.0, 9.0, 2.0, 3.0, 6.0])
    np.testing.assert_allclose(y, [3e-4, 1e-7 * (g2[1] @ q), 0.0], rtol=1e-15)
    assert not model.is_linear()
    np.testing.assert_allclose(correct_triad(model, y, specific_force_b_mps2=f), 0.0, atol=1e-19)


def test_size_effect_centripetal_sign():
    # accelerometer x at 10 cm along x, table spinning about z: senses ω×(ω×r) = −ω² r
    arms = np.zeros((3, 3))
    arms[0] = [0.1, 0.0, 0.0]
    model = TriadModel("accel", lever_arms_b_m=arms)
    w = 2.0
    f = np.array([0.0, 0.0, G0_MPS2])
    y = apply_triad(model, f, rate_b_rps=[0.0, 0.0, w], angular_accel_b_rps2=[0.0, 0.0, 0.0])
    np.testing.assert_allclose(y, [-(w**2) * 0.1, 0.0, G0_MPS2], rtol=1e-15, atol=1e-15)


def test_size_effect_tangential_term():
    # accelerometer y at 10 cm along x, angular acceleration about z: ω̇ × r = (0, 0.1·ω̇, 0)
    arms = np.zeros((3, 3))
    arms[1] = [0.1, 0.0, 0.0]
    model = TriadModel("accel", lever_arms_b_m=arms)
    y = apply_triad(model, [0.0, 0.0, 0.0], rate_b_rps=[0.0, 0.0, 0.0],
                    angular_accel_b_rps2=[0.0, 0.0, 5.0])
    np.testing.assert_allclose(y, [0.0, 0.5, 0.0], atol=1e-15)


def test_size_effect_passes_through_the_sensor_row():
    # sensor x at r_x = (0, 0.1, 0) with misalignment M_xy = δ: u_x = f_x + δ·(f_y − 0.1 ω²)
    delta, w = 2e-3, 3.0
    arms = np.zeros((3, 3))
    arms[0] = [0.0, 0.1, 0.0]
    m = np.zeros((3, 3))
    m[0, 1] = delta
    model = TriadModel("accel", scale_misalignment=m, lever_arms_b_m=arms)
    f = np.array([1.0, 2.0, 3.0])
    kin = {"rate_b_rps": [0.0, 0.0, w], "angular_accel_b_rps2": [0.0, 0.0, 0.0]}
    y = apply_triad(model, f, **kin)
    np.testing.assert_allclose(y[0], 1.0 + delta * (2.0 - 0.1 * w**2), rtol=1e-15)
    np.testing.assert_allclose(correct_triad(model, y, **kin), f, rtol=1e-14)


def test_temperature_polynomial_and_rate_on_bias():
    c1, c2, d = 1e-4, 2e-6, 5e-3
    dep = TemperatureDependence(
        20.0,
        {"bias": [[c1, 0.0, 0.0], [c2, 0.0, 0.0]]},
        {"bias": [d, 0.0, 0.0]},
    )
    model = TriadModel("gyro", bias=[1e-3, 0.0, 0.0], temperature=dep)
    temps = np.array([20.0, 30.0, 0.0])
    rates = np.array([0.0, 0.5, -1.0])
    y = apply_triad(model, np.zeros((3, 3)), temperature_degc=temps,
                    temperature_rate_degc_ps=rates)
    dt = temps - 20.0
    np.testing.assert_allclose(y[:, 0], 1e-3 + c1 * dt + c2 * dt**2 + d * rates, rtol=1e-14)
    np.testing.assert_array_equal(y[:, 1:], 0.0)
    # a scalar temperature applies to every sample; dT/dt defaults to 0
    y30 = apply_triad(model, np.zeros((2, 3)), temperature_degc=30.0)
    np.testing.assert_allclose(y30[:, 0], 1e-3 + c1 * 10 + c2 * 100, rtol=1e-14)


def test_temperature_on_scale_factor():
    dep = TemperatureDependence(25.0, {"scale_misalignment": [np.diag([1e-4, 0.0, 0.0])]})
    model = TriadModel("accel", temperature=dep)
    y = apply_triad(model, [[G0_MPS2, 0, 0]] * 2, temperature_degc=[25.0, 35.0])
    np.testing.assert_allclose(y[:, 0], [G0_MPS2, G0_MPS2 * (1 + 1e-3)], rtol=1e-15)


def test_temperature_ignored_when_model_has_none():
    model = TriadModel("accel", bias=1.0)
    y = apply_triad(model, np.zeros((2, 3)), temperature_degc=[1.0, 2.0])
    np.testing.assert_array_equal(y, 1.0)


# --- the inverse, as a property ------------------------------------------------------------

unit = st.floats(-1.0, 1.0, allow_subnormal=False)


def _arr(draw, shape, scale):
    if not draw(st.booleans()):
        return np.zeros(shape)
    return draw(hnp.arrays(np.float64, shape, elements=unit)) * scale


# realistic ranges (docs/equations.md §13): scale/misalignment ±2 %, K2 ≤ 1e-3/g,
# inputs up to 16 g or 2000 °/s
ACCEL_SCALES = {"bias": 0.5, "scale_misalignment": 0.02, "k2": 1e-3 / G0_MPS2,
                "k3": 1e-5 / G0_MPS2**2, "koq": 1e-3 / G0_MPS2, "scale_asymmetry": 1e-2,
                "lever_arms_b_m": 0.02}
GYRO_SCALES = {"bias": 0.05, "scale_misalignment": 0.02, "k2": 5e-4, "k3": 1e-5, "koq": 5e-4,
               "scale_asymmetry": 1e-2, "g_sensitivity": 0.02 * DEG, "g2_sensitivity": 1e-5}


@st.composite
def models(draw, kind):
    scales = ACCEL_SCALES if kind == "accel" else GYRO_SCALES
    params = {name: _arr(draw, SHAPES[name], scale) for name, scale in scales.items()}
    temperature = None
    if draw(st.booleans()):
        coeffs, rates = {}, {}
        for name, scale in scales.items():
            shape = params[name].shape
            if draw(st.booleans()):
                k = draw(st.integers(1, 3))
                # each term stays within 20 % of the parameter's range over ±60 °C
                coeffs[name] = np.stack([
                    draw(hnp.arrays(np.float64, shape, elements=unit)) * 0.2 * scale / 60.0**j
                    for j in range(1, k + 1)
                ])
            if draw(st.booleans()):
                rates[name] = draw(hnp.arrays(np.float64, shape, elements=unit)) * 0.1 * scale
        temperature = TemperatureDependence(draw(st.floats(0.0, 40.0)), coeffs, rates)
    return TriadModel(kind, temperature=temperature, **params)


@st.composite
def scenarios(draw, kind):
    model = draw(models(kind))
    n = draw(st.integers(1, 12))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    big = 16 * G0_MPS2 if kind == "accel" else 2000 * DEG
    # inputs spread over the full range, with exact zeros and the extremes included
    x = rng.uniform(-big, big, (n, 3)) * draw(st.sampled_from([1.0, 1e-3, 0.0]))
    x[0] = draw(st.sampled_from([[big, -big, 0.0], [0.0, 0.0, 0.0], [-big, big, big]]))
    kw = {
        "specific_force_b_mps2": rng.uniform(-16 * G0_MPS2, 16 * G0_MPS2, (n, 3)),
        "rate_b_rps": rng.uniform(-2000 * DEG, 2000 * DEG, (n, 3)) / np.sqrt(3),
        "angular_accel_b_rps2": rng.uniform(-100.0, 100.0, (n, 3)),
    }
    if model.temperature is not None:
        kw["temperature_degc"] = (rng.uniform(-40.0, 85.0, n) if draw(st.booleans())
                                  else float(rng.uniform(-40.0, 85.0)))
        if draw(st.booleans()):
            kw["temperature_rate_degc_ps"] = rng.uniform(-1.0, 1.0, n)
    return model, x, kw


def _reference_apply(model, x, kw):
    """The model equation written out sample by sample and sensor by sensor (slow, plain)."""
    n = x.shape[0]
    temps = np.broadcast_to(kw.get("temperature_degc", 0.0), (n,))
    rates = np.broadcast_to(kw.get("temperature_rate_degc_ps", 0.0), (n,))
    dep = model.temperature
    out = np.zeros((n, 3))
    for k in range(n):
        p = {}
        for name in PARAMETER_NAMES:
            value = getattr(model, name).copy()
            if dep is not None:
                dt = temps[k] - dep.reference_temperature_degc
                for j, c in enumerate(dep.coefficients.get(name, []), start=1):
                    value = value + c * dt**j
                value = value + dep.rate_coefficients.get(name, 0.0) * rates[k]
            p[name] = value
        a_mat = np.eye(3) + p["scale_misalignment"]
        for i in range(3):
            xi = x[k].copy()
            if model.kind == "accel":
                w, alpha = kw["rate_b_rps"][k], kw["angular_accel_b_rps2"][k]
                r = p["lever_arms_b_m"][i]
                xi = xi + np.cross(alpha, r) + np.cross(w, np.cross(w, r))
            u = a_mat[i] @ xi
            y = (p["bias"][i] + u + p["k2"][i] * u**2 + p["k3"][i] * u**3
                 + p["koq"][i] * u * abs(u) + p["scale_asymmetry"][i] / 2 * abs(u))
            if model.kind == "gyro":
                f = kw["specific_force_b_mps2"][k]
                q = [f[0] ** 2, f[1] ** 2, f[2] ** 2, f[0] * f[1], f[0] * f[2], f[1] * f[2]]
                y += p["g_sensitivity"][i] @ f + p["g2_sensitivity"][i] @ q
            out[k, i] = y
    return out


@pytest.mark.parametrize("kind", ["gyro", "accel"])
@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_apply_matches_the_model_equation_and_correct_inverts_it(kind, data):
    model, x, kw = data.draw(scenarios(kind))
    y = apply_triad(model, x, **kw)
    scale = max(np.max(np.abs(x)), np.max(np.abs(y)), 1e-300)
    np.testing.assert_allclose(y, _reference_apply(model, x, kw), rtol=0.0, atol=1e-13 * scale)
    back = correct_triad(model, y, **kw)
    np.testing.assert_allclose(back, x, rtol=0.0, atol=1e-9 * scale)
    # one sample as a (3,) vector gives the same as row 0
    one_kw = {k: (v if np.ndim(v) == 0 else np.asarray(v)[0]) for k, v in kw.items()}
    np.testing.assert_allclose(apply_triad(model, x[0], **one_kw), y[0], rtol=0, atol=1e-14 * scale)


@pytest.mark.parametrize("varying", [(), ("scale_misalignment",), ("lever_arms_b_m",),
                                     ("scale_misalignment", "lever_arms_b_m")])
def test_size_effect_matches_the_direct_formula(varying):
    rng = np.random.default_rng(RNG_SEED)
    n = 7
    dep = TemperatureDependence(
        20.0, {name: [rng.normal(0, 1e-4, (3, 3))] for name in varying},
        {name: rng.normal(0, 1e-4, (3, 3)) for name in varying},
    )
    model = TriadModel("accel", scale_misalignment=rng.normal(0, 0.02, (3, 3)),
                       lever_arms_b_m=rng.normal(0, 0.05, (3, 3)), temperature=dep)
    x = rng.normal(0, 10, (n, 3))
    kw = {"rate_b_rps": rng.normal(0, 5, (n, 3)), "angular_accel_b_rps2": rng.normal(0, 50, (n, 3)),
          "temperature_degc": rng.uniform(-40, 85, n),
          "temperature_rate_degc_ps": rng.normal(0, 1, n)}
    y = apply_triad(model, x, **kw)
    np.testing.assert_allclose(y, _reference_apply(model, x, kw), rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(correct_triad(model, y, **kw), x, rtol=0, atol=1e-12)


def test_correct_inverts_apply_on_many_samples_with_everything():
    rng = np.random.default_rng(RNG_SEED)
    n = 20_000  # several Newton blocks
    dep = TemperatureDependence(25.0, {"k2": [[1e-6, 0, 0]], "lever_arms_b_m": [np.eye(3) * 1e-5],
                                       "scale_misalignment": [np.full((3, 3), 1e-5)]})
    model = TriadModel("accel", bias=[0.1, -0.2, 0.3],
                       scale_misalignment=rng.normal(0, 0.01, (3, 3)), k2=5e-5, k3=-1e-7,
                       koq=[1e-5, -1e-5, 0], scale_asymmetry=[1e-3, 0, -2e-3],
                       lever_arms_b_m=rng.normal(0, 0.01, (3, 3)), temperature=dep)
    x = rng.uniform(-150, 150, (n, 3))
    kw = {"rate_b_rps": rng.normal(0, 5, (n, 3)), "angular_accel_b_rps2": rng.normal(0, 50, (n, 3)),
          "temperature_degc": rng.uniform(-40, 85, n)}
    back = correct_triad(model, apply_triad(model, x, **kw), **kw)
    np.testing.assert_allclose(back, x, rtol=0, atol=1e-12 * 150)


# --- model object --------------------------------------------------------------------------

finite = st.floats(allow_nan=False, allow_infinity=False)


@st.composite
def any_models(draw):
    kind = draw(st.sampled_from(["gyro", "accel"]))
    shapes = SHAPES
    forbidden = ("g_sensitivity", "g2_sensitivity") if kind == "accel" else ("lever_arms_b_m",)
    params = {n: draw(hnp.arrays(np.float64, s, elements=finite))
              for n, s in shapes.items() if n not in forbidden}
    temperature = None
    if draw(st.booleans()):
        names = draw(st.lists(st.sampled_from([n for n in shapes if n not in forbidden]),
                              unique=True, max_size=3))
        coeffs = {n: draw(hnp.arrays(np.float64, (draw(st.integers(1, 3)), *shapes[n]),
                                     elements=finite)) for n in names}
        rates = {n: draw(hnp.arrays(np.float64, shapes[n], elements=finite)) for n in names[:1]}
        temperature = TemperatureDependence(draw(finite), coeffs, rates)
    return TriadModel(kind, temperature=temperature, **params)


@settings(max_examples=60, deadline=None)
@given(any_models())
def test_json_round_trip_is_exact(model):
    text = json.dumps(model.to_dict(), allow_nan=False)
    back = TriadModel.from_dict(json.loads(text))
    assert back.isclose(model, atol=0.0)
    for name in PARAMETER_NAMES:
        assert getattr(back, name).tobytes() == getattr(model, name).tobytes()


def test_arrays_are_copied_and_read_only():
    bias = np.array([1.0, 2.0, 3.0])
    model = TriadModel("gyro", bias=bias)
    bias[0] = 99.0
    assert model.bias[0] == 1.0
    with pytest.raises(ValueError, match="read-only"):
        model.bias[0] = 5.0
    assert pickle.loads(pickle.dumps(model)).isclose(model, atol=0.0)


def test_replace_isclose_is_linear():
    model = TriadModel("accel", bias=[1e-3, 0, 0])
    other = model.replace(k2=1e-5)
    assert not other.is_linear() and model.is_linear()
    assert not model.isclose(other, atol=1e-6) and model.isclose(other, atol=1e-5)
    assert not model.isclose(TriadModel("gyro", bias=[1e-3, 0, 0]), atol=1.0)
    # temperature: None equals an all-zero dependence, whatever its reference temperature
    zero_dep = TemperatureDependence(60.0, {"bias": [[0.0, 0.0, 0.0]]})
    assert model.isclose(model.replace(temperature=zero_dep), atol=0.0)
    nonlinear_in_t = model.replace(temperature=TemperatureDependence(
        coefficients={"scale_asymmetry": [[1e-6, 0, 0]]}))
    assert not nonlinear_in_t.is_linear()
    with pytest.raises(InvalidInputError, match=r"unknown TriadModel field\(s\) \['scale'\]"):
        model.replace(scale=1.0)
    with pytest.raises(InvalidInputError, match=r"`k2` must have shape \(3,\); got \(2,\)"):
        model.replace(k2=[1.0, 2.0])


# --- bad input -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"kind": "gyro", "bias": [1.0, 2.0, 3.0, 4.0]}, InvalidInputError,
         r"`bias` must have shape \(3,\); got \(4,\)"),
        ({"kind": "gyro", "scale_misalignment": np.zeros((3, 2))}, InvalidInputError,
         r"`scale_misalignment` must have shape \(3, 3\); got \(3, 2\)"),
        ({"kind": "gyro", "g2_sensitivity": np.zeros((3, 3))}, InvalidInputError,
         r"`g2_sensitivity` must have shape \(3, 6\); got \(3, 3\)"),
        ({"kind": "accel", "k2": [0.0, np.nan, 0.0]}, InvalidInputError,
         r"`k2` must be finite; got 1 NaN"),
        ({"kind": "gyro", "lever_arms_b_m": np.eye(3) * 0.01}, ConfigurationError,
         r"`lever_arms_b_m` must be zero for a gyro triad"),
        ({"kind": "accel", "g_sensitivity": np.eye(3) * 1e-4}, ConfigurationError,
         r"`g_sensitivity` must be zero for an accelerometer triad"),
        ({"kind": "accel", "temperature": TemperatureDependence(
            coefficients={"g2_sensitivity": [np.ones((3, 6))]})}, ConfigurationError,
         r"`g2_sensitivity` must be zero for an accelerometer .* temperature dependence"),
        ({"kind": "magnetometer"}, ConfigurationError,
         r"`kind` must be 'gyro' or 'accel'; got 'magnetometer'"),
        ({"kind": "gyro", "temperature": TemperatureDependence(coefficients={"bais": [[1, 0, 0]]})},
         ConfigurationError, r"`temperature` names unknown parameter\(s\) \['bais'\]"),
        ({"kind": "gyro", "temperature": TemperatureDependence(coefficients={"bias": [[1, 0]]})},
         InvalidInputError, r"`temperature.coefficients\['bias'\]` must have shape \(K, 3\)"),
        ({"kind": "gyro", "temperature": TemperatureDependence(
            rate_coefficients={"g_sensitivity": [1.0, 0.0, 0.0]})}, InvalidInputError,
         r"`temperature.rate_coefficients\['g_sensitivity'\]` must have shape \(3, 3\)"),
        ({"kind": "gyro", "temperature": {"bias": [[1, 0, 0]]}}, InvalidInputError,
         r"`temperature` must be a TemperatureDependence or None; got dict"),
    ],
)
def test_constructor_rejects(kwargs, error, match):
    with pytest.raises(error, match=match):
        TriadModel(**kwargs)


def test_missing_arguments_are_named():
    temp_model = TriadModel("gyro", temperature=TemperatureDependence(
        coefficients={"bias": [[1e-5, 0, 0]]}))
    with pytest.raises(InvalidInputError,
                       match=r"`temperature_degc` is required: the gyro model's bias depend"):
        apply_triad(temp_model, np.zeros((2, 3)))
    with pytest.raises(InvalidInputError, match=r"`temperature_degc` is required"):
        correct_triad(temp_model, np.zeros((2, 3)))
    arms = TriadModel("accel", lever_arms_b_m=np.eye(3)[::-1] * 0.01)
    with pytest.raises(InvalidInputError, match=r"`rate_b_rps` is required: .*lever arms"):
        apply_triad(arms, np.zeros((2, 3)), angular_accel_b_rps2=np.zeros((2, 3)))
    with pytest.raises(InvalidInputError, match=r"`angular_accel_b_rps2` is required"):
        correct_triad(arms, np.zeros((2, 3)), rate_b_rps=np.zeros((2, 3)))
    g_model = TriadModel("gyro", g_sensitivity=np.eye(3) * 1e-4)
    with pytest.raises(InvalidInputError, match=r"`specific_force_b_mps2` is required"):
        apply_triad(g_model, np.zeros((2, 3)))


def test_bad_sample_arrays():
    model = TriadModel("accel", lever_arms_b_m=np.eye(3)[::-1] * 0.01,
                       temperature=TemperatureDependence(coefficients={"bias": [[1e-5, 0, 0]]}))
    good = {"rate_b_rps": np.zeros((2, 3)), "angular_accel_b_rps2": np.zeros((2, 3)),
            "temperature_degc": 20.0}
    with pytest.raises(InvalidInputError, match=r"`input_b` must have shape \(n, 3\) or \(3,\)"):
        apply_triad(model, np.zeros((2, 4)), **good)
    with pytest.raises(InvalidInputError, match=r"`measured_s` must be finite; got 1 NaN"):
        correct_triad(model, [[0.0, np.nan, 0.0], [0, 0, 0]], **good)
    with pytest.raises(InvalidInputError, match=r"`rate_b_rps` must have shape \(2, 3\) like"):
        apply_triad(model, np.zeros((2, 3)), **{**good, "rate_b_rps": np.zeros((3, 3))})
    with pytest.raises(InvalidInputError, match=r"`temperature_degc` must be a scalar or have "
                                                 r"shape \(2,\), one per sample; got \(3,\)"):
        apply_triad(model, np.zeros((2, 3)), **{**good, "temperature_degc": np.zeros(3)})
    with pytest.raises(InvalidInputError, match=r"`input_b` must be numeric"):
        apply_triad(model, "abc", **good)
    with pytest.raises(InvalidInputError, match=r"`tol` must be > 0"):
        correct_triad(model, np.zeros((2, 3)), tol=0.0, **good)
    with pytest.raises(InvalidInputError, match=r"`max_iter` must be an integer ≥ 1; got 0"):
        correct_triad(model, np.zeros((2, 3)), max_iter=0, **good)


def test_correct_outside_monotonic_range_is_an_error():
    # h(u) = u − 0.01·u² peaks at u = 50 with h = 25: a measurement of 30 has no preimage
    model = TriadModel("accel", k2=[-0.01, 0.0, 0.0])
    np.testing.assert_allclose(correct_triad(model, [[24.0, 0, 0]])[0, 0],
                               (1 - np.sqrt(1 - 0.04 * 24)) / 0.02, rtol=1e-13)
    with pytest.raises(InvalidInputError,
                       match=r"cannot invert .* for 1 value\(s\) \(largest \|measured - bias\| 30\)"
                             r": outside the monotonic range"):
        correct_triad(model, [[24.0, 0, 0], [30.0, 0, 0]])
    # a cubic whose slope turns negative before the root: h(u) = u − 0.03u² + 3e-4u³ + …
    cubic = TriadModel("accel", k2=[-0.03, 0, 0], k3=[2.9e-4, 0, 0])
    with pytest.raises(InvalidInputError, match="outside the monotonic range"):
        correct_triad(cubic, apply_triad(cubic, [[150.0, 0, 0]]))
    with pytest.raises(InvalidInputError, match=r"\|scale_asymmetry\| ≥ 2"):
        correct_triad(TriadModel("gyro", scale_asymmetry=[2.5, 0, 0]), [[1.0, 0, 0]])


def test_newton_budget_and_bracketed_fallback():
    model = TriadModel("accel", k2=[1e-4, 0, 0], k3=[1e-6, 0, 0])
    y = apply_triad(model, [[100.0, 0.0, 0.0]])
    with pytest.raises(InvalidInputError, match=r"no convergence within max_iter=1 to tol=1e-13"):
        correct_triad(model, y, max_iter=1)
    np.testing.assert_allclose(correct_triad(model, y, max_iter=5), [[100.0, 0, 0]], rtol=1e-14)
    # the safeguarded solver alone, from a poor start, on a nearly flat monotonic cubic
    a1, a2, a3 = np.ones(3), np.full(3, -0.01), np.full(3, 3.4e-5)
    v_true = np.array([1.0, 100.0, 250.0])
    t = ((a3 * v_true + a2) * v_true + a1) * v_true
    np.testing.assert_allclose(triad._bracketed_newton(a1, a2, a3, t, 1e-13, 200), v_true,
                               rtol=1e-10)
    # no root (h peaks at 25 below t = 30): NaN, which correct_triad turns into an error
    with np.errstate(all="ignore"):
        out = triad._bracketed_newton(np.ones(1), np.full(1, -0.01), np.zeros(1), np.full(1, 30.0),
                                      1e-13, 50)
    assert np.isnan(out[0])


def test_singular_scale_matrix_is_an_error():
    model = TriadModel("gyro", scale_misalignment=-np.eye(3))
    with pytest.raises(InvalidInputError, match=r"\(I \+ scale_misalignment\) is singular"):
        correct_triad(model, [[1.0, 0, 0]])


def test_from_dict_rejects_unknown_keys():
    d = TriadModel.ideal("gyro").to_dict()
    d["scale"] = 1.0
    with pytest.raises(InvalidInputError, match=r"unknown key\(s\) \['scale'\]"):
        TriadModel.from_dict(d)
    with pytest.raises(InvalidInputError, match=r"at least the key 'kind'"):
        TriadModel.from_dict({"bias": [0, 0, 0]})
    assert TriadModel.from_dict({"kind": "accel"}).isclose(TriadModel.ideal("accel"), atol=0.0)
