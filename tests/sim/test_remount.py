"""Remounts of the cube (P2) and up to 64 IMUs on it: poses, rig physics, equipment layouts.

The poses are :mod:`imucalib.plan.fixture_poses`; the rig's side is ``TwinRig.remount``; the
layouts are ``FixtureConfig.mounts`` and the default round-robin grid.
"""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from imucalib import units
from imucalib.errors import ConfigurationError
from imucalib.plan.equipment import TwinEquipment, hexahedral_grid_offsets_m
from imucalib.plan.fixture_poses import FIXTURE_AXES, FIXTURE_POSES, rot_pm_for_pose
from imucalib.sim.build import build_rig
from imucalib.sim.fixture import HEXAHEDRAL_FACE_NAMES, hexahedral_fixture

AXES = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0),
        "+z": (0, 0, 1), "-z": (0, 0, -1)}


# --- poses ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("up", FIXTURE_AXES)
@pytest.mark.parametrize("yaw", [0.0, 30.0, -270.0])
def test_each_pose_is_a_proper_rotation_bringing_its_axis_up(up, yaw):
    mat = rot_pm_for_pose(up, yaw)
    np.testing.assert_allclose(mat @ mat.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(mat) == pytest.approx(1.0)
    np.testing.assert_allclose(mat @ np.array(AXES[up], float), [0, 0, 1], atol=1e-15)
    c, s = np.cos(np.radians(yaw)), np.sin(np.radians(yaw))
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    np.testing.assert_allclose(mat, rz @ np.array(FIXTURE_POSES[up]), atol=1e-15)


def test_pose_table_as_documented():
    np.testing.assert_array_equal(rot_pm_for_pose("+z"), np.eye(3))
    # columns: images of x_m, y_m, z_m (module docstring's table)
    expect = {"-z": ("+x", "-y", "-z"), "+y": ("+x", "+z", "-y"), "-y": ("+x", "-z", "+y"),
              "+x": ("+z", "+y", "-x"), "-x": ("-z", "+y", "+x")}
    for up, cols in expect.items():
        np.testing.assert_array_equal(rot_pm_for_pose(up),
                                      np.array([AXES[c] for c in cols], float).T)
    assert FIXTURE_AXES == HEXAHEDRAL_FACE_NAMES == ("+z", "-z", "+y", "-y", "+x", "-x")


def test_face_up_aligns_its_imu_with_the_platform():
    cube = hexahedral_fixture(0.05)
    for name, up in zip(cube.names, FIXTURE_AXES, strict=True):
        placed = cube.remounted(rot_pm_for_pose(up))
        np.testing.assert_allclose(placed.rot_pb(name).as_matrix(), np.eye(3), atol=1e-15)
        np.testing.assert_allclose(placed.lever_arms_p_m()[cube.names.index(name)],
                                   [0, 0, 0.05], atol=1e-15)


@pytest.mark.parametrize(("up", "yaw", "match"), [
    ("z", 0.0, "must be one of"), ("+z", float("nan"), "must be finite")])
def test_bad_poses(up, yaw, match):
    with pytest.raises(ValueError, match=match):
        rot_pm_for_pose(up, yaw)


# --- rig physics ---------------------------------------------------------------------------------
def cube_equipment(faces, *, half_edge_m=0.1, offsets=None, rate_hz=50.0):
    mounts = [{"face": f, "offset_m": (offsets[i] if offsets else (0.0, 0.0))}
              for i, f in enumerate(faces)]
    return TwinEquipment.model_validate({
        "seed": 3, "table": {"kind": "single-axis", "grade": "ideal"},
        "fixture": {"kind": "hexahedral", "half_edge_m": half_edge_m, "mounts": mounts},
        "imus": [{"name": f"imu{i}", "sample_rate_hz": rate_hz} for i in range(len(faces))]})


def still_force(rig, name, t0):
    t = np.linspace(t0, t0 + 0.5, 5)
    return np.asarray(rig.imu_kinematics(name, t).specific_force_b_mps2[0])


def test_remount_turns_gravity_in_every_imu_and_clears_the_still_cache():
    rig = build_rig(cube_equipment(["+z", "+x"])).rig
    g = rig.site.local_gravity_mps2
    np.testing.assert_allclose(still_force(rig, "imu0", 1.0), [0, 0, g], atol=1e-3)
    assert rig._still  # the still table filled its cache in pose +z
    rig.generate(2.0)
    rig.remount(rot_pm_for_pose("-z"))
    assert not rig._still
    np.testing.assert_allclose(still_force(rig, "imu0", 3.0), [0, 0, -g], atol=1e-3)
    rig.remount(rot_pm_for_pose("+x"))
    np.testing.assert_allclose(still_force(rig, "imu1", 3.0), [0, 0, g], atol=1e-3)
    np.testing.assert_allclose(still_force(rig, "imu0", 3.0), [g, 0, 0], atol=1e-3)
    # the mounts in m stay: only rot_pm changed
    np.testing.assert_allclose(rig.imus["imu1"].mount.lever_arm_m_m, [0.1, 0, 0])
    np.testing.assert_allclose(rig.fixture.rot_pm.as_matrix(), rot_pm_for_pose("+x"),
                               atol=1e-15)


def test_generated_samples_follow_the_pose_from_the_remount_on():
    rig = build_rig(cube_equipment(["+z"])).rig
    first = rig.generate(1.0).imu["imu0"]
    rig.remount(rot_pm_for_pose("-z"))
    second = rig.generate(2.0).imu["imu0"]
    assert first.true_specific_force_b_mps2[:, 2].min() > 9.7
    assert second.true_specific_force_b_mps2[:, 2].max() < -9.7
    assert second.true_time_s.min() >= 1.0


@pytest.mark.parametrize(("up", "yaw"), [("+x", 0.0), ("-y", 40.0)])
def test_centripetal_force_uses_the_lever_arm_in_the_new_pose(up, yaw):
    faces, offsets = ["+z", "+x", "-y"], [(0.0, 0.0), (0.03, -0.02), (0.05, 0.04)]
    rig = build_rig(cube_equipment(faces, half_edge_m=0.1, offsets=offsets)).rig
    rig.remount(rot_pm_for_pose(up, yaw))
    omega = 200.0 * units.DEG
    rig.table.command_rate(0, omega, 0.0)
    t = np.linspace(20.0, 21.0, 11)
    rot_pm = rot_pm_for_pose(up, yaw)
    g = rig.site.local_gravity_mps2
    for name in rig.imu_names:
        kin = rig.imu_kinematics(name, t)
        mount = rig.imus[name].mount
        arm_p = rot_pm @ mount.lever_arm_m_m
        r_perp = np.r_[arm_p[:2], 0.0]
        rot_tb = kin.rot_tb
        force_t = rot_tb.apply(kin.specific_force_b_mps2)
        # in the (rotating) platform frame: −ω²·r_⟂ plus the reaction to gravity, +g·z
        rot_tp = rot_tb * (rig.fixture.rot_pm * mount.rot_mb).inv()
        force_p = rot_tp.inv().apply(force_t)
        expect = -omega**2 * r_perp + np.array([0.0, 0.0, g])
        np.testing.assert_allclose(force_p, np.broadcast_to(expect, force_p.shape), atol=2e-3)
    assert np.linalg.norm(omega**2 * np.r_[(rot_pm @ rig.imus["imu2"].mount.lever_arm_m_m)[:2]]
                          ) > 0.5  # the term is there


# --- hexahedral builder --------------------------------------------------------------------------
def test_hexahedral_faces_and_offsets_give_the_lever_arms():
    h = 0.15
    fixture = hexahedral_fixture(h, ["a", "b", "c"], faces=["+x", "-y", "+x"],
                                 offsets_m=[[0.01, 0.02], [0.15, -0.15], [0.0, 0.0]])
    # +x face: x_b = −z_m, y_b = +y_m; −y face: x_b = +x_m, y_b = +z_m
    np.testing.assert_allclose(fixture.mount("a").lever_arm_m_m, [h, 0.02, -0.01])
    np.testing.assert_allclose(fixture.mount("b").lever_arm_m_m, [0.15, -h, -0.15])
    np.testing.assert_allclose(fixture.mount("a").rot_mb.apply([0, 0, 1]), [1, 0, 0],
                               atol=1e-15)
    np.testing.assert_allclose(fixture.mount("c").lever_arm_m_m, [h, 0, 0])


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"names": [f"i{k}" for k in range(65)]}, "1 to 64 IMUs; got 65"),
    ({"names": ["a", "b"], "faces": ["+x"]}, "`faces` must have 2 entries"),
    ({"names": ["a"], "faces": ["up"]}, r"unknown cube faces \['up'\]"),
    ({"names": ["a"], "offsets_m": [[0.06, 0.0]]}, "'a': offset .* leaves its face"),
])
def test_hexahedral_builder_errors(kwargs, match):
    with pytest.raises(ConfigurationError, match=match):
        hexahedral_fixture(0.05, **kwargs)


# --- equipment layouts ---------------------------------------------------------------------------
def test_default_layout_of_64_imus():
    eq = TwinEquipment.model_validate({
        "fixture": {"kind": "hexahedral", "half_edge_m": 0.1, "spacing_m": 0.04},
        "imus": [{"name": f"U{i:02d}", "sample_rate_hz": 50.0} for i in range(64)]})
    fixture = build_rig(eq).rig.fixture
    assert len(fixture) == 64
    arms = np.array([m.lever_arm_m_m for m in fixture.mounts])
    assert len({tuple(np.round(a, 9)) for a in arms}) == 64  # no two IMUs in one place
    for i, mount in enumerate(fixture.mounts):
        normal = np.array(AXES[FIXTURE_AXES[i % 6]], float)
        np.testing.assert_allclose(mount.rot_mb.apply([0, 0, 1]), normal, atol=1e-15)
        assert mount.lever_arm_m_m @ normal == pytest.approx(0.1)  # on the face
        assert np.max(np.abs(mount.lever_arm_m_m)) <= 0.1 + 1e-12  # inside it
    # 11 IMUs on +z and −z (4×3 grid), 10 on the others (4×3), pitch 0.04 m, centred
    layout = hexahedral_grid_offsets_m(64, 0.04)
    xs = sorted({round(ox, 9) for face, ox, _ in layout if face == "+z"})
    np.testing.assert_allclose(xs, [-0.06, -0.02, 0.02, 0.06])
    assert sum(face == "+z" for face, _, _ in layout) == 11
    # up to six IMUs: one per face at its centre, as before
    assert hexahedral_grid_offsets_m(6, 0.04) == [(f, 0.0, 0.0) for f in FIXTURE_AXES]


def test_default_layout_that_does_not_fit_is_refused():
    with pytest.raises(ValidationError, match=(
            r"64 IMUs on a hexahedral fixture: up to 11 per face on a 4×3 grid of spacing_m "
            r"0\.05 m reach 0\.075 m from the face centre, beyond half_edge_m 0\.05 m")):
        TwinEquipment.model_validate({
            "fixture": {"kind": "hexahedral", "half_edge_m": 0.05, "spacing_m": 0.05},
            "imus": [{"name": f"U{i}"} for i in range(64)]})


def test_explicit_mounts_are_used_in_order():
    eq = cube_equipment(["-x", "-x", "+y"], half_edge_m=0.15,
                        offsets=[(0.1, 0.0), (-0.1, 0.05), (0.0, 0.0)])
    fixture = build_rig(eq).rig.fixture
    # −x face: x_b = +z_m, y_b = +y_m
    np.testing.assert_allclose(fixture.mount("imu0").lever_arm_m_m, [-0.15, 0.0, 0.1])
    np.testing.assert_allclose(fixture.mount("imu1").lever_arm_m_m, [-0.15, 0.05, -0.1])
    np.testing.assert_allclose(fixture.mount("imu2").lever_arm_m_m, [0.0, 0.15, 0.0])


@pytest.mark.parametrize(("fixture", "n", "match"), [
    ({"kind": "hexahedral", "mounts": [{"face": "+z"}]}, 2,
     r"fixture.mounts must hold one mount per IMU \(2\); got 1"),
    ({"kind": "hexahedral", "half_edge_m": 0.05, "mounts": [{"face": "+x", "offset_m": [0.06, 0]}]},
     1, r"mounts.0: offset_m \(0.06, 0\) m leaves face \+x .*half_edge_m 0.05 m"),
    ({"kind": "hexahedral", "mounts": [{"face": "top"}]}, 1, "face"),
    ({"kind": "array", "mounts": [{"face": "+z"}]}, 1,
     "`mounts` places IMUs on the faces of a hexahedral fixture; fixture kind is 'array'"),
    ({"kind": "hexahedral"}, 65, "at most 64"),
    ({"kind": "hexahedral", "mounts": [{"face": "+z"}, {"face": "-z"}, {"face": "+z"}]}, 3,
     r"mounts.0 and mounts.2 put two IMUs at the same place \(face \+z"),
])
def test_fixture_configuration_errors(fixture, n, match):
    with pytest.raises(ValidationError, match=match):
        TwinEquipment.model_validate({"fixture": fixture,
                                      "imus": [{"name": f"U{i}"} for i in range(n)]})
