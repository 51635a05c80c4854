"""Tests of imucalib.models.earth: reference values, frame conventions, stationary projections."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from imucalib.errors import InvalidInputError
from imucalib.models.earth import (
    Site,
    earth_rate_n_rps,
    gravity_n_mps2,
    normal_gravity_gradient_ps2,
    normal_gravity_mps2,
    rot_nt,
)
from imucalib.sim.fixture import MountedImu
from imucalib.sim.kinematics import compute_imu_kinematics, stationary_platform_motion
from imucalib.sim.table import RateTableSpec, SimRateTable
from imucalib.units import DEG_PER_H, EARTH_RATE_RPS

SEED = 20240611


# --- reference values (docs/equations.md §2, WGS-84) ---------------------------------------------
def test_normal_gravity_reference_values():
    assert normal_gravity_mps2(45.0) == pytest.approx(9.806198, abs=5e-7)
    assert normal_gravity_mps2(0.0) == pytest.approx(9.7803253359, abs=1e-10)  # γ_e
    assert normal_gravity_mps2(90.0) == pytest.approx(9.8321849378, abs=1e-9)  # γ_p (TR8350.2)
    assert normal_gravity_mps2(-30.0) == normal_gravity_mps2(30.0)


def test_free_air_gradient():
    dg = normal_gravity_mps2(45.0, 100.0) - normal_gravity_mps2(45.0, 0.0)
    assert dg / 100.0 == pytest.approx(-3.086e-6, rel=2e-3)  # docs/equations.md §2
    h = 1.0
    fd = (normal_gravity_mps2(45.0, 500.0 + h) - normal_gravity_mps2(45.0, 500.0 - h)) / (2 * h)
    assert normal_gravity_gradient_ps2(45.0, 500.0) == pytest.approx(fd, rel=1e-6)


def test_earth_rate_components_at_45_deg():
    w = earth_rate_n_rps(45.0) / DEG_PER_H
    assert w[0] == pytest.approx(10.6356, abs=5e-5)  # Ω_N
    assert -w[2] == pytest.approx(10.6356, abs=5e-5)  # Ω_U (NED: up = −z)
    assert w[1] == 0.0
    assert np.linalg.norm(w) == pytest.approx(15.041067, abs=1e-6)


def test_gravity_vector_points_down_and_override():
    assert gravity_n_mps2(45.0).tolist() == [0.0, 0.0, normal_gravity_mps2(45.0)]
    assert gravity_n_mps2(45.0, gravity_mps2=9.80708)[2] == 9.80708


# --- frames -----------------------------------------------------------------------------------
@pytest.mark.parametrize(("heading", "x_n", "y_n"), [
    (0.0, [1, 0, 0], [0, -1, 0]),  # North-West-Up
    (90.0, [0, 1, 0], [1, 0, 0]),  # East-North-Up
    (180.0, [-1, 0, 0], [0, 1, 0]),
])
def test_rot_nt_axes(heading, x_n, y_n):
    mat = rot_nt(heading).as_matrix()
    np.testing.assert_allclose(mat[:, 0], x_n, atol=1e-15)
    np.testing.assert_allclose(mat[:, 1], y_n, atol=1e-15)
    np.testing.assert_allclose(mat[:, 2], [0, 0, -1], atol=1e-15)  # z_t up
    assert np.linalg.det(mat) == pytest.approx(1.0)


def test_site_vectors():
    site = Site(latitude_deg=30.0, heading_deg=90.0, gravity_mps2=9.79)
    assert site.gravity_t_mps2.tolist() == [0.0, 0.0, -9.79]
    assert site.specific_force_static_t_mps2.tolist() == [0.0, 0.0, 9.79]
    lat = math.radians(30.0)
    # heading 90°: t is East-North-Up, so Earth rate is [0, Ω cos L, Ω sin L]
    np.testing.assert_allclose(
        site.earth_rate_t_rps, EARTH_RATE_RPS * np.array([0.0, math.cos(lat), math.sin(lat)]),
        atol=1e-20)
    grad = site.gravity_gradient_t_ps2
    assert np.trace(grad) == pytest.approx(0.0, abs=1e-20)
    assert grad[2, 2] > 0  # g_z = −γ becomes less negative with height
    assert Site(45.0).local_gravity_mps2 == normal_gravity_mps2(45.0)


# --- stationary projections against an independent closed form -----------------------------------
@pytest.mark.parametrize("seed", [SEED, SEED + 1, SEED + 2])
def test_stationary_imu_on_turned_table_matches_closed_form(seed):
    rng = np.random.default_rng(seed)
    lat, heading, height = rng.uniform(-89, 89), rng.uniform(-180, 360), rng.uniform(-100, 3000)
    theta = rng.uniform(-2 * np.pi, 2 * np.pi)
    site = Site(latitude_deg=lat, height_m=height, heading_deg=heading)
    table = SimRateTable(RateTableSpec.single_axis("ideal"))
    table.command_position(0, theta, 0.0)
    motion = table.motion(np.array([100.0, 200.0]))
    # Closed form: body x (= platform x) points at azimuth ψ − θ (a positive turn about up is
    # counter-clockwise seen from above), y at azimuth ψ − θ − 90°, z up.
    az = math.radians(heading) - theta
    om, L, g = EARTH_RATE_RPS, math.radians(lat), normal_gravity_mps2(lat, height)
    rate_p = om * np.array([math.cos(L) * math.cos(az), math.cos(L) * math.sin(az), math.sin(L)])
    # A mount turned +90° about x_m: x_b = x_m, y_b = z_m, z_b = −y_m.
    mat_mb = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    cases = [
        (Rotation.identity(), rate_p, np.array([0.0, 0.0, g])),
        (Rotation.from_matrix(mat_mb), np.array([rate_p[0], rate_p[2], -rate_p[1]]),
         np.array([0.0, g, 0.0])),
    ]
    for rot_mb, rate_b, force_b in cases:
        kin = compute_imu_kinematics(motion, site, MountedImu("u", rot_mb, np.zeros(3)))
        for row in range(2):
            np.testing.assert_allclose(kin.rate_b_rps[row], rate_b, rtol=0, atol=1e-9 * om)
            np.testing.assert_allclose(kin.specific_force_b_mps2[row], force_b, rtol=0,
                                       atol=1e-9 * g)
        np.testing.assert_allclose(kin.angular_accel_b_rps2, 0.0, atol=1e-30)


def test_stationary_platform_motion_is_at_rest():
    motion = stationary_platform_motion(np.linspace(0, 10, 5))
    kin = compute_imu_kinematics(motion, Site(0.0), MountedImu("u"))
    np.testing.assert_allclose(kin.specific_force_b_mps2[:, 2], normal_gravity_mps2(0.0))
    np.testing.assert_allclose(kin.rate_b_rps[:, 0], EARTH_RATE_RPS)  # equator, heading North


# --- bad input ------------------------------------------------------------------------------
def test_bad_inputs():
    with pytest.raises(InvalidInputError, match=r"`latitude_deg` must be in \[-90, 90\]; got 91"):
        Site(latitude_deg=91.0)
    with pytest.raises(InvalidInputError, match="`height_m` must be finite"):
        Site(latitude_deg=0.0, height_m=float("nan"))
    with pytest.raises(InvalidInputError, match="`gravity_mps2` must be > 0"):
        Site(latitude_deg=0.0, gravity_mps2=-9.8)
    with pytest.raises(InvalidInputError, match="`heading_deg` must be finite"):
        rot_nt(float("inf"))
