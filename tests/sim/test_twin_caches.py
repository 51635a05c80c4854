"""The twin's per-command caches give exactly what a fresh evaluation gives.

The chamber caches its cascade's piece states (:func:`imucalib.sim.chamber._cascade`) and the
lagged fluctuation's constants; a table axis caches its servo terms
(:meth:`imucalib.sim._servo.AxisProfile.servo_terms`). A command changes the history they are
made from: every evaluation after it must equal (bit for bit) that of a twin that received the
same commands and was never evaluated before.
"""

from __future__ import annotations

import numpy as np

from imucalib.sim.chamber import ChamberSpec, ImuThermalSpec, SimChamber, imu_temperature_degc
from imucalib.sim.table import RateTableSpec, SimRateTable

SPEC = ChamberSpec(max_ramp_degc_ps=0.5, air_time_constant_s=30.0, stability_noise_degc=0.05)
THERMAL = ImuThermalSpec(time_constant_s=90.0, self_heating_degc=2.0)
COMMANDS = ((0.0, 60.0), (150.0, -20.0), (400.0, 25.0))  # (at [s], setpoint [°C])


def _chamber_after(n_commands: int) -> SimChamber:
    chamber = SimChamber(SPEC, initial_temp_degc=20.0, rng=5)
    for at_s, temp in COMMANDS[:n_commands]:
        chamber.command_setpoint(temp, at_time_s=at_s)
    return chamber


def test_chamber_evaluations_after_each_command_equal_a_fresh_chamber():
    t = np.linspace(0.0, 900.0, 1801)
    used = SimChamber(SPEC, initial_temp_degc=20.0, rng=5)
    for n, (at_s, temp) in enumerate(COMMANDS, start=1):
        before = imu_temperature_degc(used, THERMAL, t, power_on_time_s=50.0)
        used.command_setpoint(temp, at_time_s=at_s)
        fresh = _chamber_after(n)
        for got, want in zip(
                (*imu_temperature_degc(used, THERMAL, t, power_on_time_s=50.0),
                 used.air_temperature_degc(t)),
                (*imu_temperature_degc(fresh, THERMAL, t, power_on_time_s=50.0),
                 fresh.air_temperature_degc(t)), strict=True):
            np.testing.assert_array_equal(got, want)
        assert not np.array_equal(before[0], imu_temperature_degc(used, THERMAL, t,
                                                                  power_on_time_s=50.0)[0])


def test_chamber_chunks_equal_one_evaluation():
    chamber = _chamber_after(len(COMMANDS))
    t = np.linspace(0.0, 900.0, 1801)
    whole, whole_rate = imu_temperature_degc(chamber, THERMAL, t)
    parts = [imu_temperature_degc(chamber, THERMAL, chunk) for chunk in np.array_split(t, 37)]
    np.testing.assert_array_equal(np.concatenate([p[0] for p in parts]), whole)
    np.testing.assert_array_equal(np.concatenate([p[1] for p in parts]), whole_rate)


def test_table_motion_after_each_command_equals_a_fresh_table():
    spec = RateTableSpec.dual_axis_pitch_roll("lab")
    commands = ((0, "position", 0.4, 0.0), (1, "rate", 1.0, 5.0), (1, "rate", -0.5, 30.0))

    def issue(table: SimRateTable, cmd: tuple[int, str, float, float]) -> None:
        axis, kind, value, at_s = cmd
        if kind == "position":
            table.command_position(axis, value, at_s)
        else:
            table.command_rate(axis, value, at_s)

    t = np.linspace(0.0, 60.0, 6001)
    used = SimRateTable(spec, rng=2)
    for n, cmd in enumerate(commands, start=1):
        used.motion(t)
        issue(used, cmd)
        fresh = SimRateTable(spec, rng=2)
        for c in commands[:n]:
            issue(fresh, c)
        got, want = used.motion(t), fresh.motion(t)
        np.testing.assert_array_equal(got.angle_rad, want.angle_rad)
        np.testing.assert_array_equal(got.rate_rps, want.rate_rps)
        np.testing.assert_array_equal(got.accel_rps2, want.accel_rps2)
