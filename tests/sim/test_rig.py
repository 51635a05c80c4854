"""The twin rig: closed loop of the static outputs, the configured noise, shortcuts, streams."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from imucalib import units
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.models.earth import Site
from imucalib.models.imu import ImuModel, sample_imu_model
from imucalib.models.noise import NoiseModel, compute_theoretical_adev
from imucalib.models.triad import TriadModel
from imucalib.sim.chamber import ChamberSpec, ImuThermalSpec, SimChamber, imu_temperature_degc
from imucalib.sim.fixture import hexahedral_fixture, single_imu_fixture
from imucalib.sim.kinematics import compute_imu_kinematics
from imucalib.sim.rig import TwinRig, feedback_grid_s
from imucalib.sim.synth import SimImu
from imucalib.sim.table import RateTableSpec, SimRateTable

SITE = Site(latitude_deg=37.5, heading_deg=30.0)


def oadev(y: np.ndarray, dt: float, m: int) -> np.ndarray:
    theta = np.concatenate([np.zeros((1, y.shape[1])), np.cumsum(y, axis=0) * dt])
    d = theta[2 * m:] - 2 * theta[m:-m] + theta[: -2 * m]
    return np.sqrt(np.mean(d**2, axis=0) / (2 * (m * dt) ** 2))


def linear_model(seed: int) -> ImuModel:
    """Bias and full scale/misalignment only, white noise only (its SE is N/√T exactly)."""
    truth = sample_imu_model("tactical", rng=seed)
    gyro = TriadModel(kind="gyro", bias=truth.gyro.bias,
                      scale_misalignment=truth.gyro.scale_misalignment)
    accel = TriadModel(kind="accel", bias=truth.accel.bias,
                       scale_misalignment=truth.accel.scale_misalignment)
    return ImuModel(gyro=gyro, accel=accel,
                    gyro_noise=NoiseModel(white_density=truth.gyro_noise.white_density),
                    accel_noise=NoiseModel(white_density=truth.accel_noise.white_density),
                    gyro_output=truth.gyro_output, accel_output=truth.accel_output,
                    sample_rate_hz=1000.0)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_static_means_are_bias_plus_scale_times_the_projections(seed):
    """Averaged static outputs = b + (I + M)·(Earth rate | gravity) within their standard error."""
    model = linear_model(seed)
    rot_mb = Rotation.from_euler("xyz", [90.0, 0.0, 30.0], degrees=True)  # an upright mount
    fixture = single_imu_fixture(rot_mb=rot_mb, name="u")
    rig = TwinRig(site=SITE, fixture=fixture, imus=[SimImu("u", model)], rng=seed)
    duration_s = 120.0
    chunk = rig.generate(duration_s)
    s = chunk.imu["u"]
    # projections by hand: z_t up, Earth rate in t from the site, into b through rot_mb
    earth_b = rot_mb.inv().apply(SITE.earth_rate_t_rps)
    force_b = rot_mb.inv().apply([0.0, 0.0, SITE.local_gravity_mps2])
    eye = np.eye(3)
    expected_gyro = model.gyro.bias + (eye + model.gyro.scale_misalignment) @ earth_b
    expected_accel = model.accel.bias + (eye + model.accel.scale_misalignment) @ force_b
    se_gyro = model.gyro_noise.white_density / math.sqrt(duration_s)
    se_accel = model.accel_noise.white_density / math.sqrt(duration_s)
    z_gyro = (s.gyro_rps.mean(axis=0) - expected_gyro) / se_gyro
    z_accel = (s.accel_mps2.mean(axis=0) - expected_accel) / se_accel
    assert np.all(np.abs(z_gyro) < 4.0), z_gyro
    assert np.all(np.abs(z_accel) < 4.0), z_accel


def test_allan_deviation_at_one_second_is_the_configured_noise():
    """Static twin data carries the grade's full noise model: OADEV(1 s) matches its theory."""
    model = sample_imu_model("tactical", rng=4)
    rig = TwinRig(site=SITE, fixture=single_imu_fixture(name="u"), imus=[SimImu("u", model)],
                  rng=4)
    s = rig.generate(900.0).imu["u"]
    dt = 1.0 / model.sample_rate_hz
    n, m = len(s), 1000
    edf = (3 * n / (2 * m) - 2 * (n - 1) / (n + 1)) * 4 * m**2 / (4 * m**2 + 5)  # SP 1065 white FM
    tol = 4.0 / math.sqrt(2.0 * edf)
    for measured, noise in ((s.gyro_rps, model.gyro_noise), (s.accel_mps2, model.accel_noise)):
        expected = compute_theoretical_adev(noise, np.array([1.0]))[0]
        ratio = oadev(measured - measured.mean(axis=0), dt, m) / expected
        assert np.all(np.abs(ratio - 1.0) < tol), ratio
    # and the white-noise coefficient alone is within the same band (it dominates at 1 s)
    white = model.gyro_noise.white_density
    assert np.all(np.abs(oadev(s.gyro_rps, dt, m) / white - 1.0) < tol + 0.02)


def test_rest_shortcut_equals_the_full_kinematics():
    """A table holding still gives every sample the first sample's inputs, exactly as computed."""
    spec = RateTableSpec.dual_axis_pitch_roll("high")
    table = SimRateTable(spec, rng=1)
    t_end = table.command_position(0, 0.7, 0.0)
    table.command_position(1, -1.2, 0.0)
    fixture = hexahedral_fixture(0.05, ["a", "b"])
    model = ImuModel.ideal(200.0)
    rig = TwinRig(site=SITE, fixture=fixture, imus=[SimImu("a", model), SimImu("b", model)],
                  table=table)
    t = np.linspace(t_end + 60.0, t_end + 70.0, 500)
    fast = rig.imu_kinematics("b", t)
    assert fast.constant
    full = compute_imu_kinematics(table.motion(t), SITE, fixture.mount("b"), fixture.rot_pm)
    for name in ("rate_b_rps", "specific_force_b_mps2", "angular_accel_b_rps2"):
        np.testing.assert_allclose(getattr(fast, name), getattr(full, name), rtol=0,
                                   atol=1e-15 * 10.0, err_msg=name)
    moving = rig.imu_kinematics("b", np.linspace(0.0, 0.5, 50))  # during the move
    assert not moving.constant


def test_still_air_shortcut_equals_the_thermal_model():
    thermal = ImuThermalSpec(300.0, 2.5)
    rig = TwinRig(site=SITE, fixture=single_imu_fixture(name="u"),
                  imus=[SimImu("u", ImuModel.ideal(), thermal=thermal)],
                  ambient_temperature_degc=21.0)
    t = np.linspace(0.0, 5000.0, 7)
    temp, rate = rig.imu_temperature("u", t)
    ref_temp, ref_rate = imu_temperature_degc(21.0, thermal, t)
    np.testing.assert_allclose(temp, ref_temp, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rate, ref_rate, rtol=0, atol=1e-15)


def test_streams_share_grids_across_chunks():
    table = SimRateTable(RateTableSpec.single_axis("lab"), rng=2)
    table.command_rate(0, 30.0 * units.DEG, 0.0)
    chamber = SimChamber(ChamberSpec(), 25.0)
    chamber.command_setpoint(40.0, 0.0)
    rig = TwinRig(site=SITE, fixture=single_imu_fixture(name="u"),
                  imus=[SimImu("u", ImuModel.ideal(250.0))], table=table, chamber=chamber,
                  feedback_rate_hz=50.0, chamber_rate_hz=2.0)
    chunks = [rig.generate(t) for t in (0.73, 0.73, 1.9, 4.0)]
    fb_t = np.concatenate([c.table.time_s for c in chunks if c.table is not None])
    np.testing.assert_allclose(fb_t, np.arange(200) / 50.0, rtol=0, atol=1e-12)
    ch_t = np.concatenate([c.chamber.time_s for c in chunks if c.chamber is not None])
    np.testing.assert_allclose(ch_t, np.arange(8) / 2.0, rtol=0, atol=1e-12)
    assert sum(len(c.imu["u"]) for c in chunks) == 1000
    assert rig.now_s == 4.0
    assert chunks[1].imu["u"].time_s.size == 0  # an empty span yields nothing


def test_feedback_grid_edges():
    np.testing.assert_allclose(feedback_grid_s(0.0, 0.05, 100.0), [0.0, 0.01, 0.02, 0.03, 0.04])
    assert feedback_grid_s(0.1, 0.1, 100.0).size == 0


def test_bad_rigs():
    model = ImuModel.ideal()
    fixture = single_imu_fixture(name="u")
    with pytest.raises(ConfigurationError, match=r"no mount on the fixture.*\['u'\]"):
        TwinRig(site=SITE, fixture=fixture, imus=[SimImu("v", model)])
    with pytest.raises(ConfigurationError, match="at least one IMU"):
        TwinRig(site=SITE, fixture=fixture, imus=[])
    rig = TwinRig(site=SITE, fixture=fixture, imus=[SimImu("u", model)])
    rig.generate(1.0)
    with pytest.raises(InvalidInputError, match="before the rig's current time 1 s"):
        rig.generate(0.5)
    with pytest.raises(InvalidInputError, match="no IMU named 'x'"):
        rig.generate_imu("x", 2.0)
    with pytest.raises(InvalidInputError, match="t_end_s"):
        rig.generate(math.nan)
