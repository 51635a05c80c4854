"""Acceptance against the unit's own specification, under simple or guarded acceptance."""

from __future__ import annotations

import dataclasses
import shutil

import h5py
import numpy as np
import pytest

from imucalib import units
from imucalib.analysis.verification import check_specification, decision_rule_text
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.io import open_recording
from imucalib.io.context import RecordingContext
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
    assert obs.imu_spec is not None
    result = analyze_p1_observations(obs, FAST).result
    worst_ug = max(abs(result.value(f"accel_bias_{a}")) for a in "xyz") / units.UG
    tight = obs.imu_spec.limits.model_copy(update={"accel_bias_ug": worst_ug * 0.5})
    imu = obs.imu_spec.model_copy(update={"limits": tight})
    analysis = analyze_p1_observations(dataclasses.replace(obs, imu_spec=imu), FAST)
    spec = {c.name: c for c in analysis.checks}["specification"]
    assert spec.passed is False
    failed = [r.name for r in spec.rows if not r.passed]
    assert failed and all(n.startswith("accel_bias_") for n in failed)
    assert not analysis.decision.passed and "specification" in analysis.decision.failed


def test_guarded_acceptance_refuses_a_value_whose_band_straddles_the_limit(tactical_run):
    with open_recording(tactical_run) as rec:
        obs = extract_p1_observations(rec)
    assert obs.imu_spec is not None
    result = analyze_p1_observations(obs, FAST).result
    worst = max((f"gyro_bias_{a}" for a in "xyz"), key=lambda n: abs(result.value(n)))
    value = abs(result.value(worst)) / units.DEG_PER_H
    sigma = result.sigma(worst) / units.DEG_PER_H
    limit = value + sigma  # the largest bias is within the limit, but not by 2u
    tight = obs.imu_spec.limits.model_copy(update={"gyro_bias_dph": limit})
    tweaked = dataclasses.replace(obs, imu_spec=obs.imu_spec.model_copy(update={"limits": tight}))
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


#: The keys a run writes of its plan's facts besides the plan and its hash (io/context.py).
CONTEXT_KEYS = ("procedure", "plan_name", "acceptance", "guard_band_k", "equipment_json",
                "imu_spec_json")


def test_the_specification_and_rule_come_from_the_recording_whether_old_or_new(p1_tools,
                                                                             tmp_path):
    """A run writes the unit, its limits, the equipment and the rule as keys of their own; a
    recording from before (only its stored plan) and one without the plan TOML (the keys only)
    give the same facts and the same result."""
    plan = p1_tools.p1_plan("consumer", 5, acceptance="guarded", serial="SN-42", model="M-9",
                            maker="Acme")
    plan = plan.model_copy(update={
        "acceptance": plan.acceptance.model_copy(update={"guard_band_k": 3.0}),
        "imu": plan.imu.model_copy(update={
            "gyro_noise_dps": 0.05,
            "limits": plan.imu.limits.model_copy(update={"gyro_bias_dph": 1000.0})}),
        "equipment": plan.equipment.model_copy(update={"table_position_accuracy_arcsec": 20.0})})
    new = p1_tools.run_twin(plan, tmp_path / "new.h5")
    old, no_toml = tmp_path / "old.h5", tmp_path / "no-toml.h5"
    for path, dropped in ((old, CONTEXT_KEYS), (no_toml, ("plan_toml",))):
        shutil.copyfile(new, path)
        with h5py.File(path, "r+") as f:
            for key in dropped:
                del f.attrs[key]
    contexts = []
    for path in (new, old, no_toml):
        with open_recording(path) as rec:
            contexts.append(RecordingContext.of(rec.metadata))
    assert contexts[0] == contexts[1] == contexts[2]
    ctx = contexts[0]
    assert ctx.imu_unit == {"serial": "SN-42", "model": "M-9", "maker": "Acme",
                            "grade": "consumer"}
    assert ctx.spec_limits["gyro_bias_dph"] == 1000.0 and ctx.imu_spec["gyro_noise_dps"] == 0.05
    assert (ctx.acceptance, ctx.guard_band_k) == ("guarded", 3.0)
    assert ctx.equipment["table_position_accuracy_arcsec"] == 20.0
    results = [analyze_p1(path, options=FAST) for path in (new, old, no_toml)]
    details = results[0].result.provenance.details
    assert details["unit"] == {"serial": "SN-42", "model": "M-9", "maker": "Acme",
                               "grade": "consumer"}
    assert details["acceptance"] == {"rule": "guarded", "guard_band_k": 3.0}
    assert details["specification"]["gyro_bias_dph"] == 1000.0
    assert any("position accuracy 20″" in n for n in results[0].result.notes)
    assert "guarded acceptance" in results[0].decision.rule
    for other in results[1:]:
        np.testing.assert_array_equal(other.result.values, results[0].result.values)
        np.testing.assert_array_equal(other.result.covariance, results[0].result.covariance)
        # a recording without its plan TOML has no predicted σ to compare (and says so)
        assert [n for n in other.result.notes if not n.startswith("predicted σ not compared")] \
            == list(results[0].result.notes)
        assert other.result.provenance.details == details
        assert other.to_dict()["checks"] == results[0].to_dict()["checks"]
        assert other.decision == results[0].decision
