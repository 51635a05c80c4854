"""Tests of imucalib.sim.centrifuge: the input (r_t + c·ω²)·ω², unbalance sides, arm motion."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from imucalib.errors import InvalidInputError, LimitExceededError
from imucalib.models.earth import Site
from imucalib.sim.centrifuge import CentrifugeSpec, SimCentrifuge, dynamic_radius_m
from imucalib.sim.fixture import MountedImu
from imucalib.units import ARCSEC, DEG, EARTH_RATE_RPS

R_T = 0.6
C0, C_PER_KG = 2e-7, 5e-8
INWARD = Rotation.from_euler("z", 180, degrees=True)  # x_b along −x_p: towards the axis


def _centrifuge(load_kg, **extra):
    spec = CentrifugeSpec(static_radius_m=R_T, unbalance_c0_m_per_rps_sq=C0,
                          unbalance_c_m_per_rps_sq_per_kg=C_PER_KG, **extra)
    return SimCentrifuge(spec, load_kg=load_kg)


def _spin_and_average(centrifuge, rate, static_x, site, revolutions=2, n=4000):
    centrifuge.command_rate(rate, 0.0)
    t0 = centrifuge.table.settled_after_s(0, 1.0, 1e-12 * abs(rate)) + 5.0
    t = t0 + np.arange(n) * (revolutions * 2 * np.pi / abs(rate) / n)
    mount = MountedImu("u", INWARD, np.array([static_x, 0.0, 0.0]))
    return t, centrifuge.imu_kinematics(t, site, mount)


@pytest.mark.parametrize("load_kg", [0.0, 2.0, 5.0])
@pytest.mark.parametrize("rate_dps", [120.0, 240.0, 360.0, 480.0])
def test_input_follows_dynamic_radius(load_kg, rate_dps):
    site = Site(latitude_deg=45.0)
    cf = _centrifuge(load_kg)
    w = rate_dps * DEG
    c = C0 + C_PER_KG * load_kg
    assert cf.unbalance_m_per_rps_sq == pytest.approx(c)
    _, kin = _spin_and_average(cf, w, R_T, site)
    omega_u = EARTH_RATE_RPS * np.sin(np.radians(45.0))
    expected = (R_T + c * w * w) * (w * w + 2 * w * omega_u)  # (r_t + cω²)·(ω + Ω_U)² to O(Ω)
    np.testing.assert_allclose(kin.specific_force_b_mps2[:, 0], expected, rtol=1e-12)
    # the unbalance is resolvable: c·ω⁴ is far above the tolerance
    assert c * w**4 > 1e-6 * expected


def test_references_on_both_sides_see_opposite_unbalance():
    site = Site(latitude_deg=90.0)
    w = 300 * DEG
    c = C0 + C_PER_KG * 2.0
    positions = _centrifuge(2.0).spec.p3_positions_p_m()
    for name, sign in (("ref_a", +1.0), ("ref_b", -1.0)):
        cf = _centrifuge(2.0)
        x = positions[name][0]
        _, kin = _spin_and_average(cf, w, x, site)
        radius = abs(x) + sign * c * w * w  # same side as the test position: r + cω²
        # mounted "inward" relative to +x_p: reads +ω²·x for x > 0 and −ω²·|x| for x < 0
        expected = sign * radius * w * (w + 2 * EARTH_RATE_RPS)
        np.testing.assert_allclose(kin.specific_force_b_mps2[:, 0], expected, rtol=1e-12)
    assert cf.radius_m(w, -R_T / 3) == pytest.approx(-R_T / 3 + c * w * w)
    np.testing.assert_allclose(dynamic_radius_m([0.0, 2.0], 1.0, 1e-3, 1e-4), [1.0, 1.0044])


def test_arm_geometry_during_a_ramp():
    cf = _centrifuge(3.0, arm_stretch_s2=1e-6)
    cf.command_rate(400 * DEG, 0.0)
    t = np.linspace(0.05, 6.0, 300)
    static = np.array([R_T, 0.02, 0.0])
    pos, vel, acc = cf.mount_kinematics_p(t, static)
    h = 1e-5
    np.testing.assert_allclose(vel, (cf.mount_position_p_m(t + h, static)
                                     - cf.mount_position_p_m(t - h, static)) / (2 * h),
                               atol=1e-9)
    np.testing.assert_allclose(acc, (cf.mount_kinematics_p(t + h, static)[1]
                                     - cf.mount_kinematics_p(t - h, static)[1]) / (2 * h),
                               atol=1e-8)
    w = cf.motion(t).rate_rps[:, 0]
    c = cf.unbalance_m_per_rps_sq
    np.testing.assert_allclose(pos[:, 0], R_T + (c + 1e-6 * R_T) * w**2, rtol=1e-14)
    np.testing.assert_allclose(pos[:, 1], 0.02 * (1 + 1e-6 * w**2), rtol=1e-14)
    np.testing.assert_allclose(pos[:, 2], 0.0)


def test_spin_axis_tilt_leaks_gravity_once_per_revolution():
    tilt = 30 * ARCSEC
    cf = _centrifuge(0.0, spin_axis_tilt_rad=tilt)
    site = Site(latitude_deg=90.0)
    w = 180 * DEG
    _, kin = _spin_and_average(cf, w, R_T, site)
    g = site.local_gravity_mps2
    radial = kin.specific_force_b_mps2[:, 0]
    assert np.ptp(radial) == pytest.approx(2 * g * np.sin(tilt), rel=1e-3)
    radius = R_T + C0 * w * w
    assert radial.mean() == pytest.approx(radius * w * (w + 2 * EARTH_RATE_RPS * np.cos(tilt)),
                                          rel=1e-12)


def test_arm_positioning_at_rest_and_bad_input():
    cf = _centrifuge(1.0)
    end = cf.command_arm_position(np.pi / 2, 0.0)
    assert cf.motion(np.array([end + 20.0])).angle_rad[0, 0] == pytest.approx(np.pi / 2, abs=1e-12)
    assert cf.feedback(np.array([end + 20.0])).angle_rad.shape == (1, 1)
    cf.command_rate(100 * DEG, end + 30.0)
    with pytest.raises(InvalidInputError, match="arm positioning needs the centrifuge at rest"):
        cf.command_arm_position(0.0, end + 40.0)
    stop = cf.command_stop(end + 50.0)
    assert cf.command_arm_position(np.pi, stop + 1.0) > stop
    with pytest.raises(LimitExceededError, match=r"axis 'spin': rate .* exceeds the limit"):
        cf.command_rate(2000 * DEG, stop + 60.0)
    with pytest.raises(InvalidInputError, match="`load_kg` must be ≥ 0"):
        SimCentrifuge(cf.spec, load_kg=-1.0)
    with pytest.raises(InvalidInputError, match="`static_radius_m` must be > 0"):
        CentrifugeSpec(static_radius_m=0.0)
    with pytest.raises(InvalidInputError, match=r"`static_position_p_m` must have shape \(3\)"):
        cf.mount_position_p_m(np.zeros(2), [1.0, 0.0])
