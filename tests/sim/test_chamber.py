"""Tests of imucalib.sim.chamber: ramps and limits, exact thermal lags, self-heating, stability."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from imucalib.errors import InvalidInputError, LimitExceededError
from imucalib.sim.chamber import ChamberSpec, ImuThermalSpec, SimChamber, imu_temperature_degc

SEED = 20240611


def _program(chamber):
    chamber.command_setpoint(60.0, 100.0)
    chamber.command_setpoint(-10.0, 900.0, ramp_degc_ps=0.05)  # interrupts the first ramp's hold
    chamber.command_setpoint(25.0, 2500.0)


def test_setpoint_ramp_respects_the_limit():
    spec = ChamberSpec(max_ramp_degc_ps=5.0 / 60.0, air_time_constant_s=60.0)
    chamber = SimChamber(spec, initial_temp_degc=20.0)
    end = chamber.command_setpoint(60.0, 100.0)
    assert end == pytest.approx(100.0 + 40.0 / spec.max_ramp_degc_ps)
    t = np.linspace(0.0, 2000.0, 4001)
    setpoint = chamber.setpoint_degc(t)
    assert setpoint[0] == 20.0 and setpoint[-1] == 60.0
    assert np.abs(np.diff(setpoint) / np.diff(t)).max() <= spec.max_ramp_degc_ps * (1 + 1e-9)
    air = chamber.air_temperature_degc(t)
    assert np.abs(np.diff(air) / np.diff(t)).max() <= spec.max_ramp_degc_ps
    assert air[-1] == pytest.approx(60.0, abs=1e-6)


def test_imu_temperature_is_the_exact_solution_of_the_lags():
    spec = ChamberSpec(air_time_constant_s=90.0, max_ramp_degc_ps=0.2)
    thermal = ImuThermalSpec(time_constant_s=400.0, self_heating_degc=2.5)
    chamber = SimChamber(spec, initial_temp_degc=20.0)
    _program(chamber)
    t = np.linspace(0.0, 5000.0, 1001)
    temp, rate = imu_temperature_degc(chamber, thermal, t, power_on_time_s=300.0)

    def rhs(time, y):
        s = float(chamber.setpoint_degc(np.array([time]))[0])
        heat = thermal.self_heating_degc if time >= 300.0 else 0.0
        return [(s - y[0]) / spec.air_time_constant_s,
                (y[0] + heat - y[1]) / thermal.time_constant_s]

    sol = solve_ivp(rhs, (0.0, 5000.0), [20.0, 20.0], t_eval=t, rtol=1e-10, atol=1e-10,
                    max_step=5.0)
    np.testing.assert_allclose(temp, sol.y[1], atol=1e-6)
    np.testing.assert_allclose(chamber.air_temperature_degc(t), sol.y[0], atol=1e-6)
    h = 1e-3
    fd = (imu_temperature_degc(chamber, thermal, t[1:-1] + h, power_on_time_s=300.0)[0]
          - imu_temperature_degc(chamber, thermal, t[1:-1] - h, power_on_time_s=300.0)[0]) / (2 * h)
    smooth = np.abs(t[1:-1] - 300.0) > 2 * h  # dT/dt jumps by h/τ_i at power-on
    np.testing.assert_allclose(rate[1:-1][smooth], fd[smooth], atol=1e-7)
    assert rate[60] - rate[59] > 0.9 * thermal.self_heating_degc / thermal.time_constant_s


def test_equal_time_constants_branch():
    spec = ChamberSpec(air_time_constant_s=200.0)
    chamber = SimChamber(spec, initial_temp_degc=0.0)
    chamber.command_setpoint(10.0, 0.0)
    t = np.linspace(0.0, 3000.0, 31)
    same, _ = imu_temperature_degc(chamber, ImuThermalSpec(200.0), t)
    near, _ = imu_temperature_degc(chamber, ImuThermalSpec(200.0 * (1 + 1e-9)), t)
    np.testing.assert_allclose(same, near, atol=1e-7)


def test_first_order_lag_time_constant_and_self_heating():
    """Ambient air: after power-on the IMU warms by h·(1 − e^{−t/τ}) exactly."""
    thermal = ImuThermalSpec(time_constant_s=600.0, self_heating_degc=4.0)
    t = np.array([0.0, 100.0, 100.0 + 600.0, 100.0 + 1800.0, 1e6])
    temp, rate = imu_temperature_degc(23.0, thermal, t, power_on_time_s=100.0)
    np.testing.assert_allclose(temp, [23.0, 23.0, 23.0 + 4.0 * (1 - math.exp(-1.0)),
                                      23.0 + 4.0 * (1 - math.exp(-3.0)), 27.0], atol=1e-12)
    np.testing.assert_allclose(rate[1], 4.0 / 600.0, rtol=1e-12)
    # powered all along: steady at ambient + self-heating
    steady, steady_rate = imu_temperature_degc(23.0, thermal, t)
    np.testing.assert_allclose(steady, 27.0)
    np.testing.assert_allclose(steady_rate, 0.0)
    # in a chamber with a fast air loop, a setpoint step reaches 63 % after one IMU time constant
    spec = ChamberSpec(air_time_constant_s=1.0, max_ramp_degc_ps=100.0)
    chamber = SimChamber(spec, initial_temp_degc=20.0)
    chamber.command_setpoint(30.0, 0.0)
    temp, _ = imu_temperature_degc(chamber, ImuThermalSpec(600.0, 1.5), np.array([600.0, 1e5]))
    assert temp[0] - 21.5 == pytest.approx(10.0 * (1 - math.exp(-1.0)), rel=3e-3)
    assert temp[1] == pytest.approx(31.5, abs=1e-9)  # self-heating offset at steady state


def test_stability_fluctuation_is_consistent_and_filtered():
    spec = ChamberSpec(stability_noise_degc=0.1, air_time_constant_s=60.0)
    chamber = SimChamber(spec, initial_temp_degc=25.0, rng=SEED)
    t = np.linspace(0.0, 2e6, 200_001)
    air = chamber.air_temperature_degc(t)
    assert np.std(air) == pytest.approx(0.1, rel=0.05)
    np.testing.assert_array_equal(chamber.air_temperature_degc(t[:10]), air[:10])
    imu, _ = imu_temperature_degc(chamber, ImuThermalSpec(900.0), t)
    assert np.std(imu) < 0.8 * np.std(air)  # the IMU's lag attenuates the cycling
    fine = np.linspace(1000.0, 1010.0, 2001)
    imu, rate = imu_temperature_degc(chamber, ImuThermalSpec(900.0), fine)
    np.testing.assert_allclose(rate[1:-1], np.gradient(imu, fine)[1:-1], rtol=1e-6)


def test_bad_inputs():
    chamber = SimChamber(ChamberSpec(min_temp_degc=-40.0, max_temp_degc=85.0))
    with pytest.raises(LimitExceededError, match=r"150 °C is outside the range \[-40, 85\] °C"):
        chamber.command_setpoint(150.0, 0.0)
    with pytest.raises(LimitExceededError, match=r"ramp .* exceeds the limit"):
        chamber.command_setpoint(30.0, 0.0, ramp_degc_ps=1.0)
    chamber.command_setpoint(30.0, 100.0)
    with pytest.raises(InvalidInputError, match=r"non-decreasing time.*at_time_s=50"):
        chamber.command_setpoint(20.0, 50.0)
    with pytest.raises(InvalidInputError, match="`temp_degc` must be finite"):
        chamber.command_setpoint(float("nan"), 200.0)
    with pytest.raises(LimitExceededError, match="`initial_temp_degc` -100 °C is outside"):
        SimChamber(ChamberSpec(), initial_temp_degc=-100.0)
    with pytest.raises(InvalidInputError, match="`time_constant_s` must be > 0"):
        ImuThermalSpec(time_constant_s=0.0)
    with pytest.raises(InvalidInputError, match="`min_temp_degc` must be below"):
        ChamberSpec(min_temp_degc=50.0, max_temp_degc=10.0)
