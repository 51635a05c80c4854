"""Hand-held sessions on the twin (imucalib.sim.handheld): the motion is exactly the attitude's,
statics are still, full turns are ±2π about the vertical, the outputs are the truth model's, the
variance detector finds every pose, and the CSVs a user would have read back."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.io.import_spec import read_imu_table
from imucalib.models.triad import apply_triad
from imucalib.processing.static_detector import detect_static_and_rotations
from imucalib.sim import handheld_session, write_session_csv
from imucalib.units import G0_MPS2

SEED = 20261127
UP_T = np.array([0.0, 0.0, 1.0])
AXES = {"+x": [1, 0, 0], "-x": [-1, 0, 0], "+y": [0, 1, 0], "-y": [0, -1, 0], "+z": [0, 0, 1],
        "-z": [0, 0, -1]}


@pytest.fixture(scope="module")
def session():
    return handheld_session("consumer", seed=SEED)


@pytest.fixture(scope="module")
def white():
    return handheld_session("consumer", seed=SEED + 1, noise="white", n_poses=12)


def _rows(sess, start, stop):
    return (sess.time_s >= start) & (sess.time_s < stop)


def test_the_same_seed_gives_the_same_session(session):
    again = handheld_session("consumer", seed=SEED)
    other = handheld_session("consumer", seed=SEED + 7)
    assert np.array_equal(again.gyro_rps, session.gyro_rps)
    assert np.array_equal(again.accel_mps2, session.accel_mps2)
    assert np.array_equal(again.model.gyro.bias, session.model.gyro.bias)
    assert [p.start_time_s for p in again.statics] == [p.start_time_s for p in session.statics]
    assert not np.array_equal(other.model.accel.bias, session.model.accel.bias)
    assert len(other) != len(session) or not np.array_equal(other.gyro_rps, session.gyro_rps)
    # the truth at the samples is the motion's, evaluated again at any time
    kin = session.kinematics(session.time_s)
    np.testing.assert_array_equal(kin.rate_b_rps, session.true_rate_b_rps)
    np.testing.assert_array_equal(kin.specific_force_b_mps2, session.true_specific_force_b_mps2)


def test_the_session_shape(session):
    # initial rest, 18 poses, three of them with a static after each of their two turns
    assert len(session.statics) == 1 + 18 + 6
    assert len(session.rotations) == len(session.statics) - 1
    assert session.statics[0].pose_index == 0
    assert session.statics[0].stop_time_s - session.statics[0].start_time_s == 10.0
    for before, rot, after in zip(session.statics[:-1], session.rotations, session.statics[1:],
                                  strict=True):
        assert before.stop_time_s == rot.start_time_s and rot.stop_time_s == after.start_time_s
        assert 1.5 <= rot.stop_time_s - rot.start_time_s <= (8.0 if rot.full_turn else 4.0)
    for pose in session.statics[1:]:
        assert 4.0 <= pose.stop_time_s - pose.start_time_s <= 8.0
    assert session.time_s[1] - session.time_s[0] == pytest.approx(0.01)
    moves = [len(seg.moves) for seg in session.motion.segments if not seg.is_static]
    assert set(moves) == {1, 2}  # some rotations pause halfway
    assert session.time_s[-1] < session.motion.duration_s <= session.time_s[-1] + 0.01


def test_statics_are_truly_still(session):
    site = session.site
    g = site.local_gravity_mps2
    for pose in session.statics:
        rows = _rows(session, pose.start_time_s, pose.stop_time_s)
        earth_b = pose.rot_tb.inv().apply(site.earth_rate_t_rps)
        np.testing.assert_allclose(session.true_rate_b_rps[rows], np.tile(earth_b, (rows.sum(), 1)),
                                   rtol=0, atol=1e-15)
        force = session.true_specific_force_b_mps2[rows]
        assert np.abs(np.linalg.norm(force, axis=1) - g).max() < 1e-9
        np.testing.assert_allclose(force, np.tile(g * pose.up_b, (rows.sum(), 1)), atol=1e-9)
        assert np.linalg.norm(pose.up_b) == pytest.approx(1.0, abs=1e-12)


def test_poses_cycle_the_faces_within_their_tilt_range(session):
    poses = {p.pose_index: p for p in session.statics}
    assert [poses[k].face for k in range(1, 19)] == ["+x", "-x", "+y", "-y", "+z", "-z"] * 3
    turned = {session.statics[i].pose_index for i, r in enumerate(session.rotations)
              if r.full_turn}
    assert {poses[k].face for k in turned} == {"+x", "+y", "+z"}
    headings = []
    for k, pose in poses.items():
        axis_t = pose.rot_tb.apply(AXES[pose.face])
        tilt = np.degrees(np.arccos(np.clip(axis_t @ UP_T, -1, 1)))
        assert tilt == pytest.approx(pose.tilt_deg, abs=1e-9)
        if k == 0 or k in turned:
            assert tilt < 3.0
        else:
            assert 5.0 <= tilt <= 30.0
        headings.append(pose.rot_tb.as_euler("ZYX")[0])
    assert np.ptp(headings) > np.pi  # random headings


def _integrated_attitude(motion, t0, t1, h=2e-4):
    """Integrate the motion's own rate: per step the rotation vector of a 4th-order Magnus
    expansion (Simpson's rule plus the commutator term), composed in a balanced tree."""
    n = int(np.ceil((t1 - t0) / h))
    t = np.linspace(t0, t1, n + 1)
    _, w, _ = motion.evaluate(t)
    _, wm, _ = motion.evaluate(0.5 * (t[1:] + t[:-1]))
    step = t[1] - t[0]
    theta = step / 6.0 * (w[:-1] + 4.0 * wm + w[1:]) + step**2 / 12.0 * np.cross(w[:-1], w[1:])
    rots = Rotation.from_rotvec(theta)
    while len(rots) > 1:
        if len(rots) % 2:
            rots = Rotation.concatenate([rots, Rotation.identity()])
        rots = rots[0::2] * rots[1::2]
    return rots[0]


def test_the_rate_integrates_to_each_attitude_change(session):
    worst = 0.0
    for before, rot, after in zip(session.statics[:-1], session.rotations,
                                  session.statics[1:], strict=True):
        change = before.rot_tb.inv() * after.rot_tb
        integrated = _integrated_attitude(session.motion, rot.start_time_s, rot.stop_time_s)
        worst = max(worst, (integrated.inv() * change).magnitude())
        if not rot.full_turn:  # the shortest arc
            np.testing.assert_allclose(change.as_rotvec(), rot.rotvec_b_rad, atol=1e-12)
            assert rot.angle_rad == pytest.approx(np.linalg.norm(rot.rotvec_b_rad))
    assert worst < 1e-6
    print(f"worst attitude error {worst:.2e} rad")


def test_the_angular_acceleration_is_the_rate_derivative(session):
    rot = next(r for r in session.rotations if not r.full_turn)
    t = np.linspace(rot.start_time_s - 0.2, rot.stop_time_s + 0.2, 20001)
    _, w, a = session.motion.evaluate(t)
    numeric = np.gradient(w, t, axis=0)
    assert np.abs(numeric - a)[1:-1].max() < 1e-3 * np.abs(a).max()
    assert np.abs(a).max() > 1.0  # a hand's motion, tremor included
    # rate and acceleration start and end at zero: statics stay static
    _, w_end, a_end = session.motion.evaluate(np.array([rot.start_time_s, rot.stop_time_s]))
    assert np.abs(w_end).max() < 1e-12 and np.abs(a_end).max() < 1e-9


def test_full_turns_are_two_pi_about_the_vertical(session):
    turns = session.full_turns
    assert [np.sign(r.angle_rad) for r in turns] == [1, -1] * 3
    for i, rot in enumerate(session.rotations):
        if not rot.full_turn:
            continue
        before, after = session.statics[i], session.statics[i + 1]
        assert (before.rot_tb.inv() * after.rot_tb).magnitude() < 1e-12
        assert abs(rot.angle_rad) == pytest.approx(2 * np.pi, abs=1e-12)
        np.testing.assert_allclose(rot.rotvec_b_rad, rot.angle_rad * before.up_b, atol=1e-12)
        # the plain integral of the rate is the rotation vector (the tremor is about the same axis)
        t = np.linspace(rot.start_time_s, rot.stop_time_s, 40001)
        _, w, _ = session.motion.evaluate(t)
        integral = np.trapezoid(w, t, axis=0)
        np.testing.assert_allclose(integral, rot.rotvec_b_rad, atol=1e-6)
        assert np.degrees(np.abs(before.up_b @ UP_T)) > 0  # level: the up axis is the face's
        face_axis = np.array(AXES[before.face], dtype=float)
        assert np.degrees(np.arccos(before.up_b @ face_axis)) < 3.0


def test_outputs_are_the_truth_model_within_the_white_noise(white):
    model = white.model
    n_gyro = model.gyro_noise.white_density
    n_accel = model.accel_noise.white_density
    lsb_g, lsb_a = model.gyro_output.effective_lsb, model.accel_output.effective_lsb
    z = []
    for pose in white.statics:
        rows = _rows(white, pose.start_time_s + 0.2, pose.stop_time_s - 0.2)
        n = rows.sum()
        dur = n / white.sample_rate_hz
        w, f = white.true_rate_b_rps[rows], white.true_specific_force_b_mps2[rows]
        gyro_true = apply_triad(model.gyro, w, specific_force_b_mps2=f).mean(axis=0)
        accel_true = apply_triad(model.accel, f, rate_b_rps=w,
                                 angular_accel_b_rps2=np.zeros_like(w)).mean(axis=0)
        sig_g = np.sqrt(n_gyro**2 / dur + lsb_g**2 / 12 / n)
        sig_a = np.sqrt(n_accel**2 / dur + lsb_a**2 / 12 / n)
        z.extend((white.gyro_rps[rows].mean(axis=0) - gyro_true) / sig_g)
        z.extend((white.accel_mps2[rows].mean(axis=0) - accel_true) / sig_a)
    z = np.asarray(z)
    print(f"{z.size} normalised residuals: std {z.std():.3f}, max |z| {np.abs(z).max():.2f}")
    assert np.abs(z).max() < 4.0
    assert 0.7 < z.std() < 1.3  # the spread is the noise's, not a looser bound
    # and the errors are there: a consumer gyro's bias is far above that noise
    assert np.abs(model.gyro.bias).max() > 100 * n_gyro.max() / np.sqrt(4.0)


def test_the_variance_detector_finds_every_static_pose(session):
    res = detect_static_and_rotations(session.time_s, session.gyro_rps, session.accel_mps2,
                                      init_static_s=8.0)
    assert len(res.static) == len(session.statics)
    two_samples = 2.0 / session.sample_rate_hz
    for found, true in zip(res.static, session.statics, strict=True):
        # inside the true interval, but for a sample or two where the hand has barely started
        assert true.start_time_s - two_samples <= found.start_time_s
        assert found.end_time_s <= true.stop_time_s + two_samples
        assert found.end_time_s - found.start_time_s > 0.8 * (true.stop_time_s
                                                              - true.start_time_s) - 0.5
        rot, _, _ = session.motion.evaluate(session.time_s[found.start_index:found.stop_index])
        assert np.degrees((true.rot_tb.inv() * rot).magnitude()).max() < 1e-4
    # the full turns, as the gyro sees them: ‖(I + M)·φ‖, M the true scale and misalignment
    gain = np.eye(3) + session.model.gyro.scale_misalignment
    turns = [(found, true) for found, true in zip(res.rotations, session.rotations, strict=True)
             if true.full_turn]
    assert len(turns) == 6
    for found, true in turns:
        assert np.degrees(found.angle_norm_rad) == pytest.approx(
            np.degrees(np.linalg.norm(gain @ true.rotvec_b_rad)), abs=0.5)


def test_the_imucal_csv_reads_back_with_no_options(session, tmp_path):
    out = write_session_csv(session, tmp_path / "hand.csv")
    assert out.cli_args == ()
    assert out.path.read_text().splitlines()[0] == "t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z"
    df = read_imu_table(out.path, out.spec)
    assert df.attrs["layout"] == "imucal"
    np.testing.assert_allclose(df.index.to_numpy(), session.time_s, atol=1e-9)
    np.testing.assert_allclose(df[["gyro_x_rps", "gyro_y_rps", "gyro_z_rps"]].to_numpy(),
                               session.gyro_rps, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(df[["accel_x_mps2", "accel_y_mps2", "accel_z_mps2"]].to_numpy(),
                               session.accel_mps2, rtol=1e-9, atol=1e-12)


def test_the_counts_csv_reads_back_within_one_count(session, tmp_path):
    out = write_session_csv(session, tmp_path / "raw.txt", layout="counts")
    lines = out.path.read_text().splitlines()
    assert lines[0].startswith("#") and lines[2] == "sample;gx;gy;gz;ax;ay;az"
    raw = np.array([[int(v) for v in line.split(";")] for line in lines[3:6]])
    assert raw[:, 0].tolist() == [0, 1, 2] and (raw[:, 1:] > 0).all()
    df = read_imu_table(out.path, out.spec)
    np.testing.assert_allclose(df.index.to_numpy(), session.time_s, atol=1e-9)
    gyro = df[["gyro_x_rps", "gyro_y_rps", "gyro_z_rps"]].to_numpy()
    accel = df[["accel_x_mps2", "accel_y_mps2", "accel_z_mps2"]].to_numpy()
    half_g = np.radians(0.5 / 65.5)
    half_a = 0.5 / 16384 * G0_MPS2
    assert np.abs(gyro - session.gyro_rps).max() <= half_g * (1 + 1e-9)
    assert np.abs(accel - session.accel_mps2).max() <= half_a * (1 + 1e-9)
    assert np.abs(gyro - session.gyro_rps).max() > 0.4 * half_g  # it is quantised


def test_the_cli_segments_both_files_into_the_true_poses(session, tmp_path):
    runner = CliRunner()
    for layout in ("imucal", "counts"):
        out = write_session_csv(session, tmp_path / f"{layout}.csv", layout=layout)
        doc = tmp_path / f"{layout}.json"
        res = runner.invoke(app, ["segments", str(out.path), *out.cli_args, "--detector",
                                  "variance", "--init-static-s", "8", "--json", str(doc)])
        assert res.exit_code == 0, res.output
        segs = json.loads(doc.read_text())["segments"]
        assert sum(s["kind"] == "static" for s in segs) == len(session.statics)


def test_injected_errors_are_the_truth():
    sess = handheld_session("tactical", seed=3, n_poses=6, full_turns=False,
                            errors={"gyro.bias": [1e-3, -2e-3, 3e-3]})
    np.testing.assert_array_equal(sess.model.gyro.bias, [1e-3, -2e-3, 3e-3])
    assert len(sess.statics) == 7 and not sess.full_turns


@pytest.mark.parametrize(("kwargs", "error", "message"), [
    ({"n_poses": 5}, InvalidInputError, "every face up once"),
    ({"off_axis_deg": (30.0, 5.0)}, InvalidInputError, "off_axis_deg"),
    ({"off_axis_deg": (5.0, 95.0)}, InvalidInputError, "below 90"),
    ({"errors": {"gyro.nonsense": [0, 0, 0]}}, InvalidInputError, "nonsense"),
    ({"noise": "pink"}, ConfigurationError, "'grade' or 'white'"),
])
def test_bad_arguments_are_named(kwargs, error, message):
    with pytest.raises(error, match=message):
        handheld_session("consumer", seed=1, **kwargs)


def test_an_unknown_grade_and_layout_are_named(session, tmp_path):
    with pytest.raises(ConfigurationError, match="unknown IMU grade"):
        handheld_session("toy", seed=1)
    with pytest.raises(InvalidInputError, match="layout"):
        write_session_csv(session, tmp_path / "x.csv", layout="xml")  # type: ignore[arg-type]
