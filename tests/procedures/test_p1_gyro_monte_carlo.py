"""Monte Carlo on the twin for the gyro triad: bias, 3×3 scale/misalignment and g-sensitivity.

The gyro counterpart of ``test_p1_monte_carlo.py``. Each run draws a new tactical IMU truth
(gyro bias, scale/misalignment and g-sensitivity G) and new white gyro noise, then runs the P1
gyro design on an ideal dual-axis table of the twin: the six static positions (Earth rate and
gravity as references) and rates of ±60 °/s about pitch (body Y), roll (body X) and pitch with
roll at 90° (body Z), each averaged over whole revolutions of the twin's own table angle. The
windows are fitted with the P1 triad fit (21 parameters) weighted by the white-noise standard
error of each window. Over 400 runs: every estimate within 4.5σ of its truth, and the reported
σ within 10 % of the Monte-Carlo spread (pooled per parameter group), so the fit's covariance
is the uncertainty the gyro results really have.

Why 400: the pooled bias ratio has a sampling error of 1/√(2·3·N) (2.9 % at 200 runs). Seeds
0–199 alone give 1.10 for the biases (a 3.5σ excursion; seeds 200–399, 400–599 and 600–799 give
0.99, 1.00 and 0.98), so 200 runs left the 10 % check at the mercy of one draw.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib import units
from imucalib.conventions import TABLE_AXIS_VECTORS
from imucalib.models import ImuModel, NoiseModel, TriadModel, sample_imu_model
from imucalib.procedures.p1.fit import fit_triad
from imucalib.procedures.p1.observations import (
    WindowObservation,
    site_vectors,
    table_rotation,
)
from imucalib.procedures.p1.plan import P1_SIX_POSITIONS_DEG
from imucalib.processing import compute_integer_revolution_window
from imucalib.sim import Site, TwinRig, single_imu_fixture
from imucalib.sim.synth import SimImu
from imucalib.sim.table import RateTableSpec, SimRateTable

N_RUNS = 400
FS_HZ = 100.0
STATIC_S = 10.0
RATE_DPS = 60.0
REVOLUTIONS = 2
ARW_RPS_RTHZ = 0.05 * units.DEG / 60.0  # 0.05 °/√h as a one-sided density [(rad/s)/√Hz]
SITE = Site(latitude_deg=45.0)
AXES = ("pitch", "roll")
# rate groups: (table axis, roll angle held [°], body axis turned)
RATE_GROUPS = ((0, 0.0, "Y"), (1, 0.0, "X"), (0, 90.0, "Z"))


def _window(label: str, kind: str, gyro_mean: np.ndarray, se: float, rate_b: np.ndarray,
            force_b: np.ndarray, angles: np.ndarray, table_rate: float, n: int,
            duration: float) -> WindowObservation:
    z3 = np.zeros(3)
    return WindowObservation(
        step_index=0, plan_step=0, kind=kind, role="calibration", repetition=1,
        tags=("six-position",) if kind == "static" else ("rate",), label=label,
        gyro_mean_rps=gyro_mean, accel_mean_mps2=z3, gyro_se_rps=np.full(3, se),
        accel_se_mps2=np.ones(3), gyro_std_rps=z3, accel_std_mps2=z3, rate_b_rps=rate_b,
        force_b_mps2=force_b, angles_rad=angles, table_rate_rps=table_rate,
        axis=None, n_samples=n, n_outliers=0, n_revolutions=REVOLUTIONS if kind == "rate" else 0,
        alignment_error_s=0.0, duration_s=duration)


def one_run(seed: int) -> tuple[np.ndarray, np.ndarray]:
    truth = sample_imu_model("tactical", rng=seed, nonlinear=False)
    gyro = TriadModel(kind="gyro", bias=truth.gyro.bias,
                      scale_misalignment=truth.gyro.scale_misalignment,
                      g_sensitivity=truth.gyro.g_sensitivity)
    model = ImuModel(gyro=gyro, accel=TriadModel.ideal("accel"),
                     gyro_noise=NoiseModel(white_density=ARW_RPS_RTHZ), sample_rate_hz=FS_HZ)
    table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("ideal"))
    rig = TwinRig(site=SITE, fixture=single_imu_fixture(name="u"), imus=[SimImu("u", model)],
                  table=table, rng=seed)
    g, earth_t = site_vectors(SITE.latitude_deg, SITE.heading_deg, SITE.gravity_mps2)
    gravity_t = np.array([0.0, 0.0, g])
    windows: list[WindowObservation] = []
    t = 0.0
    for (pitch, roll), label in P1_SIX_POSITIONS_DEG:
        angles = np.radians([pitch, roll])
        table.command_position(0, angles[0], t)
        t_end = table.command_position(1, angles[1], t)
        rig.generate(t_end + 5.0)
        s = rig.generate(t_end + 5.0 + STATIC_S).imu["u"]
        t = t_end + 5.0 + STATIC_S
        rot = table_rotation(AXES, angles)
        windows.append(_window(label, "static", s.gyro_rps.mean(0),
                               ARW_RPS_RTHZ / math.sqrt(STATIC_S), rot.inv().apply(earth_t),
                               rot.inv().apply(gravity_t), angles, 0.0, len(s), STATIC_S))
    for axis, roll_deg, body in RATE_GROUPS:
        for sign in (1.0, -1.0):
            table.command_position(0, 0.0, t)
            t_end = table.command_position(1, math.radians(roll_deg), t)
            rate = sign * math.radians(RATE_DPS)
            t_spin = table.command_rate(axis, rate, t_end + 1.0)
            record_s = REVOLUTIONS * 360.0 / RATE_DPS + 1.0
            rig.generate(t_spin + 5.0)
            s = rig.generate(t_spin + 5.0 + record_s).imu["u"]
            t = t_spin + 5.0 + record_s
            table.command_rate(axis, 0.0, t)
            fb = table.feedback(s.time_s)
            win = compute_integer_revolution_window(s.time_s, s.gyro_rps,
                                                    angle_rad=fb.angle_rad[:, axis])
            assert win.n_revolutions == REVOLUTIONS
            held = np.array([0.0, math.radians(roll_deg)])
            inner = table_rotation(AXES[axis + 1:], held[axis + 1:])
            spin_t = np.asarray(TABLE_AXIS_VECTORS[AXES[axis]], dtype=float)
            a_b = inner.inv().apply(spin_t)
            a_t = table_rotation(AXES, held).apply(a_b)
            rate_b = (rate + float(earth_t @ a_t)) * a_b
            force_b = float(gravity_t @ a_t) * a_b
            n = win.stop_index - win.start_index
            windows.append(_window(f"{body} {sign:+.0f}", "rate", np.asarray(win.mean),
                                   ARW_RPS_RTHZ / math.sqrt(n / FS_HZ), rate_b, force_b, held,
                                   rate, n, n / FS_HZ))
    fit = fit_triad("gyro", windows, model="triad", g_sensitivity=True)
    true = np.r_[gyro.bias, gyro.scale_misalignment.ravel(), gyro.g_sensitivity.ravel()]
    return fit.estimate - true, np.sqrt(np.diag(fit.covariance))


def test_spin_axes_turn_the_body_axes_the_design_needs():
    """The rate groups turn body Y, X and Z (the reference rate is along that axis)."""
    for axis, roll_deg, body in RATE_GROUPS:
        held = np.array([0.0, math.radians(roll_deg)])
        inner = table_rotation(AXES[axis + 1:], held[axis + 1:])
        spin_t = np.asarray(TABLE_AXIS_VECTORS[AXES[axis]], dtype=float)
        a_b = inner.inv().apply(spin_t)
        assert np.abs(a_b)["XYZ".index(body)] == pytest.approx(1.0, abs=1e-12)


@pytest.mark.slow
def test_gyro_reported_sigma_matches_the_monte_carlo_spread():
    errors, sigmas = [], []
    for seed in range(N_RUNS):
        err, sig = one_run(seed)
        errors.append(err)
        sigmas.append(sig)
    errors, sigmas = np.array(errors), np.array(sigmas)
    z = errors / sigmas
    assert np.abs(z).max() < 4.5, np.abs(z).max()
    # pooled per group: bias (3), scale/misalignment (9), g-sensitivity (9); the relative
    # sampling error of a pooled spread over 400 runs is 1–2 %
    for name, sl in (("bias", slice(0, 3)), ("scale/misalignment", slice(3, 12)),
                     ("g-sensitivity", slice(12, 21))):
        ratio = math.sqrt(np.mean(z[:, sl] ** 2))
        assert abs(ratio - 1.0) < 0.10, (name, ratio)
    # each parameter alone within its sampling error (1/√(2·399) ≈ 3.5 %, 4σ: 14 %)
    spread = errors.std(axis=0, ddof=1)
    reported = sigmas.mean(axis=0)
    assert np.all(np.abs(spread / reported - 1.0) < 0.15), spread / reported
    # no bias: the mean error of every parameter is within 4 standard errors of zero
    assert np.all(np.abs(errors.mean(axis=0)) < 4 * reported / math.sqrt(N_RUNS))
