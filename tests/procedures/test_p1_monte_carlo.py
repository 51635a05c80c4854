"""Monte Carlo on the twin: reported uncertainty against the spread, and against the bound.

Six-position accelerometer design (docs/p1.md, step 1) on an ideal dual-axis table, IMUs with
white noise only (so that the closed-form Cramér–Rao bound of docs/equations.md §12 applies): each
run draws a new IMU truth and new noise, records 10 s per position, reduces the windows to
means and fits the full triad model with the P1 fitting code. Over 300 runs the normalised
errors must have unit spread (the reported σ within 10 % of the Monte-Carlo spread) and the
spread must equal σ/√6 for the biases and σ/(g√2) for scale and misalignment.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from imucalib import units
from imucalib.estimation import compute_six_position_accel_crlb
from imucalib.models import ImuModel, NoiseModel, TriadModel, sample_imu_model
from imucalib.procedures.p1.fit import fit_triad
from imucalib.procedures.p1.observations import WindowObservation, table_rotation
from imucalib.procedures.p1.plan import P1_SIX_POSITIONS_DEG
from imucalib.sim import Site, TwinRig, single_imu_fixture
from imucalib.sim.synth import SimImu
from imucalib.sim.table import RateTableSpec, SimRateTable

N_RUNS = 300
FS_HZ = 100.0
RECORD_S = 10.0
VRW_MPS2_RTS = 50.0 * units.UG_PER_RTHZ  # tactical accelerometer white noise
SITE = Site(latitude_deg=45.0)


def one_run(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    truth = sample_imu_model("tactical", rng=seed, nonlinear=False)
    accel = TriadModel(kind="accel", bias=truth.accel.bias,
                       scale_misalignment=truth.accel.scale_misalignment)
    model = ImuModel(gyro=TriadModel.ideal("gyro"), accel=accel,
                     accel_noise=NoiseModel(white_density=VRW_MPS2_RTS), sample_rate_hz=FS_HZ)
    table = SimRateTable(RateTableSpec.dual_axis_pitch_roll("ideal"))
    rig = TwinRig(site=SITE, fixture=single_imu_fixture(name="u"), imus=[SimImu("u", model)],
                  table=table, rng=seed)
    windows = []
    g = SITE.local_gravity_mps2
    t = 0.0
    se = VRW_MPS2_RTS / math.sqrt(RECORD_S)
    for (pitch, roll), label in P1_SIX_POSITIONS_DEG:
        angles = np.radians([pitch, roll])
        table.command_position(0, angles[0], t)
        t_end = table.command_position(1, angles[1], t)
        rig.generate(t_end + 5.0)  # move and settle
        s = rig.generate(t_end + 5.0 + RECORD_S).imu["u"]
        t = t_end + 5.0 + RECORD_S
        force = table_rotation(("pitch", "roll"), angles).inv().apply([0.0, 0.0, g])
        z3 = np.zeros(3)
        windows.append(WindowObservation(
            step_index=0, plan_step=0, kind="static", role="calibration", repetition=1,
            tags=("six-position",), label=label, gyro_mean_rps=z3,
            accel_mean_mps2=s.accel_mps2.mean(0),
            gyro_se_rps=np.ones(3), accel_se_mps2=np.full(3, se), gyro_std_rps=z3,
            accel_std_mps2=z3, rate_b_rps=z3, force_b_mps2=force, angles_rad=angles,
            table_rate_rps=0.0, axis=None, n_samples=len(s), n_outliers=0, n_revolutions=0,
            alignment_error_s=0.0, duration_s=RECORD_S))
    fit = fit_triad("accel", windows, model="triad")
    true = np.r_[accel.bias, accel.scale_misalignment.ravel()]
    return fit.estimate - true, np.sqrt(np.diag(fit.covariance)), np.asarray(fit.H)


@pytest.mark.slow
def test_reported_sigma_matches_the_monte_carlo_spread_and_the_bound():
    errors, sigmas = [], []
    for seed in range(N_RUNS):
        err, sig, _ = one_run(seed)
        errors.append(err)
        sigmas.append(sig)
    errors, sigmas = np.array(errors), np.array(sigmas)
    z = errors / sigmas
    spread = errors.std(axis=0, ddof=1)
    reported = sigmas.mean(axis=0)
    # every estimate within 4σ of its truth
    assert np.abs(z).max() < 4.5
    # reported σ within 10 % of the Monte-Carlo spread, pooled per kind (bias: 3 parameters,
    # scale/misalignment: 9; relative sampling error of a pooled spread ≈ 2–4 %)
    for sl in (slice(0, 3), slice(3, 12)):
        ratio = math.sqrt(np.mean(z[:, sl] ** 2))
        assert abs(ratio - 1.0) < 0.10, ratio
    # each parameter alone within its sampling error (1/√(2·299) ≈ 4 %, 4σ: 17 %)
    assert np.all(np.abs(spread / reported - 1.0) < 0.17), spread / reported
    # the spread equals the closed-form Cramér–Rao bound: σ/√6 (bias), σ/(g√2) (scale, mis.)
    bound = compute_six_position_accel_crlb(VRW_MPS2_RTS / math.sqrt(RECORD_S),
                                            gravity_mps2=SITE.local_gravity_mps2)
    np.testing.assert_allclose(reported[:3], bound.bias_std_mps2, rtol=1e-9)
    np.testing.assert_allclose(reported[3:], bound.scale_misalignment_std, rtol=1e-9)
    mc_bias = math.sqrt(np.mean(spread[:3] ** 2))
    mc_m = math.sqrt(np.mean(spread[3:] ** 2))
    assert mc_bias == pytest.approx(float(np.mean(bound.bias_std_mps2)), rel=0.10)
    assert mc_m == pytest.approx(float(np.mean(bound.scale_misalignment_std)), rel=0.10)
