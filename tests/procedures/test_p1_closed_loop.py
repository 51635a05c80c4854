"""P1 on the twin, closed loop: estimates against the truth, the residual rule, verification."""

from __future__ import annotations

import numpy as np
import pytest

from imucalib.io import open_recording
from imucalib.models import ImuModel
from imucalib.models.result import CalibrationResult
from imucalib.procedures.p1.analysis import P1Options, analyze_p1


def truth_vector(result: CalibrationResult, model: ImuModel) -> np.ndarray:
    true = {}
    for triad, tm in (("accel", model.accel), ("gyro", model.gyro)):
        for i, a in enumerate("xyz"):
            true[f"{triad}_bias_{a}"] = tm.bias[i]
            for j, b in enumerate("xyz"):
                true[f"{triad}_M_{a}{b}"] = tm.scale_misalignment[i, j]
                if triad == "gyro":
                    true[f"{triad}_G_{a}{b}"] = tm.g_sensitivity[i, j]
            if triad == "accel":
                true[f"{triad}_K2_{a}"] = tm.k2[i]
    return np.array([true[n] for n in result.param_names])


def normalized_errors(path) -> tuple[np.ndarray, object]:
    analysis = analyze_p1(path, options=P1Options(type_b=False, hash_recording=False))
    with open_recording(path) as rec:
        model = ImuModel.from_dict(rec.truth["imu_models"][analysis.result.sensor_id])
    res = analysis.result
    sigma = np.sqrt(np.diag(res.covariance))
    return (res.values - truth_vector(res, model)) / sigma, analysis


@pytest.mark.slow
@pytest.mark.parametrize(("grade", "seed"), [("consumer", 11), ("consumer", 12),
                                             ("tactical", 21), ("tactical", 22),
                                             ("navigation", 31), ("navigation", 32)])
def test_every_estimate_within_4_sigma_of_the_truth(p1_tools, grade, seed, tmp_path):
    path = p1_tools.run_twin(p1_tools.p1_plan(grade, seed), tmp_path / "r.h5")
    z, analysis = normalized_errors(path)
    # accelerometer bias + M (+ K2, the data's choice), gyro bias + M + G (G by rule;
    # docs/p1.md, "Model terms")
    accel, gyro = analysis.model_selection
    assert z.size == 33 + 3 * ("k2" in accel["chosen"])
    assert gyro["ruled"] == {"g": True} and gyro["chosen"] == ["g"]
    by_name = dict(zip(analysis.result.param_names, np.round(z, 2), strict=True))
    assert np.all(np.abs(z) < 4.0), by_name
    # a correct model on honest data passes its own residual rule and the held-out check
    names = {c.name: c for c in analysis.checks}
    assert names["accelerometer residuals"].passed
    assert names["gyro residuals"].passed
    assert names["held-out accelerometer accuracy"].passed
    assert names["held-out gyro accuracy"].passed
    # the Kalman refinement agrees with least squares; the fit is efficient (σ = CRLB)
    assert analysis.kalman_max_difference_sigma < 1e-3
    assert max(analysis.crlb_ratio.values()) == pytest.approx(1.0, abs=1e-6)


def test_residual_rule_catches_a_model_that_is_too_simple(consumer_run):
    """Consumer-grade misalignments (mrad): the per-axis model fails, the triad model passes."""
    per_axis = analyze_p1(consumer_run, options=P1Options(model="per-axis",
                                                          hash_recording=False))
    triad = analyze_p1(consumer_run, options=P1Options(model="triad", hash_recording=False))
    pa = {c.name: c for c in per_axis.checks}
    tr = {c.name: c for c in triad.checks}
    assert pa["accelerometer residuals"].passed is False
    assert pa["gyro residuals"].passed is False
    failed_rows = [r for r in pa["accelerometer residuals"].rows if not r.passed]
    assert any("|mean|" in r.name for r in failed_rows)  # cross-axis misfit beyond 0.002 g
    assert tr["accelerometer residuals"].passed and tr["gyro residuals"].passed
    assert not per_axis.decision.passed and "accelerometer residuals" in per_axis.decision.failed
    assert triad.decision.passed
    # the misfit is said in the result, the decision and the report, with Birge-scaled σ
    quality = {q.group: q for q in per_axis.result.fit_quality}
    assert quality["accel"].misfit and quality["accel"].reduced_chi2 > quality[
        "accel"].expected_high
    assert any("MODEL MISFIT" in n for n in per_axis.decision.notes)
    assert "MODEL MISFIT" in per_axis.decision.summary()
    assert any("MODEL MISFIT" in n for n in per_axis.result.notes)
    scaled, std = per_axis.result.std(scaled=True), per_axis.result.std()
    ratio = quality["accel"].birge_ratio
    assert scaled["accel_K_x"] == pytest.approx(std["accel_K_x"] * ratio)
    report = per_axis.to_dict()
    assert [q["group"] for q in report["fit_quality"]] == ["accel", "gyro"]
    assert report["std_scaled"]["accel_K_x"] == pytest.approx(std["accel_K_x"] * ratio)
    assert not triad.result.misfit and not triad.decision.notes
    assert triad.result.std(scaled=True) == triad.result.std()


def test_repeatability_over_repetitions_and_the_decision(tactical_run):
    analysis = analyze_p1(tactical_run, options=P1Options(hash_recording=False))
    assert sorted(analysis.per_repetition) == [1, 2]
    rep = {c.name: c for c in analysis.checks}["repeatability"]
    assert rep.passed, [r for r in rep.rows if not r.passed]
    cv_rows = [r for r in rep.rows if r.unit == "CV"]
    assert len(cv_rows) == 6 and all(r.value < 0.01 for r in cv_rows)  # scale factors
    spread_rows = [r for r in rep.rows if r.unit != "CV"]
    assert len(spread_rows) == 27
    assert analysis.decision.passed and not analysis.decision.not_assessed
    # the pooled fit is tighter than each repetition's
    pooled = np.sqrt(np.diag(analysis.result.covariance))
    single = np.sqrt(np.diag(analysis.per_repetition[1].covariance))
    assert np.all(pooled <= single * 1.0001)


def test_result_carries_provenance_and_notes(tactical_run):
    analysis = analyze_p1(tactical_run)
    res = analysis.result
    with open_recording(tactical_run) as rec:
        assert res.provenance.plan_hash == rec.metadata["plan_hash"]
    import hashlib

    assert res.provenance.recording_sha256 == hashlib.sha256(tactical_run.read_bytes()).hexdigest()
    assert any("Earth rate" in n for n in res.notes)
    assert any("Type B" in n for n in res.notes)
    assert res.provenance.details["max_alignment_error_s"] <= 1e-3
    back = CalibrationResult.from_json(res.to_json())
    assert back.isclose(res) and back.notes == res.notes
