"""The arm fixture of P3 on the twin's centrifuge, unit swaps, load changes and range overrides.

Units sit on the arm with their x axes pointing inward, so that each x accelerometer reads
+ω²·|r|; the dynamic unbalance c moves the test side out (+c·ω²) and the far side in (−c·ω²).
"""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError
from scipy.spatial.transform import Rotation

from imucalib import units
from imucalib.errors import InvalidInputError
from imucalib.plan.equipment import ImuConfig, TwinEquipment
from imucalib.sim.build import build_rig
from imucalib.sim.rig import TwinRig
from imucalib.station.sim import SimStation

RATE_RPS = 360.0 * units.DEG
W2 = RATE_RPS**2
# Earth rate adds 2·ω·Ω_U to ω² on average (docs/equations.md §7): 1.6e-5 relative at 45°
EARTH_REL = 2.0 * 7.292115e-5 * np.sin(np.radians(45.0)) / RATE_RPS


def arm_twin(radii=(0.5, -0.2), c0=0.0, c_per_kg=0.0, **imu) -> TwinEquipment:
    names = ["T", "B", "A"][:len(radii)]
    return TwinEquipment.model_validate({
        "seed": 3,
        "centrifuge": {"enabled": True, "static_radius_m": 0.5, "unbalance_c0_m_per_rps_sq": c0,
                       "unbalance_c_m_per_rps_sq_per_kg": c_per_kg},
        "fixture": {"kind": "arm", "arm_radii_m": list(radii)},
        "imus": [{"name": n, "grade": "navigation", "noise": "white", **imu} for n in names]})


def spin(rig: TwinRig, seconds: float = 10.0) -> dict[str, tuple[float, float]]:
    """Spin up (or keep spinning), settle, and return each unit's mean (measured, true) accel x."""
    end = rig.centrifuge.command_rate(RATE_RPS, rig.now_s)
    rig.generate(end + 2.0)
    chunk = rig.generate(end + 2.0 + seconds)  # whole revolutions at 1 rev/s
    return {n: (float(s.accel_mps2[:, 0].mean()), float(s.true_specific_force_b_mps2[:, 0].mean()))
            for n, s in chunk.imu.items()}


def test_arm_fixture_places_units_at_their_radii_with_x_inward():
    built = build_rig(arm_twin())
    fixture = built.rig.fixture
    np.testing.assert_array_equal(fixture.mount("T").lever_arm_m_m, [0.5, 0.0, 0.0])
    np.testing.assert_array_equal(fixture.mount("B").lever_arm_m_m, [-0.2, 0.0, 0.0])
    # x_b points inward: towards −x_m on the test side, +x_m on the far side
    np.testing.assert_allclose(fixture.mount("T").rot_mb.apply([1.0, 0, 0]), [-1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(fixture.mount("B").rot_mb.apply([1.0, 0, 0]), [1, 0, 0])
    assert built.truth["mounts"]["B"]["lever_arm_m_m"] == [-0.2, 0.0, 0.0]


def test_units_on_both_sides_read_plus_omega_squared_r():
    means = spin(build_rig(arm_twin()).rig)
    for name, r in (("T", 0.5), ("B", 0.2)):
        measured, true = means[name]
        expected = W2 * r * (1.0 + EARTH_REL)
        assert true == pytest.approx(expected, rel=2e-6)
        assert measured == pytest.approx(expected, rel=5e-4)  # the unit's own errors


def test_unbalance_moves_the_test_side_out_and_the_far_side_in():
    c = 1e-5
    means = spin(build_rig(arm_twin(c0=c)).rig)
    assert means["T"][1] == pytest.approx(W2 * (0.5 + c * W2) * (1 + EARTH_REL), rel=2e-6)
    assert means["B"][1] == pytest.approx(W2 * (0.2 - c * W2) * (1 + EARTH_REL), rel=2e-6)


def test_a_load_change_changes_c():
    station = SimStation(arm_twin(c_per_kg=1e-6))
    rig = station.rig
    before = spin(rig)
    station.set_centrifuge_load(10.0)
    assert rig.centrifuge.load_kg == 10.0
    assert rig.centrifuge.unbalance_m_per_rps_sq == pytest.approx(1e-5)
    after = spin(rig)
    shift = W2 * 1e-5 * W2 * (1 + EARTH_REL)
    assert after["T"][1] - before["T"][1] == pytest.approx(shift, rel=1e-4)
    assert after["B"][1] - before["B"][1] == pytest.approx(-shift, rel=1e-4)
    assert [kg for _, kg in station.load_changes] == [10.0]
    with pytest.raises(InvalidInputError, match="load_kg"):
        station.set_centrifuge_load(-1.0)


def test_a_load_without_centrifuge_is_refused():
    station = SimStation(TwinEquipment.model_validate({"imus": [{"name": "U"}]}))
    with pytest.raises(InvalidInputError, match="no centrifuge"):
        station.set_centrifuge_load(1.0)


def test_swapping_two_units_exchanges_their_places_and_readings():
    station = SimStation(arm_twin())
    rig = station.rig
    before = spin(rig)
    station.swap_units("T", "B")
    for name, arm, x_m in (("T", [-0.2, 0, 0], [1, 0, 0]), ("B", [0.5, 0, 0], [-1, 0, 0])):
        for mount in (rig.imus[name].mount, rig.fixture.mount(name)):
            assert mount is not None and mount.name == name
            np.testing.assert_array_equal(mount.lever_arm_m_m, arm)
            np.testing.assert_allclose(mount.rot_mb.apply([1.0, 0, 0]), x_m, atol=1e-15)
    assert rig.fixture.names == ("T", "B")
    after = spin(rig)
    assert after["T"][1] == pytest.approx(before["B"][1], rel=1e-6)
    assert after["B"][1] == pytest.approx(before["T"][1], rel=1e-6)
    # each unit keeps its own errors: its scale factor now applies to the other radius
    ratio_t = before["T"][0] / before["T"][1]
    assert after["T"][0] / after["T"][1] == pytest.approx(ratio_t, abs=2e-5)
    assert [(a, b) for _, a, b in station.swaps] == [("T", "B")]


def test_a_swap_of_unknown_or_equal_units_is_refused():
    rig = build_rig(arm_twin()).rig
    with pytest.raises(InvalidInputError, match="no IMU named 'X'"):
        rig.swap_mounts("T", "X")
    with pytest.raises(InvalidInputError, match="twice"):
        rig.swap_mounts("T", "T")
    assert rig.fixture.mount("T").rot_mb.approx_equal(Rotation.from_euler("z", 180, degrees=True))


def test_range_overrides_replace_the_grades_full_scale():
    built = build_rig(arm_twin(radii=(0.5,), gyro_range_dps=1000.0, accel_range_g=1.5))
    model = built.imu_models["T"]
    assert model.gyro_output.range == pytest.approx(1000.0 * units.DEG)
    assert model.accel_output.range == pytest.approx(1.5 * units.G0_MPS2)
    assert built.truth["imu_models"]["T"]["accel_output"]["range"] == pytest.approx(
        1.5 * units.G0_MPS2)
    default = build_rig(arm_twin(radii=(0.5,))).imu_models["T"]
    assert default.gyro_output.range == pytest.approx(400.0 * units.DEG)  # the grade's
    assert default.gyro_output.resolution_bits == model.gyro_output.resolution_bits


def test_a_unit_with_a_small_accel_range_flags_saturation_on_the_arm():
    rig = build_rig(arm_twin(radii=(0.5, -0.2), accel_range_g=1.5)).rig  # T sees 2 g
    end = rig.centrifuge.command_rate(RATE_RPS, 0.0)
    chunk = rig.generate(end + 3.0)
    t, b = chunk.imu["T"], chunk.imu["B"]
    late = t.true_time_s > end + 1.0
    assert t.saturated[late].all()
    assert np.abs(t.accel_mps2[late, 0]).max() <= 1.5 * units.G0_MPS2
    assert not b.saturated[b.true_time_s > end + 1.0].any()  # 0.8 g, within range


@pytest.mark.parametrize(("fixture", "match"), [
    ({"kind": "arm", "arm_radii_m": [0.5]}, "one arm_radii_m entry per IMU"),
    ({"kind": "arm", "arm_radii_m": [0.5, 0.0]}, "arm_radii_m.1 is 0"),
    ({"kind": "arm", "arm_radii_m": [0.5, -21.0]}, "greater than or equal to -20"),
    ({"kind": "array", "arm_radii_m": [0.5, -0.2]}, "fixture kind is 'array'"),
])
def test_arm_fixture_errors(fixture, match):
    with pytest.raises(ValidationError, match=match):
        TwinEquipment.model_validate({"fixture": fixture,
                                      "imus": [{"name": "T"}, {"name": "B"}]})


@pytest.mark.parametrize(("fields", "match"), [
    ({"gyro_range_dps": 0.0}, "greater than 0"),
    ({"accel_range_g": 20000.0}, "less than or equal to 10000"),
])
def test_range_override_bounds(fields, match):
    with pytest.raises(ValidationError, match=match):
        TwinEquipment.model_validate({"imus": [{"name": "U", **fields}]})


def test_centrifuge_tilt_and_stretch_reach_the_spec():
    eq = TwinEquipment.model_validate({
        "centrifuge": {"enabled": True, "spin_axis_tilt_deg": 0.5, "arm_stretch_s2": 1e-6},
        "imus": [{"name": "U"}]})
    spec = build_rig(eq).rig.centrifuge.spec
    assert spec.spin_axis_tilt_rad == pytest.approx(0.5 * units.DEG)
    assert spec.arm_stretch_s2 == 1e-6
    with pytest.raises(ValidationError, match="less than or equal to 5"):
        TwinEquipment.model_validate({"centrifuge": {"spin_axis_tilt_deg": 6.0},
                                      "imus": [{"name": "U"}]})


def test_imu_errors_replace_the_drawn_truth():
    """ImuConfig.errors: a known nonlinearity injected into the twin's truth, shape-checked."""
    cfg = ImuConfig(name="U", grade="navigation",
              errors={"gyro.scale_asymmetry": (1e-4, 0.0, -2e-4), "accel.k3": (1e-7, 0.0, 0.0),
                      "gyro.g_sensitivity": ((1e-5, 0, 0), (0, 0, 0), (0, 0, 0))})
    model = build_rig(TwinEquipment(imus=(cfg,))).imu_models["U"]
    assert list(model.gyro.scale_asymmetry) == [1e-4, 0.0, -2e-4]
    assert model.accel.k3[0] == 1e-7 and model.gyro.g_sensitivity[0, 0] == 1e-5
    assert model.accel.k2.any()  # what is not replaced stays drawn
    for bad in ({"gyro.k9": (1, 2, 3)}, {"accel.k2": (1.0, 2.0)}, {"mag.k2": (0, 0, 0)}):
        with pytest.raises(ValidationError, match="errors"):
            ImuConfig(name="U", errors=bad)
