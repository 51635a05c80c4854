"""Correcting data with a result that carries temperature models: against known truth."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from imucalib.conventions import ACCEL_COLUMNS, AXES, GYRO_COLUMNS
from imucalib.errors import InvalidInputError
from imucalib.models.correct import (
    LEG_DEAD_BAND_DEGC_PS,
    TemperatureRate,
    correct_imu,
    correct_imu_frame,
    temperature_leg,
)
from imucalib.models.result import (
    CalibrationResult,
    ParameterTemperatureModel,
    triad_parameter_names,
)
from imucalib.models.temperature import TemperatureDependence
from imucalib.models.triad import TriadModel, apply_triad

T0 = 20.0
N = 2000


def truth_models(rng: np.random.Generator) -> dict[str, TriadModel]:
    """Triads whose bias, M and G follow cubics in (T − T0) plus a rate term."""
    def dep(*, g: bool) -> TemperatureDependence:
        coeffs = {"bias": rng.normal(size=(3, 3)) * [[1e-4], [1e-6], [1e-8]],
                  "scale_misalignment": rng.normal(size=(3, 3, 3)) * np.array(
                      [1e-5, 1e-7, 1e-9])[:, None, None]}
        rates = {"bias": rng.normal(size=3) * 1e-2}
        if g:
            coeffs["g_sensitivity"] = rng.normal(size=(3, 3, 3)) * np.array(
                [1e-6, 1e-8, 1e-10])[:, None, None]
        return TemperatureDependence(T0, coeffs, rates)

    accel = TriadModel("accel", bias=rng.normal(size=3) * 0.05,
                       scale_misalignment=rng.normal(size=(3, 3)) * 2e-3,
                       temperature=dep(g=False))
    gyro = TriadModel("gyro", bias=rng.normal(size=3) * 1e-3,
                      scale_misalignment=rng.normal(size=(3, 3)) * 1e-3,
                      g_sensitivity=rng.normal(size=(3, 3)) * 1e-4, temperature=dep(g=True))
    return {"accel": accel, "gyro": gyro}


def result_of(models: dict[str, TriadModel], legs: dict[str, float] | None = None
              ) -> CalibrationResult:
    """The CalibrationResult holding exactly `models` (each scalar's polynomial a record)."""
    names: list[str] = []
    values: list[float] = []
    records: list[ParameterTemperatureModel] = []
    legs = legs or {}
    for triad, m in models.items():
        dep = m.temperature
        assert dep is not None
        fields = [("bias", f"{triad}_bias_{a}", (k,)) for k, a in enumerate(AXES)]
        fields += [("scale_misalignment", f"{triad}_M_{i}{j}", (r, c))
                   for r, i in enumerate(AXES) for c, j in enumerate(AXES)]
        if triad == "gyro":
            fields += [("g_sensitivity", f"{triad}_G_{i}{j}", (r, c))
                       for r, i in enumerate(AXES) for c, j in enumerate(AXES)]
        for field, name, pos in fields:
            base = float(getattr(m, field)[pos])
            names.append(name)
            values.append(base)
            poly = dep.coefficients.get(field)
            rate = dep.rate_coefficients.get(field)
            coeffs = (base, *([] if poly is None else [float(c[pos]) for c in poly]))
            d = None if rate is None else float(rate[pos])
            h = legs.get(name)
            q = len(coeffs) + (d is not None) + (h is not None)
            records.append(ParameterTemperatureModel(
                name=name, reference_temperature_degc=T0, coefficients=coeffs,
                rate_coefficient=d, leg_coefficient=h, covariance=np.eye(q) * 1e-20, chi2=1.0,
                dof=4, order_criterion="fixed", temperature_range_degc=(-40.0, 85.0)))
    assert sorted(names) == sorted((*triad_parameter_names("accel", "triad"),
                                    *triad_parameter_names("gyro", "triad",
                                                           g_sensitivity=True)))
    return CalibrationResult(sensor_id="IMU-T", procedure="p2", model="triad",
                             param_names=tuple(names), values=np.array(values),
                             covariance=np.eye(len(names)) * 1e-20,
                             units=dict.fromkeys(names, "1"), temperature_models=tuple(records))


def sweep(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    temp = np.linspace(-40.0, 85.0, N)
    rate = rng.uniform(-0.05, 0.05, N)
    omega = rng.normal(size=(N, 3)) * 2.0
    force = rng.normal(size=(N, 3)) * 9.8
    return temp, rate, omega, force


def relative_error(got: np.ndarray, want: np.ndarray) -> float:
    return float(np.max(np.abs(got - want)) / np.max(np.abs(want)))


def test_correction_recovers_the_truth_over_minus40_to_85_degc():
    rng = np.random.default_rng(12)
    truth = truth_models(rng)
    temp, rate, omega, force = sweep(rng)
    accel_meas = apply_triad(truth["accel"], force, temperature_degc=temp,
                             temperature_rate_degc_ps=rate)
    gyro_meas = apply_triad(truth["gyro"], omega, specific_force_b_mps2=force,
                            temperature_degc=temp, temperature_rate_degc_ps=rate)
    res = CalibrationResult.from_json(result_of(truth).to_json())  # through the file format
    gyro, accel = correct_imu(gyro_meas, accel_meas, res, temperature_degc=temp,
                              temperature_rate_degc_ps=rate, leg=np.zeros(N))
    assert gyro is not None and accel is not None
    assert relative_error(accel, force) <= 1e-12
    assert relative_error(gyro, omega) <= 1e-12
    # the triad models the result gives are the truth's
    for triad in ("accel", "gyro"):
        assert res.triad_model(triad).isclose(truth[triad], atol=1e-18)  # type: ignore[arg-type]
    # ignoring the temperature is wrong by far more
    plain = CalibrationResult(sensor_id="IMU-T", procedure="p2", model="triad",
                              param_names=res.param_names, values=res.values,
                              covariance=res.covariance, units=res.units)
    _, wrong = correct_imu(gyro_meas, accel_meas, plain)
    assert wrong is not None and relative_error(wrong, force) > 1e-4


def test_the_leg_term_is_applied_by_the_leg_rule():
    rng = np.random.default_rng(3)
    truth = truth_models(rng)
    h = 5e-3
    res = result_of(truth, legs={"accel_bias_y": h})
    temp, rate, _, force = sweep(rng)
    rate[:10] = 0.0  # steady: the mean of both legs
    leg = temperature_leg(rate)
    measured = apply_triad(truth["accel"], force, temperature_degc=temp,
                           temperature_rate_degc_ps=rate)
    measured[:, 1] += h * leg
    _, accel = correct_imu(None, measured, res, temperature_degc=temp,
                           temperature_rate_degc_ps=rate)  # leg from the rule
    assert accel is not None and relative_error(accel, force) <= 1e-12
    _, no_leg = correct_imu(None, measured, res, temperature_degc=temp,
                            temperature_rate_degc_ps=rate, leg=0.0)
    assert no_leg is not None and relative_error(no_leg, force) > 1e-5
    with pytest.raises(InvalidInputError, match="`leg` must be -1, 0 or \\+1"):
        correct_imu(None, measured, res, temperature_degc=temp, leg=0.5)


def test_leg_rule():
    band = LEG_DEAD_BAND_DEGC_PS
    rate = [0.0, band, -band, 1.5 * band, -1.5 * band, 0.5, -0.5, 1e-4]
    np.testing.assert_array_equal(temperature_leg(rate), [0, 0, 0, 1, -1, 1, -1, 0])
    np.testing.assert_array_equal(temperature_leg(0.001, dead_band_degc_ps=0.0), [1.0])
    with pytest.raises(InvalidInputError, match="dead_band_degc_ps"):
        temperature_leg(0.1, dead_band_degc_ps=-1.0)
    with pytest.raises(InvalidInputError, match="finite"):
        temperature_leg([np.nan])


def test_temperature_rate_window_and_chunks():
    t = np.arange(0.0, 600.0, 0.1)
    rng = np.random.default_rng(5)
    temp = 20.0 + 0.01 * t + 0.3 * np.sin(t / 50.0) + rng.normal(size=t.size) * 0.002
    whole = TemperatureRate(window_s=60.0)(t, temp)
    est = TemperatureRate(window_s=60.0)
    cuts = np.sort(rng.choice(np.arange(1, t.size), 12, replace=False))
    parts = [est(a, b) for a, b in zip(np.split(t, cuts), np.split(temp, cuts), strict=True)]
    np.testing.assert_allclose(np.concatenate(parts), whole, rtol=0, atol=1e-10)
    assert np.all(whole[t < 30.0 - 1e-9] == 0.0)  # less than half a window: 0
    assert est._t.size <= 601  # bounded memory: one window of samples
    # a straight ramp is found exactly once the window is half full
    ramp = TemperatureRate(window_s=60.0)(t, 20.0 + 0.004 * t)
    np.testing.assert_allclose(ramp[t >= 30.0], 0.004, rtol=1e-9)
    # the lag of a trailing window is W/2: the slope of the sine term there
    slope = 0.01 + 0.3 / 50.0 * np.cos((t - 30.0) / 50.0)
    sel = t > 100.0
    assert np.max(np.abs(whole[sel] - slope[sel])) < 4e-4  # the window also averages the curvature
    with pytest.raises(InvalidInputError, match="must not decrease"):
        est(np.array([0.0]), np.array([20.0]))
    with pytest.raises(InvalidInputError, match="window_s"):
        TemperatureRate(window_s=0.0)


def frame(temp: np.ndarray, gyro: np.ndarray, accel: np.ndarray) -> pd.DataFrame:
    df = pd.DataFrame(np.c_[gyro, accel], columns=[*GYRO_COLUMNS, *ACCEL_COLUMNS],
                      index=pd.Index(np.arange(temp.size) * 0.01, name="time_s"))
    df["temperature_degc"] = temp
    return df


def test_frame_correction_uses_the_temperature_column_and_refuses_without_it():
    rng = np.random.default_rng(8)
    truth = truth_models(rng)
    res = result_of(truth)
    temp = np.full(300, 30.0)
    force = rng.normal(size=(300, 3)) * 9.8
    omega = rng.normal(size=(300, 3))
    accel = apply_triad(truth["accel"], force, temperature_degc=temp)
    gyro = apply_triad(truth["gyro"], omega, specific_force_b_mps2=force, temperature_degc=temp)
    out = correct_imu_frame(frame(temp, gyro, accel), res)
    assert relative_error(out[list(ACCEL_COLUMNS)].to_numpy(), force) <= 1e-12
    assert relative_error(out[list(GYRO_COLUMNS)].to_numpy(), omega) <= 1e-12
    np.testing.assert_array_equal(out["temperature_degc"], temp)
    with pytest.raises(InvalidInputError, match="no 'temperature_degc' column"):
        correct_imu_frame(frame(temp, gyro, accel).drop(columns="temperature_degc"), res)
    bad = temp.copy()
    bad[[5, 9]] = np.nan
    with pytest.raises(InvalidInputError, match=r"2 of 300 temperatures .*the first at row 5"):
        correct_imu_frame(frame(bad, gyro, accel), res)
    with pytest.raises(InvalidInputError, match="`temperature_degc` is required"):
        correct_imu(gyro, accel, res)
    with pytest.raises(InvalidInputError, match=r"`temperature_degc` must be a scalar or have "
                                                r"shape \(300,\)"):
        correct_imu(gyro, accel, res, temperature_degc=temp[:5])
    with pytest.raises(InvalidInputError, match="needs the accelerometer data"):
        correct_imu(gyro, None, res, temperature_degc=temp)


def test_a_per_axis_result_with_temperature_models():
    names = triad_parameter_names("accel", "per-axis")
    k0, b0 = np.array([1.01, 0.99, 1.002]), np.array([0.01, -0.02, 0.03])
    records = tuple(ParameterTemperatureModel(
        name=n, reference_temperature_degc=T0, coefficients=(v, c1, c2),
        covariance=np.zeros((3, 3)), chi2=0.0, dof=1, order_criterion="aicc")
        for n, v, c1, c2 in zip(names, [*k0, *b0], [1e-5, 2e-5, -1e-5, 1e-4, 0, -2e-4],
                                [1e-7, 0, 0, 1e-6, 1e-6, 0], strict=True))
    res = CalibrationResult(sensor_id="u", procedure="p2", model="per-axis",
                            param_names=names, values=np.r_[k0, b0],
                            covariance=np.zeros((6, 6)), units=dict.fromkeys(names, "1"),
                            temperature_models=records)
    temp = np.linspace(-40, 85, 50)
    x = np.random.default_rng(1).normal(size=(50, 3)) * 9.8
    values, _ = res.values_at(temp)
    y = values[:, :3] * (x + values[:, 3:])
    _, got = correct_imu(None, y, res, temperature_degc=temp)
    assert got is not None and relative_error(got, x) <= 1e-13
