"""Tests of imucalib.sim.fixture: hexahedral geometry (P2), arrays, validation.

The cube and its six orientations are those of P2 (docs/procedures.md).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.sim.fixture import (
    HEXAHEDRAL_FACES,
    Fixture,
    MountedImu,
    array_fixture,
    as_rotation,
    hexahedral_fixture,
    single_imu_fixture,
)


def test_hexahedral_fixture_geometry():
    h = 0.06
    fixture = hexahedral_fixture(h)
    assert len(fixture) == 6
    assert fixture.names == ("imu_zp", "imu_zn", "imu_yp", "imu_yn", "imu_xp", "imu_xn")
    normals = []
    for mount in fixture.mounts:
        mat = mount.rot_mb.as_matrix()
        assert np.linalg.det(mat) == pytest.approx(1.0)
        np.testing.assert_allclose(mat @ mat.T, np.eye(3), atol=1e-15)
        assert np.linalg.norm(mount.lever_arm_m_m) == pytest.approx(h)
        outward = mount.lever_arm_m_m / h
        np.testing.assert_allclose(mount.rot_mb.apply([0.0, 0.0, 1.0]), outward, atol=1e-15)
        normals.append(outward)
    np.testing.assert_allclose(np.array(normals) @ np.array(normals).T,
                               np.kron(np.eye(3), [[1, -1], [-1, 1]]), atol=1e-15)
    # the documented face table: x_b, y_b of the +y face are +x_m, −z_m; of the +x face −z_m, +y_m
    np.testing.assert_allclose(fixture.mount("imu_yp").rot_mb.as_matrix()[:, :2],
                               [[1, 0], [0, 0], [0, -1]], atol=1e-15)
    np.testing.assert_allclose(fixture.mount("imu_xp").rot_mb.as_matrix()[:, :2],
                               [[0, 0], [0, 1], [-1, 0]], atol=1e-15)
    assert len(HEXAHEDRAL_FACES) == 6


def test_hexahedral_subset_and_remount():
    fixture = hexahedral_fixture(0.05, names=["A", "B", "C"])
    assert fixture.names == ("A", "B", "C")
    np.testing.assert_allclose(fixture.lever_arms_p_m(), [[0, 0, 0.05], [0, 0, -0.05],
                                                          [0, 0.05, 0]], atol=1e-15)
    turned = fixture.remounted(Rotation.from_euler("x", 90, degrees=True))
    np.testing.assert_allclose(turned.lever_arms_p_m()[0], [0, -0.05, 0], atol=1e-15)
    np.testing.assert_allclose(turned.rot_pb("A").apply([0, 0, 1]), [0, -1, 0], atol=1e-15)


def test_array_and_single_fixtures():
    offsets = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [-0.1, 0.0, 0.0], [0.0, -0.1, 0.0]]
    rots = Rotation.from_euler("z", [[0], [90], [180], [270]], degrees=True)
    fixture = array_fixture(offsets, rot_mb=rots)
    assert fixture.names == ("imu0", "imu1", "imu2", "imu3")
    # every IMU's x axis points radially outward
    for mount in fixture.mounts:
        np.testing.assert_allclose(mount.rot_mb.apply([1, 0, 0]), mount.lever_arm_m_m / 0.1,
                                   atol=1e-15)
    same = array_fixture(offsets, names=list("abcd"), rot_mb=Rotation.from_euler("x", 180,
                                                                                 degrees=True))
    assert all(np.allclose(m.rot_mb.as_matrix(), np.diag([1, -1, -1])) for m in same.mounts)
    single = single_imu_fixture()
    assert single.names == ("imu0",)
    np.testing.assert_array_equal(single.mounts[0].lever_arm_m_m, np.zeros(3))
    assert single.rot_pm.magnitude() == 0.0
    assert as_rotation(np.eye(3), "m").magnitude() == 0.0


def test_bad_inputs():
    with pytest.raises(ConfigurationError, match=r"IMU names on a fixture must be unique; "
                                                 r"repeated: \['a'\]"):
        array_fixture([[0, 0, 0], [1, 0, 0]], names=["a", "a"])
    with pytest.raises(ConfigurationError, match="must be a proper rotation matrix"):
        MountedImu("u", np.diag([1.0, 1.0, -1.0]), np.zeros(3))  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="must be a proper rotation matrix"):
        as_rotation([[1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "rot_mb")
    with pytest.raises(InvalidInputError, match="`lever_arm_m_m of 'u'` must be finite"):
        MountedImu("u", Rotation.identity(), np.array([0.0, np.nan, 0.0]))
    with pytest.raises(ConfigurationError, match="1 to 64 IMUs; got 65 names"):
        hexahedral_fixture(0.05, names=[f"n{i}" for i in range(65)])
    with pytest.raises(ConfigurationError, match="IMUs 'n0' and 'n6' sit at the same place on "
                                                 r"face \+z"):
        hexahedral_fixture(0.05, names=[f"n{i}" for i in range(7)])
    with pytest.raises(InvalidInputError, match="`half_edge_m` must be > 0"):
        hexahedral_fixture(0.0)
    with pytest.raises(ConfigurationError, match="at least one mounted IMU"):
        Fixture(mounts=())
    with pytest.raises(ConfigurationError, match="`names` must have 2 entries"):
        array_fixture([[0, 0, 0], [1, 0, 0]], names=["a"])
    with pytest.raises(ConfigurationError, match="no IMU named 'zz'"):
        single_imu_fixture().mount("zz")
    with pytest.raises(ConfigurationError, match="must be a single rotation"):
        as_rotation(Rotation.identity(2), "rot_pm")
