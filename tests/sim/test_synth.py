"""IMU synthesis at its own clock: timing, counter, drops, jitter, chunking, output."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib import units
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.earth import Site
from imucalib.models.imu import ImuModel, sample_imu_model
from imucalib.models.triad import apply_triad
from imucalib.sim.chamber import ImuThermalSpec
from imucalib.sim.fixture import single_imu_fixture
from imucalib.sim.kinematics import compute_imu_kinematics, stationary_platform_motion
from imucalib.sim.synth import ClockSpec, ImuSynthesizer, SimImu

SITE = Site(latitude_deg=48.0)
FIXTURE = single_imu_fixture(name="u1")


def kinematics(t: np.ndarray):
    return compute_imu_kinematics(stationary_platform_motion(t), SITE, FIXTURE.mounts[0])


def constant_temperature(t: np.ndarray):
    return np.full(t.shape, 25.0), np.zeros(t.shape)


def make(model: ImuModel | None = None, **clock) -> ImuSynthesizer:
    imu = SimImu("u1", model or ImuModel.ideal(1000.0), ClockSpec(**clock),
                 mount=FIXTURE.mounts[0])
    return ImuSynthesizer(imu, rng=7)


def test_sample_times_follow_the_drifting_oscillator():
    synth = make(drift_ppm=250.0, phase_s=3e-4)
    s = synth.synthesize(10.0, kinematics, constant_temperature)
    period = 1.0 / (1000.0 * (1 + 250e-6))
    n_expected = math.ceil((10.0 - 3e-4) / period)
    assert len(s) == n_expected
    np.testing.assert_allclose(s.true_time_s, 3e-4 + np.arange(len(s)) * period, rtol=0,
                               atol=1e-12)
    np.testing.assert_array_equal(s.counter, np.arange(len(s)))
    np.testing.assert_allclose(s.device_time_s, np.arange(len(s)) / 1000.0, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(s.time_s, s.true_time_s)  # no latency, no jitter


def test_latency_and_jitter_and_monotonic_receive_times():
    synth = make(latency_s=2e-3, jitter_s=1e-4)
    s = synth.synthesize(20.0, kinematics, constant_temperature)
    delay = s.time_s - s.true_time_s
    assert np.all(np.diff(s.time_s) >= 0.0)
    assert delay.mean() == pytest.approx(2e-3, abs=5e-6)
    assert delay.std() == pytest.approx(1e-4, rel=0.05)


def test_dropped_samples_leave_counter_gaps():
    synth = make(drop_probability=0.02)
    s = synth.synthesize(50.0, kinematics, constant_temperature)
    n_total = 50_000
    missing = n_total - len(s)
    assert missing == pytest.approx(0.02 * n_total, abs=5 * math.sqrt(0.02 * n_total))
    jumps = np.diff(s.counter)
    assert int(np.sum(jumps - 1)) + int(s.counter[0]) + (n_total - 1 - int(s.counter[-1])) \
        == missing


def test_counter_wraps_at_its_width():
    synth = make(counter_bits=8)
    s = synth.synthesize(1.0, kinematics, constant_temperature)
    assert s.counter.max() == 255
    np.testing.assert_array_equal(s.counter, np.arange(len(s)) % 256)


@pytest.mark.parametrize("cuts", [[0.5, 1.0, 3.0], [0.0011, 2.2, 2.2004, 3.7]])
def test_chunked_synthesis_equals_one_shot(cuts):
    model = sample_imu_model("consumer", rng=3)
    one = make(model, jitter_s=1e-4, drop_probability=0.01)
    whole = one.synthesize(4.0, kinematics, constant_temperature)
    parts = make(model, jitter_s=1e-4, drop_probability=0.01)
    pieces = [parts.synthesize(t, kinematics, constant_temperature) for t in [*cuts, 4.0]]
    for name in ("time_s", "counter", "gyro_rps", "accel_mps2", "true_time_s"):
        joined = np.concatenate([getattr(p, name) for p in pieces])
        np.testing.assert_array_equal(joined, getattr(whole, name), err_msg=name)


def test_noise_free_output_is_the_error_model_of_the_true_input():
    model = sample_imu_model("tactical", rng=5)
    ideal_noise = ImuModel(gyro=model.gyro, accel=model.accel, sample_rate_hz=1000.0)
    s = make(ideal_noise).synthesize(0.5, kinematics, constant_temperature)
    kin = kinematics(s.true_time_s)
    np.testing.assert_allclose(
        s.gyro_rps, apply_triad(model.gyro, kin.rate_b_rps,
                                specific_force_b_mps2=kin.specific_force_b_mps2),
        rtol=1e-14, atol=1e-18)
    np.testing.assert_allclose(
        s.accel_mps2, apply_triad(model.accel, kin.specific_force_b_mps2,
                                  rate_b_rps=kin.rate_b_rps,
                                  angular_accel_b_rps2=kin.angular_accel_b_rps2),
        rtol=1e-14, atol=1e-15)


def test_constant_input_shortcut_equals_the_full_evaluation():
    """The synthesizer evaluates one row for inputs flagged constant; the result is the same."""
    model = sample_imu_model("consumer", rng=9)
    model = ImuModel(gyro=model.gyro, accel=model.accel, sample_rate_hz=500.0)

    def flagged(t):
        return kinematics(t[:1]).repeat(t.shape[0], time_s=t)

    fast = make(model).synthesize(2.0, flagged, constant_temperature)
    slow = make(model).synthesize(2.0, kinematics, constant_temperature)
    np.testing.assert_allclose(fast.gyro_rps, slow.gyro_rps, rtol=1e-14, atol=1e-18)
    np.testing.assert_allclose(fast.accel_mps2, slow.accel_mps2, rtol=1e-14, atol=1e-14)


def test_temperature_sensor_resolution():
    imu = SimImu("u1", ImuModel.ideal(100.0), mount=FIXTURE.mounts[0],
                 temperature_resolution_degc=0.25, thermal=ImuThermalSpec(600.0, 0.0))
    s = ImuSynthesizer(imu, rng=1).synthesize(
        1.0, kinematics, lambda t: (np.full(t.shape, 25.13), np.zeros(t.shape)))
    np.testing.assert_array_equal(s.temperature_degc, 25.25)
    np.testing.assert_array_equal(s.true_temperature_degc, 25.13)


def test_saturation_is_flagged():
    model = sample_imu_model("consumer", rng=1)
    spin = 3000.0 * units.DEG  # above the consumer range of 2000 °/s

    def spinning(t):
        kin = kinematics(t)
        rate = kin.rate_b_rps.copy()
        rate[:, 2] = spin
        return type(kin)(t, rate, kin.specific_force_b_mps2, kin.angular_accel_b_rps2,
                         kin.rot_tb)

    s = make(model).synthesize(0.1, spinning, constant_temperature)
    assert s.saturated.all()
    assert np.abs(s.gyro_rps[:, 2]).max() <= model.gyro_output.range


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"drift_ppm": math.nan}, "drift_ppm"),
    ({"jitter_s": -1e-3}, "jitter_s"),
    ({"drop_probability": 1.0}, r"drop_probability.*\[0, 1\)"),
    ({"counter_bits": 4}, "counter_bits"),
])
def test_bad_clock_specs(kwargs, match):
    with pytest.raises(InvalidInputError, match=match):
        ClockSpec(**kwargs)


def test_empty_name_is_refused():
    with pytest.raises(ConfigurationError, match="name"):
        SimImu(" ", ImuModel.ideal())
