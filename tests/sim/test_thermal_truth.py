"""The twin's temperature-dependent truth: hysteresis state across chunks, build, end to end."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from pydantic import ValidationError

from imucalib.models.earth import Site
from imucalib.models.imu import ImuModel, sample_imu_model
from imucalib.models.noise import NoiseModel
from imucalib.models.temperature import hysteresis_state
from imucalib.models.triad import apply_triad
from imucalib.plan.equipment import ImuConfig, TwinEquipment
from imucalib.sim.build import build_rig
from imucalib.sim.chamber import ChamberSpec, ImuThermalSpec, SimChamber
from imucalib.sim.fixture import single_imu_fixture
from imucalib.sim.kinematics import compute_imu_kinematics, stationary_platform_motion
from imucalib.sim.rig import TwinRig
from imucalib.sim.synth import ImuSynthesizer, SimImu

SITE = Site(latitude_deg=48.0)
FIXTURE = single_imu_fixture(name="u")


def _kinematics(t: np.ndarray):
    return compute_imu_kinematics(stationary_platform_motion(t), SITE, FIXTURE.mounts[0])


def _temperature(t: np.ndarray):
    temp = 25.0 + 30.0 * np.sin(t / 20.0) + 0.3 * np.sin(7.0 * t)
    return temp, 1.5 * np.cos(t / 20.0) + 2.1 * np.cos(7.0 * t)


def _noise_free(grade: str, seed: int) -> ImuModel:
    drawn = sample_imu_model(grade, seed, sample_rate_hz=100.0,
                             temperature_dependence="typical", hysteresis_fraction=0.5)
    return ImuModel(gyro=drawn.gyro, accel=drawn.accel, sample_rate_hz=100.0)


def test_synthesis_does_not_depend_on_the_chunking():
    model = _noise_free("tactical", 4)
    whole = ImuSynthesizer(SimImu("u", model, mount=FIXTURE.mounts[0]), rng=1)
    one = whole.synthesize(300.0, _kinematics, _temperature)
    chunked = ImuSynthesizer(SimImu("u", model, mount=FIXTURE.mounts[0]), rng=1)
    ends = np.cumsum(np.random.default_rng(3).uniform(0.0, 9.0, 80))
    parts = [chunked.synthesize(t, _kinematics, _temperature) for t in ends[ends < 300.0]]
    parts.append(chunked.synthesize(300.0, _kinematics, _temperature))
    for field in ("accel_mps2", "gyro_rps"):
        got = np.concatenate([getattr(p, field) for p in parts])
        np.testing.assert_allclose(got, getattr(one, field), rtol=1e-13, atol=1e-16)
    assert set(whole.hysteresis_states) == {"gyro", "accel"}
    for kind, state in whole.hysteresis_states.items():
        assert chunked.hysteresis_states[kind] == pytest.approx(state, abs=1e-13)
    # and the state is the one of the whole true-temperature history, from 0
    states, final = hysteresis_state(one.true_temperature_degc, 0.0, 5.0)
    assert whole.hysteresis_states["accel"] == pytest.approx(final, abs=1e-13)
    want = apply_triad(model.accel, one.true_specific_force_b_mps2,
                       rate_b_rps=one.true_rate_b_rps,
                       angular_accel_b_rps2=np.zeros_like(one.true_rate_b_rps),
                       temperature_degc=one.true_temperature_degc,
                       temperature_rate_degc_ps=_temperature(one.true_time_s)[1],
                       hysteresis_state=states)
    np.testing.assert_allclose(one.accel_mps2, want, rtol=0, atol=1e-12)


def test_build_rig_draws_and_records_the_thermal_truth():
    eq = TwinEquipment(seed=3, imus=(ImuConfig(name="u", temperature_dependence="typical",
                                               hysteresis_fraction=0.25,
                                               reference_temperature_degc=20.0),))
    built = build_rig(eq)
    model = built.imu_models["u"]
    assert model.accel.temperature is not None
    assert model.accel.temperature.reference_temperature_degc == 20.0
    assert model.gyro.temperature is not None and model.gyro.temperature.has_hysteresis
    back = ImuModel.from_dict(json.loads(json.dumps(built.truth["imu_models"]))["u"])
    assert back.to_dict() == model.to_dict()
    plain = build_rig(TwinEquipment(seed=3, imus=(ImuConfig(name="u"),))).imu_models["u"]
    assert plain.accel.temperature is None
    assert plain.accel.bias.tolist() == model.accel.bias.tolist()  # same base draws
    with pytest.raises(ValidationError, match="typical"):
        ImuConfig(name="u", hysteresis_fraction=0.1)
    with pytest.raises(ValidationError, match="hysteresis_fraction"):
        ImuConfig(name="u", temperature_dependence="typical", hysteresis_fraction=0.7)


def _window(samples, t0: float, t1: float):
    t = np.concatenate([s.true_time_s for s in samples])
    keep = (t >= t0) & (t < t1)
    accel = np.concatenate([s.accel_mps2 for s in samples])[keep]
    temp = np.concatenate([s.true_temperature_degc for s in samples])[keep]
    force = np.concatenate([s.true_specific_force_b_mps2 for s in samples])[keep]
    return accel, temp, force


def test_static_accelerometer_follows_the_cubic_and_its_hysteresis_in_a_chamber():
    drawn = sample_imu_model("tactical", 21, sample_rate_hz=50.0, nonlinear=False,
                             temperature_dependence="typical", hysteresis_fraction=0.5)
    # white noise only (no bias instability), so that a window's mean has a known spread
    model = dataclasses.replace(
        drawn, gyro_noise=NoiseModel(white_density=drawn.gyro_noise.white_density),
        accel_noise=NoiseModel(white_density=drawn.accel_noise.white_density))
    chamber = SimChamber(ChamberSpec(max_ramp_degc_ps=1.0, air_time_constant_s=5.0), 25.0)
    rig = TwinRig(site=SITE, fixture=FIXTURE,
                  imus=[SimImu("u", model, thermal=ImuThermalSpec(5.0))], chamber=chamber,
                  rng=5)
    # cool to 0 °C, heat to 40 °C (heating approach), 70 °C, back to 40 °C (cooling approach)
    commands = {0.0: 0.0, 100.0: 40.0, 300.0: 70.0, 500.0: 40.0}
    samples = []
    for t_end in np.arange(10.0, 701.0, 10.0):
        start = t_end - 10.0
        if start in commands:
            chamber.command_setpoint(commands[start], start)
        samples.append(rig.generate(float(t_end)).imu["u"])
    all_temp = np.concatenate([s.true_temperature_degc for s in samples])
    states, _ = hysteresis_state(all_temp, 0.0, 5.0)
    all_t = np.concatenate([s.true_time_s for s in samples])

    def reading(t0: float, t1: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        accel, temp, force = _window(samples, t0, t1)
        s = states[(all_t >= t0) & (all_t < t1)]
        assert np.ptp(temp) < 0.01 and np.ptp(s) < 1e-6  # soaked: T and s constant
        p = model.parameters_at(float(temp.mean()), float(s.mean()))
        bias = np.array([p[f"accel_bias_{a}"] for a in "xyz"])
        mat = np.array([[p[f"accel_M_{a}{b}"] for b in "xyz"] for a in "xyz"])
        want = bias + (np.eye(3) + mat) @ force.mean(axis=0)
        sigma = accel.std(axis=0) / np.sqrt(accel.shape[0])
        return accel.mean(axis=0), want, sigma

    hot40, want40, sig40 = reading(250.0, 300.0)
    hot70, want70, sig70 = reading(450.0, 500.0)
    cold40, wantc40, sigc40 = reading(650.0, 700.0)
    for got, want, sig in ((hot40, want40, sig40), (hot70, want70, sig70),
                           (cold40, wantc40, sigc40)):
        np.testing.assert_array_less(np.abs(got - want), 6.0 * sig)
    # the reading moved with the cubic between the two soaks, well beyond the noise
    assert np.max(np.abs(want70 - want40)) > 20.0 * sig40.max()
    # heating vs cooling approach at 40 °C: ≈ 2h (bias and M terms), far beyond the noise
    h = model.parameters_at(40.0, 1.0)
    c = model.parameters_at(40.0, -1.0)
    _, _, force = _window(samples, 250.0, 300.0)
    g = force.mean(axis=0)
    two_h = np.array([h[f"accel_bias_{a}"] - c[f"accel_bias_{a}"]
                      + sum((h[f"accel_M_{a}{b}"] - c[f"accel_M_{a}{b}"]) * g[j]
                            for j, b in enumerate("xyz")) for a in "xyz"])
    assert np.all(np.abs(two_h) > 20.0 * sig40)
    np.testing.assert_allclose(hot40 - cold40, two_h, rtol=0.02,
                               atol=float(6.0 * np.hypot(sig40, sigc40).max()))
