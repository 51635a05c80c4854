"""Goodness of fit: χ²/ν with its expected range, the misfit flag, and Birge-scaled σ."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from imucalib.errors import InvalidInputError
from imucalib.estimation import solve_weighted_lsq
from imucalib.estimation.designs import SIX_POSITION_UP_B, build_triad_design
from imucalib.models.fit_quality import assess_fit
from imucalib.models.result import CalibrationResult

G = 9.80665


def test_a_right_model_is_flagged_about_one_time_in_a_hundred():
    rng = np.random.default_rng(3)
    for dof in (6, 42, 500):
        flags = sum(assess_fit("accel", float(c), dof).misfit
                    for c in rng.chisquare(dof, 4000))
        assert 0.005 < flags / 4000 < 0.016, (dof, flags)  # 1 % ± 3 binomial σ
    q = assess_fit("accel", 6.0, 6)
    assert q.expected_low < 1.0 < q.expected_high
    assert q.sigma_scale == 1.0 and "MISFIT" not in q.summary()


@pytest.mark.parametrize(("chi2", "dof", "match"), [
    (-1.0, 6, "chi2"), (math.nan, 6, "chi2"), (1.0, -1, "dof"), (1.0, True, "dof")])
def test_bad_arguments_are_refused(chi2, dof, match):
    with pytest.raises(InvalidInputError, match=match):
        assess_fit("accel", chi2, dof)


def test_no_redundancy_cannot_be_tested():
    q = assess_fit("gyro", 0.0, 0)
    assert not q.misfit and q.sigma_scale == 1.0 and "not testable" in q.summary()


def _hand_placed_fit(seed: int, b, M, tilt_deg: float, noise_mps2: float):
    """Six positions × 3 placed by hand (tilts of `tilt_deg` rms), fitted with nominal poses."""
    nominal = np.tile(G * SIX_POSITION_UP_B, (3, 1))
    rng = np.random.default_rng(seed)
    true_f = Rotation.from_rotvec(
        rng.normal(0.0, math.radians(tilt_deg), nominal.shape)).apply(nominal)
    y = b + true_f @ (np.eye(3) + M).T + rng.normal(0.0, noise_mps2, true_f.shape)
    design = build_triad_design(nominal)
    z = (y - nominal).ravel()
    return solve_weighted_lsq(design.H, z, param_names=design.param_names,
                              sigma=np.full(z.size, noise_mps2))


def test_a_richer_truth_is_flagged_and_the_scaled_sigma_cover_the_error():
    """Poses 0.5° off nominal, noise 10 µg: χ²/ν ≈ 4e5; noise-only σ cover nothing."""
    rng = np.random.default_rng(0)
    b, M = np.array([0.02, -0.01, 0.03]), rng.normal(0.0, 1e-3, (3, 3))
    truth = np.concatenate([b, M.ravel()])
    flagged, cover_noise, cover_scaled = 0, [], []
    for seed in range(200):
        sol = _hand_placed_fit(100 + seed, b, M, 0.5, 1e-4)
        q = assess_fit("accel", sol.chi2, sol.dof)
        flagged += q.misfit
        err = np.abs(sol.estimate - truth)
        cover_noise.append(np.mean(err <= 2.0 * sol.std))
        cover_scaled.append(np.mean(err <= 2.0 * sol.std * q.sigma_scale))
    assert flagged == 200
    assert np.mean(cover_noise) < 0.05
    # 2σ of a t-like statistic with ν = 42: about 95 %
    assert 0.90 <= np.mean(cover_scaled) <= 0.99, np.mean(cover_scaled)


def test_the_result_carries_fit_quality_and_scales_only_the_misfit_group():
    names = ("accel_bias_x", "accel_bias_y", "accel_bias_z",
             *(f"accel_M_{i}{j}" for i in "xyz" for j in "xyz"),
             "gyro_bias_x", "gyro_bias_y", "gyro_bias_z",
             *(f"gyro_M_{i}{j}" for i in "xyz" for j in "xyz"))
    k = len(names)
    quality = (assess_fit("accel", 60.0, 6), assess_fit("gyro", 5.0, 6))
    res = CalibrationResult(sensor_id="U1", procedure="p1", model="triad", param_names=names,
                            values=np.zeros(k), covariance=np.eye(k) * 1e-8,
                            units=dict.fromkeys(names, "1"), fit_quality=quality)
    assert res.misfit
    std, scaled = res.std(), res.std(scaled=True)
    assert scaled["accel_bias_x"] == pytest.approx(std["accel_bias_x"] * math.sqrt(10.0))
    assert scaled["gyro_bias_x"] == std["gyro_bias_x"]
    back = CalibrationResult.from_json(res.to_json())
    assert back.fit_quality == res.fit_quality and back.misfit
    doc = json.loads(res.to_json())
    doc["fit_quality"][0]["birge_ratio"] = 1.0
    with pytest.raises(InvalidInputError, match=r"fit_quality\[0\]\.birge_ratio"):
        CalibrationResult.from_dict(doc, "r.json")
    # a version 1 document has no fit_quality and still reads
    doc = json.loads(res.to_json())
    doc["format_version"] = 1
    del doc["fit_quality"], doc["temperature_models"]
    old = CalibrationResult.from_dict(doc, "v1.json")
    assert old.fit_quality == () and not old.misfit and old.std(scaled=True) == old.std()


def test_allan_fits_carry_their_goodness_and_the_table_scales_a_misfit():
    """A white-noise record fits its model (flagged about 1 time in 100); the noise table
    shows χ²/ν and scales a misfit channel's σ by the Birge ratio."""
    from imucalib.analysis import compute_oadev, fit_noise_terms
    from imucalib.models.noise import NoiseModel
    from imucalib.models.noise_generator import simulate_noise
    from imucalib.report.noise_table import format_noise_table

    white = NoiseModel(white_density=1e-3)
    flags, fits = 0, {}
    for seed in range(30):
        x = simulate_noise(white, 1 << 16, 0.01, rng=np.random.default_rng([5, seed]))[:, 0]
        fit = fit_noise_terms(compute_oadev(x, 100.0), sensor="gyro")
        flags += fit.quality.misfit
        fits[f"gyro_{seed}"] = fit
    assert flags <= 3  # 1 % expected; 3 of 30 would be a 1e-3 event
    table = format_noise_table({"gyro_x": fits["gyro_0"]})
    assert "Fit χ²/ν" in table
    assert f"{fits['gyro_0'].quality.reduced_chi2:.2g}" in table
    doc = fits["gyro_0"].to_dict()["fit_quality"]
    assert doc["misfit"] == fits["gyro_0"].quality.misfit
    # a fit made a misfit by hand: its σ are shown scaled by √(χ²/ν)
    import dataclasses

    bad = dataclasses.replace(fits["gyro_0"], chi2=fits["gyro_0"].dof * 100.0)
    assert bad.quality.misfit and bad.quality.sigma_scale == pytest.approx(10.0)
    assert "misfit: σ×10" in format_noise_table({"gyro_x": bad})
