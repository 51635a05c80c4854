"""The field calibration against imu_tk's published method, written here as a plain fit.

imu_tk (Tedaldi, Pretto & Menegatti, ICRA 2014) fits the accelerometer by unweighted
Levenberg–Marquardt on g − ‖T·K·(y − b)‖ over the static poses, then the gyro's nine
scale/misalignment numbers by unweighted Levenberg–Marquardt on the change of the (calibrated)
gravity direction between consecutive poses, integrating the gyro corrected with the bias of
the initial static interval. It reports no uncertainty. The reference below is that method,
given the same static intervals and rotations as imucalib's analysis, so that the differences
come from the estimators alone. (imucal's Ferraris procedure is the known-angle form, tested
in tests/estimation/test_gyro_rotations.py as the closed form of turns.)
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from imucalib.estimation.gravity_norm import correct_accel
from imucalib.procedures.common.static_intervals import FieldLog
from imucalib.procedures.field.analysis import FieldOptions, analyze_field
from imucalib.procedures.field.result import accel_matrix
from imucalib.sim import handheld_session

from ._field_twin import field_truth


def _imu_tk_accel(y: np.ndarray, g: float) -> np.ndarray:
    sol = least_squares(lambda p: g - np.linalg.norm(correct_accel(p, y), axis=1), np.zeros(9),
                        method="lm", xtol=1e-14, ftol=1e-14)
    return np.asarray(sol.x)


def _product(q: np.ndarray) -> np.ndarray:
    """q_0·q_1·…·q_{n−1} of unit quaternions (x, y, z, w), by pairwise reduction."""
    while len(q) > 1:
        if len(q) % 2:
            q = np.vstack([q, [0.0, 0.0, 0.0, 1.0]])
        a, b = q[0::2], q[1::2]
        q = np.column_stack([
            a[:, 3] * b[:, 0] + a[:, 0] * b[:, 3] + a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
            a[:, 3] * b[:, 1] - a[:, 0] * b[:, 2] + a[:, 1] * b[:, 3] + a[:, 2] * b[:, 0],
            a[:, 3] * b[:, 2] + a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0] + a[:, 2] * b[:, 3],
            a[:, 3] * b[:, 3] - a[:, 0] * b[:, 0] - a[:, 1] * b[:, 1] - a[:, 2] * b[:, 2]])
    return q[0]


def _imu_tk_gyro(session, result, theta_a: np.ndarray) -> np.ndarray:
    """M of (I + M)⁻¹·(y − b_init), b_init the mean of the initial static interval."""
    t, gyro = session.time_s, session.gyro_rps
    first = result.poses[0]
    b0 = gyro[(t >= first["start_time_s"]) & (t <= first["end_time_s"])].mean(axis=0)
    up = [correct_accel(theta_a, p["accel_mean_mps2"])[0] for p in result.poses]
    up = [u / np.linalg.norm(u) for u in up]
    segments = []
    for row in result.rotations:
        keep = (t >= row["start_time_s"]) & (t <= row["end_time_s"])
        segments.append((t[keep], gyro[keep] - b0, up[row["pose_before"]],
                         up[row["pose_after"]]))

    def residual(m: np.ndarray) -> np.ndarray:
        inv = np.linalg.inv(np.eye(3) + m.reshape(3, 3))
        out = []
        for ts, y, u0, u1 in segments:
            w = y @ inv.T
            phi = 0.5 * (w[1:] + w[:-1]) * np.diff(ts)[:, None]
            r = Rotation.from_quat(_product(Rotation.from_rotvec(phi).as_quat()))
            out.append(u1 - r.inv().apply(u0))
        return np.concatenate(out)

    return np.asarray(least_squares(residual, np.zeros(9), method="lm").x)


def test_imucalib_agrees_with_the_imu_tk_method_where_its_model_holds_and_beats_it_where_not():
    # a unit whose truth holds no term imu_tk lacks (no K2, no gyro g-sensitivity)
    s = handheld_session("tactical", seed=61, noise="white",
                         errors={"accel.k2": [0.0, 0.0, 0.0],
                                 "gyro.g_sensitivity": [[0.0] * 3] * 3})
    log = FieldLog("IMU", "twin", s.time_s, s.gyro_rps, s.accel_mps2)
    ours = analyze_field(log, FieldOptions(latitude_deg=s.site.latitude_deg, accel_k2="no",
                                           gyro_g_sensitivity="no", gyro_form="gravity"))
    y = np.array([p["accel_mean_mps2"] for p in ours.poses])
    ref_a = _imu_tk_accel(y, ours.gravity_mps2)
    cal = ours.result
    std = cal.std(scaled=True)
    for i, a in enumerate("xyz"):
        assert abs(ref_a[i] - cal.value(f"accel_bias_{a}")) < 0.5 * std[f"accel_bias_{a}"]
    ref_m = accel_matrix(ref_a) - np.eye(3)
    for i, a in enumerate("xyz"):
        for j, b in enumerate("xyz"):
            n = f"accel_M_{a}{b}"
            if std[n] > 0:
                assert abs(ref_m[i, j] - cal.value(n)) < 0.5 * std[n], n
    ref_g = _imu_tk_gyro(s, ours, np.asarray(ours.details["accel_values"]))
    ours_g = np.array([cal.value(f"gyro_M_{a}{b}") for a in "xyz" for b in "xyz"])
    sg = np.array([std[f"gyro_M_{a}{b}"] for a in "xyz" for b in "xyz"])
    # the reference is the less efficient estimate (unweighted, the Earth's rate ignored,
    # one bias): it differs from imucalib's by up to 2.4σ here (seeds 61, 63, 64: its error
    # RMS 1.2σ against imucalib's 0.7σ)
    assert np.all(np.abs(ref_g - ours_g) < 3.0 * sg)
    truth = field_truth(s.model)
    tg = np.array([truth[f"gyro_M_{a}{b}"] for a in "xyz" for b in "xyz"])
    assert np.all(np.abs(ours_g - tg) < 4 * sg)

    # a consumer unit with K2 and a g-sensitive gyro: imu_tk's model misses both
    s = handheld_session("consumer", seed=62, noise="white")
    log = FieldLog("IMU", "twin", s.time_s, s.gyro_rps, s.accel_mps2)
    ours = analyze_field(log, FieldOptions(latitude_deg=s.site.latitude_deg,
                                           gyro_form="gravity"))
    cal = ours.result
    truth = field_truth(s.model)
    ref_a = _imu_tk_accel(np.array([p["accel_mean_mps2"] for p in ours.poses]),
                          ours.gravity_mps2)
    names = [f"accel_bias_{a}" for a in "xyz"]
    ours_err = np.array([cal.value(n) - truth[n] for n in names])
    ref_err = ref_a[:3] - np.array([truth[n] for n in names])
    std = cal.std(scaled=True)
    assert np.all(np.abs(ours_err) < 4 * np.array([std[n] for n in names]))
    assert np.linalg.norm(ref_err) > 3 * np.linalg.norm(ours_err)
    ref_g = _imu_tk_gyro(s, ours, np.asarray(ours.details["accel_values"]))
    names = [f"gyro_M_{a}{b}" for a in "xyz" for b in "xyz"]
    tg = np.array([truth[n] for n in names])
    ours_g = np.array([cal.value(n) for n in names])
    assert np.linalg.norm(ref_g - tg) > 2 * np.linalg.norm(ours_g - tg)


def test_imucalib_against_imucal_s_ferraris_calibration_on_a_fixture_session():
    """imucal (a dev dependency) implements Ferraris et al. (1995) for one record per face and
    one turn per axis: the six-position form and the known-angle turns. On such a session
    (faces exact, turns flat, no K2 in the truth: imucal has none) the accelerometer's M agree
    within 2σ (the same ± differences; imucal uses one visit per face, imucalib every pose),
    while imucal's gyro bias, which ignores the Earth's rate (and takes one mean over unequal
    poses), and its gyro M are far off where imucalib's are within 4σ. With the consumer's K2
    in the truth imucal's accelerometer biases are 40–80σ off (imucalib fits K2)."""
    from imucal import FerrarisCalibration, FerrarisSignalRegions

    s = handheld_session("consumer", seed=6, noise="white", n_poses=6, off_axis_deg=(0.0, 0.0),
                         level_tilt_deg=0.0, errors={"accel.k2": [0.0, 0.0, 0.0]})
    log = FieldLog("IMU", "twin", s.time_s, s.gyro_rps, s.accel_mps2)
    ours = analyze_field(log, FieldOptions(latitude_deg=s.site.latitude_deg,
                                           accel_form="six-position", gyro_form="turns"))
    t = s.time_s
    regions: dict[str, np.ndarray] = {}
    first = {}
    for pose in s.statics[1:]:
        first.setdefault(pose.face, pose)
    for axis in "xyz":
        for sign, tag in (("+", "p"), ("-", "a")):
            pose = first[sign + axis]
            keep = (t >= pose.start_time_s + 0.5) & (t <= pose.stop_time_s - 0.5)
            regions[f"acc_{axis}_{tag}"] = s.accel_mps2[keep]
            regions[f"gyr_{axis}_{tag}"] = np.degrees(s.gyro_rps[keep])
    for turn in (r for r in s.rotations if r.full_turn and r.angle_rad > 0):
        axis = "xyz"[int(np.argmax(np.abs(turn.rotvec_b_rad)))]
        keep = (t >= turn.start_time_s - 0.2) & (t <= turn.stop_time_s + 0.2)
        regions[f"acc_{axis}_rot"] = s.accel_mps2[keep]
        regions[f"gyr_{axis}_rot"] = np.degrees(s.gyro_rps[keep])
    info = FerrarisCalibration(grav=ours.gravity_mps2, expected_angle=360.0).compute(
        FerrarisSignalRegions(**regions), s.sample_rate_hz, "m/s^2", "deg/s")
    cal = ours.result
    std = cal.std(scaled=True)
    truth = field_truth(s.model, six_position=True)
    z = {n: (cal.value(n) - truth[n]) / std[n] for n in cal.param_names if std[n] > 0}
    assert max(abs(v) for v in z.values()) < 4.0
    accel_m = info.K_a @ info.R_a - np.eye(3)
    diff = [abs(accel_m[i, j] - cal.value(f"accel_M_{a}{b}")) / std[f"accel_M_{a}{b}"]
            for i, a in enumerate("xyz") for j, b in enumerate("xyz")]
    assert max(diff) < 2.0                  # measured 0.36 (seeds 5–7: 0.82, 0.36, 0.42)
    gyro_b = np.radians(np.asarray(info.b_g))
    ours_b = np.array([cal.value(f"gyro_bias_{a}") for a in "xyz"])
    true_b = np.array([truth[f"gyro_bias_{a}"] for a in "xyz"])
    assert np.linalg.norm(gyro_b - true_b) > 5 * np.linalg.norm(ours_b - true_b)
    gyro_m = (info.K_g @ info.R_g - np.eye(3)).ravel()
    names = [f"gyro_M_{a}{b}" for a in "xyz" for b in "xyz"]
    true_m = np.array([truth[n] for n in names])
    ours_m = np.array([cal.value(n) for n in names])
    assert np.linalg.norm(gyro_m - true_m) > 2 * np.linalg.norm(ours_m - true_m)
