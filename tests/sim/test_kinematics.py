"""Tests of imucalib.sim.kinematics: centripetal, tangential and Coriolis terms, and an inertial
finite-difference check of the whole chain (table imperfections, mount rotation, lever arm)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from imucalib.errors import InvalidInputError
from imucalib.models.earth import Site
from imucalib.sim.fixture import MountedImu, hexahedral_fixture
from imucalib.sim.kinematics import (
    compute_fixture_kinematics,
    compute_imu_kinematics,
    stationary_platform_motion,
)
from imucalib.sim.table import RateTableSpec, SimRateTable
from imucalib.units import DEG, EARTH_RATE_RPS

SEED = 20240611


def _spinning_table(rate_rps, grade="ideal"):
    table = SimRateTable(RateTableSpec.single_axis(grade))
    table.command_rate(0, rate_rps, 0.0)
    return table


@pytest.mark.parametrize("rate_dps", [30.0, -100.0, 360.0])
@pytest.mark.parametrize("radius_m", [0.05, 0.3])
def test_centripetal_specific_force_at_the_pole(rate_dps, radius_m):
    """At the pole Ω = Ω_U ẑ exactly, so f_p = [−ω(ω + 2Ω)r, 0, g] at every instant."""
    w = rate_dps * DEG
    table = _spinning_table(w)
    site = Site(latitude_deg=90.0)
    t = np.linspace(5.0, 5.0 + 4 * np.pi / abs(w), 400)
    kin = compute_imu_kinematics(table.motion(t), site, MountedImu("u", Rotation.identity(),
                                                                   np.array([radius_m, 0, 0])))
    g = site.local_gravity_mps2
    expected = np.array([-w * (w + 2 * EARTH_RATE_RPS) * radius_m, 0.0, g])
    np.testing.assert_allclose(kin.specific_force_b_mps2, np.tile(expected, (t.size, 1)),
                               rtol=0, atol=1e-12 * max(g, w * w * radius_m))
    assert kin.specific_force_b_mps2[0, 0] < 0  # points to the axis (−x_p from a mount at +x_p)
    np.testing.assert_allclose(kin.rate_b_rps[:, 2], w + EARTH_RATE_RPS, rtol=1e-14)


def test_centripetal_mean_over_revolutions_at_mid_latitude():
    w, r = 200 * DEG, 0.25
    table = _spinning_table(w)
    site = Site(latitude_deg=45.0, heading_deg=30.0)
    omega_u = EARTH_RATE_RPS * np.sin(np.radians(45.0))
    n = 4000
    t = 10.0 + np.arange(n) * (2 * (2 * np.pi / w) / n)  # two whole revolutions
    # IMU turned 180° about z: its x axis points inward (towards the spin axis) and reads +ω²r
    mount = MountedImu("u", Rotation.from_euler("z", 180, degrees=True), np.array([r, 0, 0]))
    kin = compute_imu_kinematics(table.motion(t), site, mount)
    mean = kin.specific_force_b_mps2.mean(axis=0)
    assert mean[0] == pytest.approx(w * (w + 2 * omega_u) * r, rel=1e-12)
    assert mean[1] == pytest.approx(0.0, abs=1e-12)
    assert mean[2] == pytest.approx(site.local_gravity_mps2, rel=1e-14)
    # horizontal Earth rate: once per revolution on the radial gyro, zero mean
    assert np.ptp(kin.rate_b_rps[:, 0]) == pytest.approx(
        2 * EARTH_RATE_RPS * np.cos(np.radians(45.0)), rel=1e-3)
    assert kin.rate_b_rps[:, 0].mean() == pytest.approx(0.0, abs=1e-15)


def test_tangential_term_during_spin_up():
    w, r = 90 * DEG, 0.2
    table = SimRateTable(RateTableSpec.single_axis("lab", non_orthogonality_rad=0.0,
                                                   wobble_rad=0.0))
    table.command_rate(0, w, 0.0)
    t = np.linspace(0.0, table.settled_after_s(0, 1.0, 1e-3), 500)
    motion = table.motion(t)
    kin = compute_imu_kinematics(motion, Site(latitude_deg=90.0),
                                 MountedImu("u", Rotation.identity(), np.array([r, 0, 0])))
    alpha = motion.accel_rps2[:, 0]
    assert alpha.max() > 0.9 * table.spec.axes[0].reference_accel_rps2
    # α × r = α ẑ × r x̂ = α r ŷ; Coriolis at the pole is radial only
    np.testing.assert_allclose(kin.specific_force_b_mps2[:, 1], alpha * r, atol=1e-12)
    np.testing.assert_allclose(kin.angular_accel_b_rps2[:, 2], alpha, atol=1e-12)


@pytest.mark.parametrize("seed", [SEED, SEED + 7])
def test_inertial_finite_difference_check(seed):
    """f and ω_ib from differentiating the IMU's path in a frame turning with the Earth."""
    rng = np.random.default_rng(seed)
    spec = RateTableSpec.dual_axis_pitch_roll("lab", wobble_rad=0.01, non_orthogonality_rad=0.02)
    table = SimRateTable(spec)
    table.command_rate("pitch", 1.5, 0.0)
    table.command_rate("roll", -2.5, 0.3)
    table.command_position("pitch", 2.0, 2.0)
    site = Site(latitude_deg=rng.uniform(-80, 80), heading_deg=rng.uniform(0, 360))
    mount = MountedImu("u", Rotation.random(random_state=seed), rng.uniform(-0.3, 0.3, 3))
    rot_pm = Rotation.from_rotvec(rng.normal(0, 0.01, 3))
    t = np.linspace(2.2, 4.0, 97)
    kin = compute_imu_kinematics(table.motion(t), site, mount, rot_pm)

    omega_t = site.earth_rate_t_rps
    r_p = rot_pm.apply(mount.lever_arm_m_m)

    def inertial(times):
        m = table.motion(times)
        rot_it = Rotation.from_rotvec(np.outer(times, omega_t))  # t turning with the Earth
        return rot_it, rot_it.apply(m.rot_tp.apply(r_p)), rot_it * m.rot_tp * rot_pm * mount.rot_mb

    def richardson(coarse, fine):  # O(h⁴): the servo transients have large high derivatives
        return (4 * fine - coarse) / 3

    h = 2e-4
    rot_it0, rho0, rot_ib0 = inertial(t)
    _, rho_p, rot_ib_p = inertial(t + h)
    _, rho_m, rot_ib_m = inertial(t - h)
    _, rho_p2, rot_ib_p2 = inertial(t + h / 2)
    _, rho_m2, rot_ib_m2 = inertial(t - h / 2)
    accel_i = richardson((rho_p - 2 * rho0 + rho_m) / h**2,
                         (rho_p2 - 2 * rho0 + rho_m2) / (h / 2) ** 2)
    rho_t = rot_it0.inv().apply(rho0)
    centrifugal = np.cross(omega_t, np.cross(omega_t, rho_t))  # in g already, not in the model
    force_t = rot_it0.inv().apply(accel_i) - centrifugal + [0, 0, site.local_gravity_mps2]
    force_b = (rot_ib0.inv() * rot_it0).apply(force_t)
    np.testing.assert_allclose(kin.specific_force_b_mps2, force_b, rtol=0, atol=2e-7)
    def log_diff(plus, minus, step):
        return ((rot_ib0.inv() * plus).as_rotvec() - (rot_ib0.inv() * minus).as_rotvec()) / step

    rate_b = richardson(log_diff(rot_ib_p, rot_ib_m, 2 * h), log_diff(rot_ib_p2, rot_ib_m2, h))
    np.testing.assert_allclose(kin.rate_b_rps, rate_b, rtol=0, atol=1e-8)
    def gyro(times):
        return compute_imu_kinematics(table.motion(times), site, mount, rot_pm).rate_b_rps

    accel_b = richardson((gyro(t + h) - gyro(t - h)) / (2 * h),
                         (gyro(t + h / 2) - gyro(t - h / 2)) / h)
    np.testing.assert_allclose(kin.angular_accel_b_rps2, accel_b, rtol=0, atol=1e-6)
    assert ((rot_it0.inv() * rot_ib0).inv() * kin.rot_tb).magnitude().max() < 1e-12


def test_gravity_gradient_option():
    site = Site(latitude_deg=45.0)
    motion = stationary_platform_motion(np.zeros(1))
    up = MountedImu("u", Rotation.identity(), np.array([0.0, 0.0, 1.0]))
    plain = compute_imu_kinematics(motion, site, up).specific_force_b_mps2[0, 2]
    with_grad = compute_imu_kinematics(motion, site, up, gravity_gradient=True)
    # one metre higher, gravity is weaker by the free-air gradient (≈ 3.086 µm/s²)
    assert with_grad.specific_force_b_mps2[0, 2] - plain == pytest.approx(-3.086e-6, rel=2e-3)


def test_fixture_kinematics_and_bad_input():
    table = _spinning_table(1.0)
    motion = table.motion(np.linspace(10, 11, 5))
    fixture = hexahedral_fixture(0.05)
    kins = compute_fixture_kinematics(motion, Site(latitude_deg=0.0), fixture)
    assert list(kins) == list(fixture.names)
    # the ±z faces sit on the axis: no centripetal term; the side faces see ω²h along −z_b
    np.testing.assert_allclose(kins["imu_zp"].specific_force_b_mps2[:, :2], 0.0, atol=1e-9)
    np.testing.assert_allclose(kins["imu_xp"].specific_force_b_mps2[:, 2], -0.05, rtol=1e-3)
    with pytest.raises(InvalidInputError, match=r"`lever_arm_p_m` must have shape \(5, 3\)"):
        compute_imu_kinematics(motion, Site(0.0), fixture.mounts[0], lever_arm_p_m=np.zeros((4, 3)))
    with pytest.raises(InvalidInputError, match="`motion` must be a PlatformMotion"):
        compute_imu_kinematics("motion", Site(0.0), fixture.mounts[0])  # type: ignore[arg-type]
