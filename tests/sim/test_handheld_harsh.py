"""Harsh hand-held sessions on the twin (imucalib.sim.handheld items 4–7): turns of 90–180° about
any axis, knocked poses, large gyro biases, a narrow gyro range that clips, a warming IMU whose
truth follows its temperature, and the signed-count and imu_tk files read back."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.io.import_spec import read_imu_table
from imucalib.sim import HARSH, handheld_session, harsh_handheld_session, write_session_csv
from imucalib.units import DEG, G0_MPS2

UP_T = np.array([0.0, 0.0, 1.0])


@pytest.fixture(scope="module")
def harsh():
    # more bumps than the preset's, so that a short session surely has some
    return harsh_handheld_session("consumer", seed=7, n_poses=20, bump_probability=0.4)


def _rows(sess, start, stop):
    return (sess.time_s >= start) & (sess.time_s < stop)


def test_the_harsh_session_shape(harsh):
    turns = [r for r in harsh.rotations if not r.bump]
    bumps = [r for r in harsh.rotations if r.bump]
    assert len(turns) == 20 and 3 <= len(bumps) <= 14 and not harsh.full_turns
    assert len(harsh.statics) == 1 + 20 + len(bumps)
    assert harsh.statics[0].stop_time_s == 50.0
    for r in turns:
        assert 90.0 <= math.degrees(r.angle_rad) <= 180.0
        assert 1.0 <= r.stop_time_s - r.start_time_s <= 3.0
    for r in bumps:
        assert 1.0 <= math.degrees(r.angle_rad) <= 5.0
        assert 0.1 <= r.stop_time_s - r.start_time_s <= 0.3
    # a pose's statics (two when knocked) last 2–5 s together, less the jolt
    by_pose: dict[int, float] = {}
    for p in harsh.statics[1:]:
        by_pose[p.pose_index] = by_pose.get(p.pose_index, 0.0) + p.stop_time_s - p.start_time_s
    assert sorted(by_pose) == list(range(1, 21))
    assert all(1.7 <= d <= 5.0 for d in by_pose.values())
    # the attitude after each turn is the one before turned by φ about the start body axis
    for before, rot, after in zip(harsh.statics[:-1], harsh.rotations, harsh.statics[1:],
                                  strict=True):
        moved = before.rot_tb * type(before.rot_tb).from_rotvec(rot.rotvec_b_rad)
        assert np.degrees((moved.inv() * after.rot_tb).magnitude()) < 1e-9
        # the face is the body axis nearest the vertical
        i = int(np.argmax(np.abs(after.up_b)))
        assert after.face == ("+" if after.up_b[i] > 0 else "-") + "xyz"[i]
    # poses point everywhere: gravity seen from every octant's side on each axis
    ups = np.array([p.up_b for p in harsh.statics])
    assert (ups.max(axis=0) > 0.5).all() and (ups.min(axis=0) < -0.5).all()


def test_biases_range_and_warm_up_are_the_truth(harsh):
    bias_dps = np.degrees(harsh.model.gyro.bias)
    assert (np.abs(bias_dps) <= 5.0).all() and np.abs(bias_dps).max() > 1.0
    assert harsh.model.gyro_output.range == pytest.approx(500.0 * DEG)
    # T(t) = T0 + ΔT·(1 − e^(−t/τ)), as the temperature sensor reads it (1/256 °C steps)
    t = harsh.time_s
    expected = 25.0 + 4.0 * (1.0 - np.exp(-t / 300.0))
    assert np.abs(harsh.temperature_degc - expected).max() < 0.01
    assert harsh.model.gyro.temperature is not None  # its parameters follow the temperature


def _gyro_truth(params, omega_b, f_b):
    """y = b + (I + M)·ω + G·f of the truth's parameters (names of parameters_at)."""
    ax = "xyz"
    b = np.array([params[f"gyro_bias_{i}"] for i in ax])
    m = np.array([[params[f"gyro_M_{i}{j}"] for j in ax] for i in ax])
    g = np.array([[params[f"gyro_G_{i}{j}"] for j in ax] for i in ax])
    return b + (np.eye(3) + m) @ omega_b + g @ f_b


def test_a_static_holds_the_truth_at_its_temperature(harsh):
    # the output's mean over a static is the truth at the IMU's temperature then, applied to
    # the true input: the bias drifts with the warm-up
    site = harsh.site
    np.testing.assert_allclose([harsh.model.parameters_at(25.0)[f"gyro_bias_{i}"]
                                for i in "xyz"], harsh.model.gyro.bias, rtol=1e-12)
    for pose in (harsh.statics[0], harsh.statics[-1]):
        rows = _rows(harsh, pose.start_time_s, pose.stop_time_s)
        temp = float(np.mean(harsh.temperature_degc[rows]))
        omega_b = pose.rot_tb.inv().apply(site.earth_rate_t_rps)
        f_b = pose.up_b * site.local_gravity_mps2
        want = _gyro_truth(harsh.model.parameters_at(temp), omega_b, f_b)
        np.testing.assert_allclose(harsh.gyro_rps[rows].mean(axis=0), want, atol=0.05 * DEG)
    assert float(np.mean(harsh.temperature_degc[-100:])) > 25.5


def test_a_fast_turn_clips_at_the_gyro_range():
    sess = handheld_session("consumer", seed=11, n_poses=6, rotation_deg=(170.0, 180.0),
                            rotation_s=(0.5, 0.6), full_turns=False, gyro_range_dps=250.0,
                            tremor_deg=0.0, pause_probability=0.0)
    peak = np.abs(sess.true_rate_b_rps).max()
    assert peak > 400.0 * DEG                                   # the hand is faster …
    assert np.abs(sess.gyro_rps).max() <= 250.0 * DEG * 1.0001  # … than the part can tell


def test_the_gentle_session_is_unchanged_by_the_new_options():
    a = handheld_session("consumer", seed=5, n_poses=6)
    b = handheld_session("consumer", seed=5, n_poses=6, bump_probability=0.0, warmup_degc=0.0)
    np.testing.assert_array_equal(a.gyro_rps, b.gyro_rps)
    assert np.all(a.temperature_degc == a.temperature_degc[0])


def test_signed_counts_and_imu_tk_files_read_back(harsh, tmp_path):
    signed = write_session_csv(harsh, tmp_path / "signed.csv", layout="counts", signed=True)
    raw = np.array([[int(v) for v in line.split(";")]
                    for line in signed.path.read_text().splitlines()[3:]])
    assert raw[:, 1:].min() < 0 and raw[:, 1:].max() < 32768
    df = read_imu_table(signed.path, signed.spec)
    gyro = df[["gyro_x_rps", "gyro_y_rps", "gyro_z_rps"]].to_numpy()
    accel = df[["accel_x_mps2", "accel_y_mps2", "accel_z_mps2"]].to_numpy()
    assert np.abs(gyro - harsh.gyro_rps).max() <= np.radians(0.5 / 65.5) * (1 + 1e-9)
    # ±2 g: a knock or a fast turn's centripetal part may clip the accelerometer codes
    inside = np.abs(harsh.accel_mps2).max(axis=1) < 1.99 * G0_MPS2
    assert np.abs(accel - harsh.accel_mps2)[inside].max() <= 0.5 / 16384 * G0_MPS2 * (1 + 1e-9)
    tk = write_session_csv(harsh, tmp_path / "gyro.txt", layout="imu_tk")
    assert tk.spec.accel_file == tmp_path / "gyro_acc.txt"
    assert len(tk.path.read_text().splitlines()[0].split(" ")) == 4
    df = read_imu_table(tk.path, tk.spec)
    assert df.attrs["layout"] == "imu_tk"
    np.testing.assert_allclose(df[["gyro_x_rps", "gyro_y_rps", "gyro_z_rps"]].to_numpy(),
                               harsh.gyro_rps, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(df[["accel_x_mps2", "accel_y_mps2", "accel_z_mps2"]].to_numpy(),
                               harsh.accel_mps2, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"rotation_deg": (90.0, 200.0)}, "within 180"),
    ({"bump_probability": 1.5}, "bump_probability"),
    ({"gyro_bias_dps": -1.0}, "gyro_bias_dps"),
    ({"warmup_tau_s": 0.0}, "warmup_tau_s"),
])
def test_bad_harsh_arguments_are_named(kwargs, message):
    with pytest.raises(InvalidInputError, match=message):
        handheld_session("consumer", seed=1, **kwargs)


def test_the_preset_is_what_the_docs_say():
    assert HARSH["n_poses"] == 40 and HARSH["rotation_deg"] == (90.0, 180.0)
    assert HARSH["init_static_s"] == 50.0 and HARSH["gyro_bias_dps"] == 5.0
