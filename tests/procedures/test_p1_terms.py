"""P1's optional model terms chosen by the data (docs/p1.md, "Model terms"): a unit with K2 gets
K2 and one without does not, the chosen model's σ cover the truth, forced terms hold, the G rule
follows the specification, and the choice with its evidence is in the result.

The windows are made from each twin unit's model with white noise (tests/procedures/
_p1_synthetic.py: the six positions and the rate points of three repetitions), so that many seeds
cost little (about 15 ms a seed)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from imucalib.errors import InvalidInputError
from imucalib.procedures.p1.analysis import P1Options, analyze_p1_observations
from imucalib.procedures.p1.fit import fit_p1
from imucalib.procedures.p1.plan import default_specification
from imucalib.procedures.p1.procedure import PROCEDURE

from . import _p1_synthetic as synth

#: Seeds of the choice-rate test. Measured on seeds 0–199 (docs/p1.md, "Model terms"): a
#: tactical unit's drawn K2 (50 µg/g² per axis, 1σ) chosen in 197 of 200, none in 191 of 200
#: without one (the test's size α = 5 %); a consumer unit's in 200 of 200.
SEEDS = range(100)
FAST = P1Options(hash_recording=False)


def _run(grade: str, seed: int, *, k2: bool, **options):
    model = synth.truth(grade, seed, k2=k2)
    fit = fit_p1(synth.observations(model, grade, seed), g_sensitivity=None, k2=None,
                 **options)
    truth = synth.truth_values(model)
    z = [(v - truth[n]) / s for n, v, s in zip(fit.param_names, fit.estimate,
                                               np.sqrt(np.diag(fit.covariance)), strict=True)]
    return fit, np.array(z)


def test_a_unit_with_k2_gets_k2_and_one_without_does_not():
    with_k2 = without = 0
    z_all = []
    for seed in SEEDS:
        fit, z = _run("tactical", seed, k2=True)
        with_k2 += fit.accel.choice.has("k2")
        assert ("accel_K2_x" in fit.param_names) == fit.accel.choice.has("k2")
        z_all.append(z)
        fit, z = _run("tactical", seed, k2=False)
        without += fit.accel.choice.has("k2")
        z_all.append(z)
    n = len(SEEDS)
    assert with_k2 >= 0.95 * n and without <= 0.05 * n, (with_k2, without)
    # the chosen model's σ cover the truth (K2 on the scaled input, (P1.K2′))
    z = np.concatenate(z_all)
    assert 0.9 < np.sqrt(np.mean(z**2)) < 1.1 and np.abs(z).max() < 4.5
    for seed in range(10):  # a consumer unit's K2 (10³ µg/g²) is never missed
        assert _run("consumer", seed, k2=True)[0].accel.choice.has("k2")


def test_a_term_the_data_leave_out_keeps_the_shared_sigma_honest():
    """Without K2 in the model the biases carry (TS.4): never tighter than the model with it."""
    model = synth.truth("tactical", 5, k2=False)
    obs = synth.observations(model, "tactical", 5)
    free = fit_p1(obs, g_sensitivity=None, k2=None)
    assert not free.accel.choice.has("k2")
    assert {f"accel_bias_{a}" for a in "xyz"} <= set(free.accel.choice.model_std)
    with_k2 = fit_p1(obs, g_sensitivity=None, k2=True)
    s_free = dict(zip(free.param_names, np.sqrt(np.diag(free.covariance)), strict=True))
    s_k2 = dict(zip(with_k2.param_names, np.sqrt(np.diag(with_k2.covariance)), strict=True))
    assert all(s_free[f"accel_bias_{a}"] >= 0.999 * s_k2[f"accel_bias_{a}"] for a in "xyz")


def test_forced_terms_hold_and_add_no_model_uncertainty():
    obs_k2 = synth.observations(synth.truth("tactical", 1), "tactical", 1)
    obs_lin = synth.observations(synth.truth("tactical", 1, k2=False), "tactical", 1)
    out = analyze_p1_observations(obs_k2, dataclasses.replace(FAST, terms="-k2,+g"))
    assert "accel_K2_x" not in out.result.param_names and "gyro_G_xx" in out.result.param_names
    accel, gyro = out.model_selection
    assert accel["forced"] == {"k2": False} and gyro["forced"] == {"g": True}
    assert accel["model_std"] == {} and [c["terms"] for c in accel["candidates"]] == [[]]
    forced_in = analyze_p1_observations(obs_lin, dataclasses.replace(FAST, terms="+k2"))
    assert "accel_K2_x" in forced_in.result.param_names
    assert any("forced +k2" in n for n in forced_in.notes)
    # the older switch: g_sensitivity=True/False forces G as it always did; terms overrides it
    assert "gyro_G_xx" not in analyze_p1_observations(
        obs_lin, dataclasses.replace(FAST, g_sensitivity=False)).result.param_names
    assert P1Options(g_sensitivity=False, terms="+g").forced_terms() == {"g": True}
    with pytest.raises(InvalidInputError, match="unknown term 'k3'"):
        P1Options(terms="+k3")
    with pytest.raises(InvalidInputError, match="term_criterion"):
        P1Options(term_criterion="aic")  # type: ignore[arg-type]
    assert {"terms", "term_criterion", "term_level"} <= PROCEDURE.analysis_options


def test_g_is_ruled_in_with_or_without_a_specification_and_the_choice_is_in_the_result():
    """G by rule whatever the plan says: the same windows give the same model with and without
    a specification (docs/p1.md, "Model terms")."""
    model = synth.truth("tactical", 2)
    obs = synth.observations(model, "tactical", 2)
    free = analyze_p1_observations(obs, FAST)  # no specification
    specified = analyze_p1_observations(
        dataclasses.replace(obs, imu_spec=default_specification("tactical")), FAST)
    for analysis in (free, specified):
        gyro = analysis.model_selection[1]
        assert gyro["ruled"] == {"g": True} and gyro["chosen"] == ["g"]
        assert "gyro_G_xx" in analysis.result.param_names
        assert any("G by rule" in n for n in analysis.notes)
    np.testing.assert_array_equal(free.result.values, specified.result.values)
    doc = json.loads(json.dumps(free.to_dict()))["model_selection"]
    assert [d["group"] for d in doc] == ["accel (six positions)",
                                         "gyro (rate points and statics)"]
    accel = doc[0]
    assert accel["criterion"] == "lrt" and accel["level"] == 0.05
    assert accel["chosen"] == ["k2"]
    assert [c["terms"] for c in accel["candidates"]] == [[], ["k2"]]
    for c in accel["candidates"] + doc[1]["candidates"]:
        assert c["chi2"] > 0 and c["dof"] > 0 and c["score"] is not None
        assert c["reduced_chi2"] == pytest.approx(c["chi2"] / c["dof"])
    assert any(n.startswith("accel (six positions) model terms: k2 (by likelihood-ratio")
               for n in free.notes)
    # the per-axis model has no optional terms
    assert analyze_p1_observations(obs, dataclasses.replace(
        FAST, model="per-axis")).model_selection == ()


def test_calibrate_takes_the_terms_and_shows_the_candidates(tactical_run, tmp_path):
    from typer.testing import CliRunner

    from imucalib.cli import app

    runner = CliRunner()
    result = runner.invoke(app, ["calibrate", str(tactical_run), "--out", str(tmp_path),
                                 "--set", "terms=+k2,-g", "--set", "term_level=0.01"])
    assert result.exit_code == 0, result.output
    assert "model terms (docs/p1.md)" in result.output  # the candidates' table
    report = json.loads(next(tmp_path.glob("*.p1.report.json")).read_text())
    accel, gyro = report["model_selection"]
    assert accel["forced"] == {"k2": True} and gyro["forced"] == {"g": False}
    assert accel["level"] == 0.01
    names = {p["name"] for p in report["result"]["parameters"]}
    assert "accel_K2_x" in names and "gyro_G_xx" not in names
    bad = runner.invoke(app, ["calibrate", str(tactical_run), "--out", str(tmp_path),
                              "--set", "terms=+k3"])
    assert bad.exit_code == 2 and "unknown term 'k3'" in bad.output
