"""P1 reads what it needs from the recorded steps (roles, tags, commanded), not from the plan."""

from __future__ import annotations

import dataclasses
import shutil

import h5py
import numpy as np
import pytest

from imucalib.errors import RecordingError
from imucalib.io import open_recording
from imucalib.plan import parse_plan
from imucalib.procedures.p1.analysis import P1Options, analyze_p1, analyze_p1_observations

FAST = P1Options(hash_recording=False)
#: What a run writes of its plan: the plan, its hash and the facts read from it (io/context.py).
PLAN_KEYS = ("plan_toml", "plan_hash", "procedure", "plan_name", "acceptance", "guard_band_k",
             "equipment_json", "imu_spec_json")


def _planless_copy(run, path):
    """A copy of `run` as a recording no plan made: without the plan and its facts."""
    shutil.copyfile(run, path)
    with h5py.File(path, "r+") as f:
        for key in PLAN_KEYS:
            f.attrs.pop(key, None)
    return path


def test_a_station_run_stores_each_steps_role_tags_and_units(tactical_run):
    with open_recording(tactical_run) as rec:
        assert rec.format_version >= 2  # version 2 added the step fields
        plan = parse_plan(rec.metadata["plan_toml"])
        steps = rec.steps
    for step in steps:
        planned = plan.steps[step.commanded["plan_step"]]
        assert (step.role, step.tags) == (planned.role, planned.tags)
        assert step.commanded["tags"] == list(planned.tags)
        assert step.units == ("IMU-0001",)
    assert {s.role for s in steps} == {"", "p1.accel-position", "p1.gyro-bias", "p1.gyro-rate",
                                       "p1.held-out-rate", "p1.held-out-position"}


def test_a_recording_without_its_plan_calibrates_the_same(tactical_run, tmp_path):
    """Without the plan (and the facts a run writes from it): the same windows, estimates and
    Type B (the defaults, which the generated plan also uses); no specification to accept
    against, so that check is not assessed, and the held-out limits are the generic defaults
    (the checks still pass). The model's terms are the same too: G by rule with or without
    the plan, K2 by the same data (docs/p1.md, "Model terms"). One input is the plan's: its
    grade's flicker and random walk, which the 5-min static cannot show for the tactical gyro
    (docs/p1.md, "Noise model of the window means"); given the same noise model, the planless
    recording's estimates and covariance are those of the run with its plan, bit for bit."""
    bare = _planless_copy(tactical_run, tmp_path / "bare.h5")
    with_plan = analyze_p1(tactical_run, options=FAST)
    without = analyze_p1(bare, options=FAST)
    assert with_plan.model_selection[1]["ruled"] == without.model_selection[1]["ruled"] == {
        "g": True}
    assert with_plan.result.param_names == without.result.param_names
    assert not without.observations.context.has_plan and without.observations.imu_spec is None
    assert any("flicker floor is not determined" in n for n in with_plan.observations.notes)
    assert not any("flicker floor" in n for n in without.observations.notes)
    a, b = with_plan.observations, without.observations
    for wa, wb in zip(a.windows, b.windows, strict=True):
        np.testing.assert_array_equal(wa.accel_mean_mps2, wb.accel_mean_mps2)
        np.testing.assert_array_equal(wa.gyro_mean_rps, wb.gyro_mean_rps)
    same_noise = dataclasses.replace(b, noise=a.noise, windows=tuple(
        dataclasses.replace(wb, accel_se_mps2=wa.accel_se_mps2, gyro_se_rps=wa.gyro_se_rps)
        for wa, wb in zip(a.windows, b.windows, strict=True)))
    again = analyze_p1_observations(same_noise, FAST)
    np.testing.assert_array_equal(again.result.values, with_plan.result.values)
    np.testing.assert_array_equal(again.result.covariance, with_plan.result.covariance)
    spec_without = {c.name: c for c in without.checks}.pop("specification")
    assert spec_without.passed is None and "not assessed" in spec_without.summary
    assert {c.name: c.passed for c in with_plan.checks}["specification"] is True
    assert ([c.passed for c in without.checks if c.name != "specification"]
            == [c.passed for c in with_plan.checks if c.name != "specification"])
    assert sorted(without.per_repetition) == [1, 2]


def test_the_equipment_accuracy_can_be_given_as_options(tactical_run):
    plan_b = analyze_p1(tactical_run, options=FAST).result
    no_b = analyze_p1(tactical_run, options=P1Options(hash_recording=False, type_b=False)).result
    zero = analyze_p1(tactical_run, options=P1Options(
        hash_recording=False, table_position_accuracy_arcsec=0.0,
        table_orthogonality_arcsec=0.0)).result
    np.testing.assert_allclose(zero.covariance, no_b.covariance, rtol=1e-12)
    assert plan_b.sigma("accel_M_xy") > zero.sigma("accel_M_xy")
    assert any("(P1Options)" in n for n in zero.notes)


def test_steps_without_roles_or_a_plan_say_so(tactical_run, tmp_path):
    bare = _planless_copy(tactical_run, tmp_path / "bare.h5")
    with h5py.File(bare, "r+") as f:
        n = f["steps/role"].shape[0]
        f["steps/role"][:n] = np.full(n, b"", dtype=f["steps/role"].dtype)
        f["steps/tags"][:n] = np.full(n, b"[]", dtype=f["steps/tags"].dtype)
    with pytest.raises(RecordingError, match=r"holds no plan \(plan_toml\) and none of its "
                                             r"steps has a P1 role"):
        analyze_p1(bare, options=FAST)
