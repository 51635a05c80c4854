"""P1's predicted σ beside the achieved σ (docs/test-design.md, "Predicted against achieved")."""

from __future__ import annotations

import io
import math
import shutil

import h5py
import pytest
from rich.console import Console

from imucalib.io import open_recording
from imucalib.plan import parse_plan
from imucalib.procedures.p1.achieved import WORSE_QUANTILE
from imucalib.procedures.p1.analysis import (
    NO_PREDICTION_NOTE,
    P1Options,
    analyze_p1,
    analyze_p1_observations,
)
from imucalib.procedures.p1.console import render_calibration
from imucalib.procedures.p1.report import PREDICTION_COLUMNS, prediction_rows

FAST = P1Options(hash_recording=False)
WARNING = "achieved σ worse than predicted: "
#: What a run writes of its plan (tests/procedures/test_p1_step_roles.py).
PLAN_KEYS = ("plan_toml", "plan_hash", "procedure", "plan_name", "acceptance", "guard_band_k",
             "equipment_json", "imu_spec_json")


@pytest.fixture(scope="module")
def consumer(consumer_run):
    return analyze_p1(consumer_run, options=FAST)


def _console(analysis) -> str:
    buf = io.StringIO()
    render_calibration(Console(file=buf, width=200, color_system=None), analysis, [])
    return buf.getvalue()


def test_the_analysis_carries_both_predictions_beside_the_achieved_sigma(consumer):
    check = consumer.prediction
    assert check is not None
    assert [r.name for r in check.rows] == list(consumer.result.param_names)
    achieved = consumer.result.std(scaled=True)
    model_std: dict[str, float] = {}
    for choice in consumer.model_selection:
        model_std.update(choice["model_std"])
    for r in check.rows:
        assert r.achieved_std == achieved[r.name]
        assert r.predicted_fitted_std is not None
        # the like-for-like comparison: the fitted noise's prediction is the noise-only σ
        noise_only = math.sqrt(r.achieved_std**2 - model_std.get(r.name, 0.0) ** 2)
        assert 0.98 <= noise_only / r.predicted_fitted_std <= 1.02, r.name
    assert {g.name for g in check.groups} == {"accel", "gyro"}
    for g in check.groups:  # (PA.4): a normal twin run is within its bound
        assert not g.worse and 0.0 < g.correlated_share < 1.0 and g.limit > 1.0
    assert check.warning() is None
    assert not any(n.startswith(WARNING) for n in consumer.notes)
    data = consumer.to_dict()["prediction"]
    assert data["worse_than_predicted"] is False and data["quantile"] == WORSE_QUANTILE
    first = data["parameters"][0]
    assert set(first) >= {"name", "predicted_std", "predicted_std_fitted_noise", "achieved_std",
                          "ratio"}
    out = _console(consumer)
    assert "achieved σ / predicted σ (plan, grade noise): accel ×" in out
    assert "note:" not in out


def test_a_unit_noisier_than_its_grade_warns(consumer, consumer_run):
    """A consumer unit run under a plan that states a tactical one (2.4–8× its noise)."""
    with open_recording(consumer_run) as rec:
        plan = parse_plan(rec.metadata["plan_toml"])
    claimed = plan.model_copy(update={"imu": plan.imu.model_copy(update={"grade": "tactical"})})
    noisy = analyze_p1_observations(consumer.observations, FAST, plan=claimed)
    check = noisy.prediction
    assert check is not None and {g.name for g in check.worse} == {"accel", "gyro"}
    assert all(g.variance_ratio > 2.0 * g.limit for g in check.worse)
    warnings = [n for n in noisy.notes if n.startswith(WARNING)]
    assert len(warnings) == 1 and "noisier than its grade" in warnings[0]
    notes = [line for line in _console(noisy).splitlines() if line.startswith("note:")]
    assert len(notes) == 1 and notes[0].startswith("note: " + WARNING)
    assert noisy.to_dict()["prediction"]["worse_than_predicted"] is True
    # the estimates are the same: the prediction only adds a note
    assert list(noisy.result.values) == list(consumer.result.values)


def test_a_recording_without_its_plan_says_so(consumer_run, tmp_path):
    bare = tmp_path / "bare.h5"
    shutil.copyfile(consumer_run, bare)
    with h5py.File(bare, "r+") as f:
        for key in PLAN_KEYS:
            f.attrs.pop(key, None)
    analysis = analyze_p1(bare, options=FAST)
    assert analysis.prediction is None
    assert analysis.notes.count(NO_PREDICTION_NOTE) == 1
    assert analysis.to_dict()["prediction"] is None
    assert "achieved σ /" not in _console(analysis)


def test_the_report_table(consumer):
    rows = prediction_rows(consumer.prediction)
    assert len(PREDICTION_COLUMNS) == len(rows[0]) == 6
    bias = next(r for r in rows if r[0] == "accel_bias_x")
    assert bias[4] == "µg" and all(c != "—" for c in bias)
    assert 0.5 < float(bias[5]) < 2.0
