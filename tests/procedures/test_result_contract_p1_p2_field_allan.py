"""The result contract of P1, P2, the field calibration and Allan (docs/procedures.md).

Each result is a :class:`~imucalib.models.procedure_result.ProcedureResult`; its
``parameter_rows()`` are :class:`~imucalib.models.reported.ReportedParameter` rows whose
reported σ is the σ before Birge scaling times the scale of the fit that gave it
(docs/processing-estimation.md, Eq. (3)); ``passed`` is its decision's verdict; and
``result_document`` writes it as strict JSON whose parameters are its rows.
"""

from __future__ import annotations

import json
from collections.abc import Callable

import numpy as np
import pytest

from imucalib.errors import InvalidInputError, MissingSegmentError
from imucalib.models.decision import Decision
from imucalib.models.procedure_result import ProcedureResult
from imucalib.models.reported import ReportedParameter
from imucalib.models.result_document import result_document
from imucalib.procedures.allan.analysis import NO_DECISION_REASON, analyze_allan_arrays
from imucalib.procedures.common.static_intervals import FieldLog
from imucalib.procedures.field.analysis import FieldOptions, analyze_field
from imucalib.procedures.p1.analysis import P1Options, analyze_p1
from imucalib.procedures.p2.analysis import analyze_unit, failed_unit
from imucalib.procedures.p2.batch import P2BatchResult
from imucalib.procedures.p2.result import DECISION_RULE, HELD_OUT_CHECK
from imucalib.sim import handheld_session

from ._p2_synthetic import draw_truth, unit_observations


def _check_contract(result: ProcedureResult, scale: Callable[[str], float]) -> None:
    """The contract of one unit's result; `scale`: the Birge factor on each parameter's σ."""
    assert isinstance(result, ProcedureResult)
    assert isinstance(result.decision, Decision)
    assert result.passed is result.decision.passed
    assert result.members == () and result.error == ""
    assert all(isinstance(n, str) for n in result.notes)
    rows = result.parameter_rows()
    assert rows and all(isinstance(r, ReportedParameter) for r in rows)
    for r in rows:
        if r.std_noise == 0.0:  # a parameter fixed by the model (zero variance)
            assert r.std == 0.0, r
            continue
        assert r.std >= r.std_noise > 0.0, r
        assert r.std == pytest.approx(r.std_noise * scale(r.name), rel=1e-12), r
    doc = result_document(result)
    text = json.dumps(doc, allow_nan=False)
    back = json.loads(text)
    assert [ReportedParameter(p["name"], p["value"], p["std"], p["unit"], p["std_noise"])
            for p in back["parameters"]] == rows
    assert back["decision"]["passed"] is result.passed
    assert back["procedure"] == result.procedure and back["unit"] == result.unit
    # the covariance as reported agrees with the rows' σ
    names, values, cov = result.triad_parameters()
    by_name = {r.name: r for r in rows}
    assert len(names) == values.size == cov.shape[0] == cov.shape[1]
    for i, n in enumerate(names):
        assert values[i] == by_name[n].value
        assert np.sqrt(cov[i, i]) == pytest.approx(by_name[n].std, rel=1e-12, abs=0.0)
    if names:
        assert back["covariance"]["names"] == names


def test_p1_a_misfit_scales_each_triad_by_its_birge_ratio_and_the_decision_fails(consumer_run):
    """The per-axis model on a consumer IMU: both triads are misfits, the decision fails."""
    analysis = analyze_p1(consumer_run, options=P1Options(model="per-axis",
                                                          hash_recording=False))
    cal = analysis.result
    assert analysis.calibration is cal and analysis.unit == cal.sensor_id
    assert all(q.misfit for q in analysis.fit_quality)
    _check_contract(analysis, cal.sigma_scale)
    assert analysis.passed is False and "accelerometer residuals" in analysis.decision.failed
    std = cal.std(scaled=True)
    assert all(r.std == pytest.approx(std[r.name], rel=1e-15) for r in analysis.parameter_rows())
    assert [r.name for r in analysis.parameter_rows()] == list(cal.param_names)
    assert analysis.notes == tuple(cal.notes)


@pytest.fixture(scope="module")
def p2_unit():
    """A unit of three temperature points: constant models of a cubic truth (misfits)."""
    rng = np.random.default_rng(0)
    obs = unit_observations(draw_truth(rng), rng, temperatures=(-20.0, 25.0, 65.0))
    return analyze_unit(obs)


def test_p2_unit_rows_hold_the_sigma_before_the_models_birge_ratios(p2_unit):
    res = p2_unit
    assert not any(q.misfit for p in res.points for q in p.least_squares.fit_quality)
    assert any(q.misfit for q in res.fit_quality)
    _check_contract(res, lambda n: res.models[n].quality.sigma_scale)
    assert res.calibration is res.result
    std = res.result.std(scaled=True)
    assert all(r.std == std[r.name] for r in res.parameter_rows())  # bit-identical
    decision = res.decision
    assert decision.rule == DECISION_RULE
    assert decision.failed == res.reasons and decision.passed is res.passed is (not res.reasons)
    assert {c.name for c in decision.checks} == {
        "accelerometer error after compensation", "gyro error after compensation",
        "closed form against least squares", HELD_OUT_CHECK}
    # the held-out consistency is reported with the decision, not counted (docs/p2.md)
    held = next(c for c in decision.checks if c.name == HELD_OUT_CHECK)
    assert held.passed is None and len(held.rows) == len(res.held_out_inconsistent) > 0
    kinds = {"accelerometer error": "accelerometer error after compensation",
             "gyro error": "gyro error after compensation",
             "closed form": "closed form against least squares"}
    assert {c.name for c in decision.checks if c.passed is False} == {
        name for start, name in kinds.items() for r in res.reasons if r.startswith(start)}


def test_p2_batch_members_are_its_units_and_a_unit_not_calibrated_fails_it(p2_unit):
    broken = failed_unit("U2", MissingSegmentError("unit U2, temperature point 1: no turn"))
    assert isinstance(broken, ProcedureResult)
    assert broken.passed is False and broken.decision.passed is False
    assert broken.decision.failed == (broken.error,) and broken.parameter_rows() == []
    assert broken.calibration is None and broken.triad_parameters()[0] == []
    batch = P2BatchResult(recordings=("a.h5",), results=(p2_unit, broken))
    assert isinstance(batch, ProcedureResult)
    assert batch.members == (p2_unit, broken) and batch.unit == "array"
    assert batch.calibration is None and batch.parameter_rows() == [] and batch.error == ""
    assert batch.decision.failed == tuple(r.unit for r in batch.members if not r.passed)
    assert batch.passed is batch.decision.passed is all(r.passed for r in batch.members)
    assert "U2" in batch.decision.failed and any(n.startswith("U2: ") for n in batch.notes)
    with pytest.raises(InvalidInputError, match="one unit"):
        result_document(batch)
    ok = P2BatchResult(recordings=("a.h5", "b.h5"), results=())
    assert ok.passed is True and ok.unit == "lot" and ok.members == ()


def _field(**options):
    s = handheld_session("consumer", seed=101, noise="grade")
    log = FieldLog("IMU", "twin", s.time_s, s.gyro_rps, s.accel_mps2)
    return analyze_field(log, FieldOptions(latitude_deg=s.site.latitude_deg, **options))


def _field_scale(res) -> Callable[[str], float]:
    """The Birge factors of a field result: per triad, and the static gyro fit's (FL.2)."""
    quality = {q.group: q.sigma_scale for q in res.quality}
    static = quality["gyro (static poses)"]
    accel = next(s for g, s in quality.items() if g.startswith("accel"))

    def scale(name: str) -> float:
        if name.startswith("accel_bias_rate_"):
            return accel
        if name not in res.result.param_names:  # the static gyro rows of a bias-only fit
            return static
        return res.result.sigma_scale(name) * (static if name in res.gyro_static_names else 1.0)
    return scale


@pytest.mark.parametrize("gyro_form", ["auto", "none"])
def test_field_rows_and_no_decision(gyro_form):
    res = _field(gyro_form=gyro_form)
    assert res.calibration is res.result
    assert any(q.misfit for q in res.quality)  # the grade's noise: the poses scatter
    _check_contract(res, _field_scale(res))
    assert res.passed is None and res.decision.verdict == "NO DECISION"
    assert res.decision.notes == tuple(q.summary() for q in res.quality if q.misfit)
    names = [r.name for r in res.parameter_rows()]
    k = len(res.result.param_names)
    assert names[:k] == list(res.result.param_names)
    assert res.result.has_triad("gyro") is (gyro_form == "auto")
    if gyro_form == "none":  # the static gyro fit's bias and G follow the calibration's rows
        assert names[k:k + len(res.gyro_static_names)] == list(res.gyro_static_names)
    assert res.to_dict()["passed"] is None


def test_allan_noise_terms_no_decision_and_no_triad_parameters():
    rng = np.random.default_rng(1)
    n, rate_hz = 20000, 100.0
    columns = {f"gyro_{a}_rps": rng.normal(0.0, 1e-3, n) for a in "xyz"}
    columns.update({f"accel_{a}_mps2": rng.normal(0.0, 1e-2, n) for a in "xyz"})
    res = analyze_allan_arrays(np.arange(n) / rate_hz, columns, source="rest.csv", unit="IMU-A")
    _check_contract(res, lambda _n: 1.0)
    assert res.passed is None and res.decision.rule == NO_DECISION_REASON
    assert res.calibration is None and res.triad_parameters()[0] == []
    assert {r.name for r in res.parameter_rows()} >= {f"gyro_{a}_white" for a in "xyz"}
    assert result_document(res)["covariance"] is None
    assert res.provenance is not None and res.provenance.recording == "rest.csv"
