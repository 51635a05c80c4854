"""Acceptance against the unit's own specification, under simple or guarded acceptance."""

from __future__ import annotations

import dataclasses

import pytest

from imucalib import units
from imucalib.analysis.verification import check_specification, decision_rule_text
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.io import open_recording
from imucalib.models.imu import GRADES
from imucalib.procedures.p1.analysis import P1Options, analyze_p1, analyze_p1_observations
from imucalib.procedures.p1.observations import extract_p1_observations
from imucalib.procedures.p1.plan import default_specification, generate_p1_plan

FAST = P1Options(hash_recording=False)


def test_the_grade_specification_is_four_spreads_and_the_plan_carries_it():
    spec = default_specification("tactical", serial="SN-42", model="T1", maker="ACME")
    g = GRADES["tactical"]
    assert spec.limits.accel_bias_ug == 4 * g.accel_bias_ug
    assert spec.limits.gyro_misalignment_urad == 4000 * g.gyro_misalignment_mrad
    assert spec.accel_accuracy_g == 1e-3 and spec.gyro_accuracy_dps == 0.05
    # optical gyros have no g-sensitivity: not specified, not checked (a limit of 0 would fail)
    assert default_specification("navigation").limits.gyro_g_sensitivity_dph_per_g is None
    plan = generate_p1_plan(serial="SN-42", model="T1", maker="ACME", acceptance="guarded")
    assert (plan.imu.serial, plan.imu.model, plan.imu.maker) == ("SN-42", "T1", "ACME")
    assert plan.acceptance.rule == "guarded" and plan.twin.imus[0].name == "SN-42"
    with pytest.raises(ConfigurationError, match="acceptance"):
        generate_p1_plan(acceptance="lenient")


def test_simple_and_guarded_acceptance_differ_only_near_the_limit():
    rows = [("a", 9.0, 1.0, 10.0, "µg"), ("b", -3.0, 1.0, 10.0, "µg"), ("c", 50.0, 1.0, None, "")]
    simple = check_specification("specification", rows)
    guarded = check_specification("specification", rows, rule="guarded", guard_band_k=2.0)
    assert simple.passed and len(simple.rows) == 2  # the unspecified row is skipped
    assert not guarded.passed and [r.name for r in guarded.rows if not r.passed] == ["a"]
    assert "guard band" in decision_rule_text("guarded", 2.0)
    assert check_specification("specification", [("c", 1.0, 0.0, None, "")]).passed is None
    with pytest.raises(InvalidInputError, match="decision rule"):
        check_specification("specification", rows, rule="lenient")


def test_a_twin_unit_passes_its_grade_specification(tactical_run):
    analysis = analyze_p1(tactical_run, options=FAST)
    spec = {c.name: c for c in analysis.checks}["specification"]
    assert spec.passed, [r for r in spec.rows if not r.passed]
    assert len(spec.rows) == 33 + 6  # 33 parameters and 6 white-noise coefficients
    details = analysis.result.provenance.details
    assert details["unit"]["grade"] == "tactical"
    assert details["specification"]["accel_bias_ug"] == 4000.0
    assert details["acceptance"] == {"rule": "simple", "guard_band_k": 2.0}
    assert analysis.decision.passed


def test_a_unit_beyond_its_datasheet_fails_and_the_rows_say_which(tactical_run):
    with open_recording(tactical_run) as rec:
        obs = extract_p1_observations(rec)
    assert obs.plan is not None
    result = analyze_p1_observations(obs, FAST).result
    worst_ug = max(abs(result.value(f"accel_bias_{a}")) for a in "xyz") / units.UG
    tight = obs.plan.imu.limits.model_copy(update={"accel_bias_ug": worst_ug * 0.5})
    imu = obs.plan.imu.model_copy(update={"limits": tight})
    plan = obs.plan.model_copy(update={"imu": imu})
    analysis = analyze_p1_observations(dataclasses.replace(obs, plan=plan), FAST)
    spec = {c.name: c for c in analysis.checks}["specification"]
    assert spec.passed is False
    failed = [r.name for r in spec.rows if not r.passed]
    assert failed and all(n.startswith("accel_bias_") for n in failed)
    assert not analysis.decision.passed and "specification" in analysis.decision.failed


def test_guarded_acceptance_refuses_a_value_whose_band_straddles_the_limit(tactical_run):
    with open_recording(tactical_run) as rec:
        obs = extract_p1_observations(rec)
    assert obs.plan is not None
    result = analyze_p1_observations(obs, FAST).result
    worst = max((f"gyro_bias_{a}" for a in "xyz"), key=lambda n: abs(result.value(n)))
    value = abs(result.value(worst)) / units.DEG_PER_H
    sigma = result.sigma(worst) / units.DEG_PER_H
    limit = value + sigma  # the largest bias is within the limit, but not by 2u
    tight = obs.plan.imu.limits.model_copy(update={"gyro_bias_dph": limit})
    plan = obs.plan.model_copy(update={"imu": obs.plan.imu.model_copy(update={"limits": tight})})
    tweaked = dataclasses.replace(obs, plan=plan)
    simple = analyze_p1_observations(tweaked, FAST)
    guarded = analyze_p1_observations(tweaked, dataclasses.replace(FAST, acceptance="guarded"))
    row = {c.name: c for c in simple.checks}["specification"]
    assert row.passed
    spec = {c.name: c for c in guarded.checks}["specification"]
    assert worst in [r.name for r in spec.rows if not r.passed]
    assert "guarded acceptance" in guarded.decision.rule


def test_plan_new_writes_the_identity_and_the_rule(tmp_path):
    from typer.testing import CliRunner

    from imucalib.cli import app
    from imucalib.plan import load_plan

    out = tmp_path / "p1.toml"
    done = CliRunner().invoke(app, ["plan", "new", "p1", "--out", str(out), "--serial", "SN-7",
                                    "--model", "T1", "--maker", "ACME", "--acceptance",
                                    "guarded"])
    assert done.exit_code == 0, done.output
    plan = load_plan(out)
    assert plan.imu.serial == "SN-7" and plan.acceptance.rule == "guarded"
    assert plan.imu.limits.gyro_bias_dph == 20.0
    done = CliRunner().invoke(app, ["plan", "new", "allan", "--out", str(out), "--serial", "X"])
    assert done.exit_code == 2 and "takes no --serial" in done.output
