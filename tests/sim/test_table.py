"""Tests of imucalib.sim.table: P1 geometry, limits, settling, feedback, kinematic consistency."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib.errors import ConfigurationError, InvalidInputError, LimitExceededError
from imucalib.sim.table import AxisSpec, RateTableSpec, SimRateTable, compute_platform_motion
from imucalib.units import ARCSEC, DEG

SEED = 20240611
G = 9.80665


def _gravity_p(motion):
    """Specific force of a point at rest, in p: rot_tp⁻¹·[0, 0, g]."""
    return motion.rot_tp.inv().apply(np.array([0.0, 0.0, G]))


def _p1_reference(pitch, roll):
    return G * np.array([np.sin(pitch), np.sin(roll) * np.cos(pitch), np.cos(pitch) * np.cos(roll)])


# --- P1 geometry (docs/p1.md, calibration step 1) ------------------------------------------------
# P1 labels (90°, 180°) "X down", but its own formula a_X = g·sin θ gives X up there: with
# pitch outer, the roll axis is vertical at θ = 90° and roll only turns the IMU about it. X down
# is (−90°, 0°) under the formula; both are checked here.
@pytest.mark.parametrize(("pitch_deg", "roll_deg", "up"), [
    (0, 0, [0, 0, 1]), (0, 180, [0, 0, -1]), (90, 0, [1, 0, 0]), (90, 180, [1, 0, 0]),
    (-90, 0, [-1, 0, 0]), (0, 90, [0, 1, 0]), (0, 270, [0, -1, 0]),
])
def test_p1_six_positions(pitch_deg, roll_deg, up):
    table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("ideal"))
    table.command_position("pitch", pitch_deg * DEG, 0.0)
    table.command_position("roll", roll_deg * DEG, 0.0)
    f_p = _gravity_p(table.motion(np.array([60.0])))[0]
    np.testing.assert_allclose(f_p, _p1_reference(pitch_deg * DEG, roll_deg * DEG), atol=1e-12 * G)
    np.testing.assert_allclose(f_p, G * np.array(up), atol=1e-12 * G)


def test_p1_random_angles():
    rng = np.random.default_rng(SEED)
    angles = rng.uniform(-2 * np.pi, 2 * np.pi, (50, 2))
    spec = RateTableSpec.dual_axis_pitch_roll("ideal")
    motion = compute_platform_motion(spec, np.arange(50.0), angles, np.zeros((50, 2)),
                                     np.zeros((50, 2)))
    expected = np.array([_p1_reference(p, r) for p, r in angles])
    np.testing.assert_allclose(_gravity_p(motion), expected, atol=1e-12 * G)


def test_rotation_sense_is_right_handed():
    spec = RateTableSpec.single_axis("ideal")
    motion = compute_platform_motion(spec, [0.0], [[math.pi / 2]], [[1.0]], [[0.0]])
    np.testing.assert_allclose(motion.rot_tp.apply([1.0, 0.0, 0.0]), [[0, 1, 0]], atol=1e-15)
    np.testing.assert_allclose(motion.omega_tp_p_rps, [[0, 0, 1.0]], atol=1e-15)


# --- geometry of the imperfections ---------------------------------------------------------------
def test_non_orthogonality_and_wobble_geometry():
    delta, wob = 20 * ARCSEC, 7 * ARCSEC
    spec = RateTableSpec.dual_axis_pitch_roll("ideal", non_orthogonality_rad=delta)
    # axis directions in p at home, from the angular rate of each axis alone
    zero = np.zeros((2, 2))
    pitch, roll = compute_platform_motion(spec, [0.0, 0.0], zero, np.eye(2), zero).omega_tp_p_rps
    assert math.acos(np.dot(pitch, roll)) == pytest.approx(math.pi / 2 + delta, abs=1e-12)
    home = compute_platform_motion(spec, [0.0], [[0.0, 0.0]], [[0.0, 0.0]], [[0.0, 0.0]])
    f_p = _gravity_p(home)[0]  # pitch tilts the platform by δ about x, roll by δ about z
    sd, cd = math.sin(delta), math.cos(delta)
    np.testing.assert_allclose(f_p, G * np.array([sd * sd, cd * sd, cd]), atol=1e-15)
    assert math.acos(spec.axes[0].actual_axis[2]) == pytest.approx(math.pi / 2 + delta, abs=1e-12)
    single = RateTableSpec.single_axis("ideal", wobble_rad=wob)
    ideal = RateTableSpec.single_axis("ideal")
    theta = np.linspace(0, 2 * np.pi, 73)[:, None]
    zeros = np.zeros_like(theta)
    tilt = (compute_platform_motion(ideal, theta[:, 0], theta, zeros, zeros).rot_tp.inv()
            * compute_platform_motion(single, theta[:, 0], theta, zeros, zeros).rot_tp)
    np.testing.assert_allclose(tilt.magnitude(), wob, rtol=1e-9)  # constant wobble amplitude
    rotvec_t = compute_platform_motion(ideal, theta[:, 0], theta, zeros, zeros).rot_tp.apply(
        tilt.as_rotvec())
    assert np.ptp(rotvec_t[:, 0]) == pytest.approx(2 * wob, rel=1e-6)  # the tilt axis turns


def test_omega_and_alpha_match_finite_differences_with_imperfections():
    spec = RateTableSpec.dual_axis_pitch_roll("lab", wobble_rad=0.02, non_orthogonality_rad=0.03)
    table = SimRateTable(spec)
    table.command_rate("pitch", 2.0, 0.0)
    table.command_rate("roll", -3.0, 0.5)
    table.command_position("pitch", 1.0, 3.0)  # interrupt: brake, come back, settle
    t = np.linspace(0.013, 8.0, 641)
    h = 1e-5
    m0, mp, mm = table.motion(t), table.motion(t + h), table.motion(t - h)
    fwd = (m0.rot_tp.inv() * mp.rot_tp).as_rotvec()
    bwd = (m0.rot_tp.inv() * mm.rot_tp).as_rotvec()
    scale_w = np.abs(m0.omega_tp_p_rps).max()
    np.testing.assert_allclose((fwd - bwd) / (2 * h), m0.omega_tp_p_rps, atol=1e-7 * scale_w)
    alpha_fd = (mp.omega_tp_p_rps - mm.omega_tp_p_rps) / (2 * h)
    scale_a = np.abs(m0.alpha_tp_p_rps2).max()
    np.testing.assert_allclose(alpha_fd, m0.alpha_tp_p_rps2, atol=1e-6 * scale_a)
    np.testing.assert_allclose((mp.angle_rad - mm.angle_rad) / (2 * h), m0.rate_rps, atol=1e-7)
    np.testing.assert_allclose((mp.rate_rps - mm.rate_rps) / (2 * h), m0.accel_rps2,
                               atol=1e-6 * np.abs(m0.accel_rps2).max())


def test_axis_jerk_matches_finite_differences():
    table = SimRateTable(RateTableSpec.single_axis("lab"))
    table.command_rate(0, 1.5, 0.0)
    t = np.linspace(0.001, 1.5, 301)  # the jerk jumps at the command (t = 0)
    h = 1e-6
    _, _, _, jerk = table.axis_motion(0, t)
    fd = (table.axis_motion(0, t + h)[2] - table.axis_motion(0, t - h)[2]) / (2 * h)
    np.testing.assert_allclose(fd, jerk, atol=1e-4 * np.abs(jerk).max())


# --- position moves ---------------------------------------------------------------------------
@pytest.mark.parametrize("target_deg", [0.5, 30.0, 2000.0, -250.0])
def test_position_move_limits_settling_and_feedback(target_deg):
    spec = RateTableSpec.single_axis("lab")
    ax = spec.axes[0]
    table = SimRateTable(spec, rng=SEED)
    target = target_deg * DEG
    t_end = table.command_position(0, target, 1.0)
    min_time = abs(target) / ax.max_rate_rps
    assert t_end - 1.0 >= min_time
    t = np.arange(0.0, t_end + 5.0, 1e-3)
    motion = table.motion(t)
    assert np.abs(motion.rate_rps).max() <= ax.max_rate_rps
    assert np.abs(motion.accel_rps2).max() <= ax.max_accel_rps2
    if abs(target_deg) > 500:
        assert np.abs(motion.rate_rps).max() > 0.95 * ax.max_rate_rps  # the limit is used
    tol = ax.encoder_resolution_rad
    t_settled = table.settled_after_s(0, tol, 1e-4)
    assert t_end < t_settled < t_end + 3.0
    after = np.linspace(t_settled, t_settled + 30.0, 500)
    angle, rate, _, _ = table.axis_motion(0, after)
    assert np.abs(angle - target).max() <= tol
    assert np.abs(rate).max() <= 1e-4
    assert table.is_settled(0, float(after[0]), tol, 1e-4)
    assert not table.is_settled(0, 1.0 + 0.5 * (t_end - 1.0), tol, 1e-4)
    measured = table.feedback(after).angle_rad[:, 0]
    bound = (1.8 * ax.encoder_error_rad + 0.5 * ax.encoder_resolution_rad
             + 5 * ax.position_noise_rad)
    assert np.abs(measured - target).max() <= bound
    assert table.mode(0, float(after[0])) == "position"


def test_command_interrupting_a_move_keeps_motion_continuous():
    table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("high"))
    table.command_position("roll", 3.0, 0.0)
    table.command_rate("roll", -2.0, 0.7)
    eps = 1e-9
    m = table.motion(np.array([0.7 - eps, 0.7 + eps]))
    np.testing.assert_allclose(np.diff(m.angle_rad[:, 1]), 0.0, atol=1e-6)
    np.testing.assert_allclose(np.diff(m.rate_rps[:, 1]), 0.0, atol=1e-6)
    np.testing.assert_allclose(np.diff(m.accel_rps2[:, 1]), 0.0, atol=1e-4)
    end = table.command_stop("roll", 10.0)
    hold = table.motion(np.array([end + 20.0, end + 40.0]))
    assert hold.angle_rad[0, 1] == hold.angle_rad[1, 1]
    assert table.mode("roll", end + 20.0) == "stop"
    assert table.is_settled("roll", end + 20.0, 1e-9, 1e-9)


def test_position_command_while_spinning_reaches_target():
    table = SimRateTable(RateTableSpec.single_axis("high"))
    table.command_rate(0, 3.0, 0.0)
    end = table.command_position(0, 1.0, 5.0)  # far behind: brake and come back
    final = table.motion(np.array([end + 10.0]))
    assert final.angle_rad[0, 0] == pytest.approx(1.0, abs=1e-12)
    table.command_off(0, end + 20.0)
    assert table.mode(0, end + 30.0) == "off"


# --- rate mode ----------------------------------------------------------------------------------
@pytest.mark.parametrize("grade", ["high", "lab"])
@pytest.mark.parametrize("rate_dps", [50.0, -100.0])
def test_rate_mode_reads_back_its_rate_over_whole_revolutions(grade, rate_dps):
    spec = RateTableSpec.single_axis(grade)
    ax = spec.axes[0]
    table = SimRateTable(spec, rng=SEED)
    rate = rate_dps * DEG
    table.command_rate(0, rate, 0.0)
    ripple = ax.rate_ripple_fraction * abs(rate)
    t0 = table.settled_after_s(0, 1.0, 1.5 * ripple)
    period = 2 * np.pi / abs(rate)
    n = 20_000
    t = t0 + np.arange(n) * (3 * period / n)  # exactly three revolutions
    feedback = table.feedback(t)
    assert abs(feedback.rate_rps[:, 0].mean() - rate) <= ripple
    true_rate = table.motion(t).rate_rps[:, 0]
    assert 0.99 * ripple <= np.abs(true_rate - rate).max() <= 1.5 * ripple
    # the encoder error modulates the measured rate once and twice per revolution
    encoder_modulation = np.abs(feedback.rate_rps[:, 0] - true_rate).max()
    assert encoder_modulation > 0.5 * ax.encoder_error_rad * abs(rate)
    assert table.mode(0, float(t[0])) == "rate"
    assert table.is_settled(0, float(t[0]), 0.0, ripple + 1e-3 * abs(rate))


def test_rate_overshoot_is_bounded():
    spec = RateTableSpec.single_axis("lab")
    ax = spec.axes[0]
    table = SimRateTable(spec)
    table.command_rate(0, ax.max_rate_rps, 0.0)
    rate = table.motion(np.arange(0.0, 10.0, 1e-3)).rate_rps[:, 0]
    ripple = ax.rate_ripple_fraction * ax.max_rate_rps
    assert rate.max() <= ax.max_rate_rps + ax.rate_overshoot_rps + ripple
    assert ax.rate_overshoot_rps < 0.02 * ax.max_rate_rps


def test_fixed_table_and_static_speed_path():
    table = SimRateTable(RateTableSpec.fixed())
    motion = table.motion(np.linspace(0, 1, 11))
    assert motion.angle_rad.shape == (11, 0)
    np.testing.assert_allclose(motion.rot_tp.as_quat(), [[0, 0, 0, 1]] * 11)
    dual = SimRateTable(RateTableSpec.dual_axis_pitch_roll("high"))
    dual.command_position(0, 1.0, 0.0)
    t = np.arange(0.0, 600.0, 1e-2)
    static = dual.motion(t)
    direct = compute_platform_motion(dual.spec, t[-3:], static.angle_rad[-3:],
                                     static.rate_rps[-3:], static.accel_rps2[-3:])
    np.testing.assert_allclose(static.rot_tp[-3:].as_quat(), direct.rot_tp.as_quat(), atol=1e-15)


# --- bad input ------------------------------------------------------------------------------
def test_bad_inputs():
    table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("lab"))
    with pytest.raises(LimitExceededError, match=r"axis 'pitch': rate .* exceeds the limit"):
        table.command_rate("pitch", 600 * DEG, 0.0)
    with pytest.raises(LimitExceededError, match=r"acceleration .* exceeds the limit"):
        table.command_rate("roll", 1.0, 0.0, accel_rps2=1e3)
    with pytest.raises(InvalidInputError, match=r"`axis` must be an index in 0..1 or a name"):
        table.command_position("yaw", 1.0, 0.0)
    with pytest.raises(InvalidInputError, match="`axis` must be"):
        table.command_position(2, 1.0, 0.0)
    with pytest.raises(InvalidInputError, match="`angle_rad` must be finite"):
        table.command_position(0, float("nan"), 0.0)
    table.command_position(0, 1.0, 10.0)
    with pytest.raises(InvalidInputError, match=r"non-decreasing time.*at_time_s=5"):
        table.command_rate(1, 0.1, 5.0)
    with pytest.raises(ConfigurationError, match="must be a unit vector; got norm 2"):
        AxisSpec("x", np.array([2.0, 0.0, 0.0]))
    with pytest.raises(ConfigurationError, match="axis names must be unique"):
        RateTableSpec(axes=(AxisSpec.ideal("a", [0, 0, 1]), AxisSpec.ideal("a", [1, 0, 0])))
    limited = SimRateTable(RateTableSpec.single_axis("ideal", angle_limits_rad=(-1.0, 1.0)))
    with pytest.raises(LimitExceededError, match="outside the travel"):
        limited.command_position(0, 2.0, 0.0)
    with pytest.raises(ConfigurationError, match="`grade` must be one of"):
        RateTableSpec.single_axis("superb")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match=r"`time_s` must have shape \(n\)"):
        table.motion(np.zeros((2, 2)))
    with pytest.raises(InvalidInputError, match="`time_s` must be finite"):
        table.motion([0.0, float("nan")])


def test_the_twin_tables_turn_about_the_axes_the_analysis_assumes():
    """One geometry: the twin's presets take their axis directions from the conventions."""
    from imucalib.conventions import TABLE_AXIS_VECTORS
    from imucalib.sim.centrifuge import CentrifugeSpec

    specs = [RateTableSpec.dual_axis_pitch_roll(grade) for grade in ("ideal", "lab", "high")]
    specs += [RateTableSpec.single_axis(grade) for grade in ("ideal", "lab", "high")]
    specs.append(RateTableSpec(axes=(CentrifugeSpec().axis_spec(),)))
    for spec in specs:
        for ax in spec.axes:
            np.testing.assert_array_equal(ax.axis_vector, TABLE_AXIS_VECTORS[ax.name])
