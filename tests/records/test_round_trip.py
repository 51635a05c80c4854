"""A CalibrationResult in and out; history and amendment (the original stays, both shown)."""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np
import pytest

from imucalib.errors import InvalidInputError, RecordsError
from imucalib.models.result import CalibrationResult


def test_calibration_result_round_trips(records, make_result, recording_file):
    res = make_result("IMU-7", 0.0123)
    run = records.record_run(plan_name="p1-short", plan_hash="ab" * 32, procedure="p1",
                             recording=recording_file, operator="ana",
                             environment={"temperature_degc": 23.1})
    rid = records.record_result(run, res, passed=True, verification={"max_error": 1e-4})
    back = CalibrationResult.from_dict(records.result_document(rid))
    np.testing.assert_array_equal(back.values, res.values)
    np.testing.assert_array_equal(back.covariance, res.covariance)
    assert back.to_dict() == res.to_dict()
    entry = records.result(rid)
    std = res.std()
    assert [p.name for p in entry.parameters] == list(res.param_names)
    for p in entry.parameters:
        assert p.value == res.value(p.name)  # exact: doubles on both backends
        assert p.std == std[p.name]
        assert p.unit == res.units[p.name]
    assert entry.passed is True and entry.serial == "IMU-7" and entry.version == 1
    view = records.run(run)
    assert view.environment == {"temperature_degc": 23.1} and view.operator == "ana"
    assert view.recording_path == str(recording_file.resolve()) and len(view.recording_sha256) == 64
    assert view.result_ids == (rid,)
    assert records.verify() == []


def test_amendment_keeps_the_original_and_history_shows_both(records, make_result):
    run = records.record_run(plan_name="p1", started_utc=datetime(2026, 1, 5, tzinfo=UTC))
    first = records.record_result(run, make_result("IMU-1", 0.01), passed=None)
    records.review(first, "bo", approved=False, comment="bias x looks wrong")
    before = records.result(first)
    second = records.amend(first, make_result("IMU-1", 0.02), reason="wrong table offset",
                           passed=True)
    history = records.history("IMU-1")
    assert [h.result_id for h in history] == [first, second]
    old, new = history
    assert old.replaced_by == second and not old.current
    assert new.replaces == first and new.current and new.version == 2
    assert new.amendment_reason == "wrong table offset"
    assert old.parameters == before.parameters  # untouched
    assert old.parameter("accel_b_x").value == 0.01 and new.parameter("accel_b_x").value == 0.02
    assert [r.comment for r in old.reviews] == ["bias x looks wrong"] and new.reviews == ()
    with pytest.raises(RecordsError, match=f"already amended by result {second}; amend {second}"):
        records.amend(first, make_result("IMU-1"), reason="again")
    with pytest.raises(RecordsError, match="needs a reason"):
        records.amend(second, make_result("IMU-1"), reason=" ")
    assert records.verify() == []


def test_any_result_of_the_contract_is_accepted(records):
    """A procedure's result (models/procedure_result.py) is stored as its result document."""
    from imucalib.models.decision import no_decision
    from imucalib.models.procedure_result import ResultDefaults
    from imucalib.models.reported import ReportedParameter

    class Minimal(ResultDefaults):
        procedure, unit, fit_quality, notes = "allan", "", (), ()
        decision = no_decision("no limits")

        def parameter_rows(self):
            return [ReportedParameter("arw", 1e-3, 1e-4, "rad/s^0.5", 1e-4),
                    ReportedParameter("vrw", 2e-3, 2e-4, "m/s^1.5", 1e-4)]

        def to_dict(self):
            return {"kind": "minimal"}

    run = records.record_run(plan_name="allan")
    rid = records.record_result(run, Minimal(), serial="IMU-9")
    entry = records.result(rid)
    assert [(p.name, p.value, p.std) for p in entry.parameters] == [
        ("arw", 1e-3, 1e-4), ("vrw", 2e-3, 2e-4)]
    document = records.result_document(rid)
    assert document["format_version"] == 4 and document["details"] == {"kind": "minimal"}
    assert [p["std_noise"] for p in document["parameters"]] == [1e-4, 1e-4]
    with pytest.raises(InvalidInputError, match="names no unit"):
        records.record_result(run, Minimal())


def test_unknown_things_are_named(records, make_result):
    records.add_unit("IMU-1", model="BMI088", maker="Bosch", specification={"range_g": 24})
    with pytest.raises(RecordsError, match=r"no unit with serial 'IMU-2'.*known serials: IMU-1"):
        records.history("IMU-2")
    with pytest.raises(RecordsError, match="already recorded"):
        records.add_unit("IMU-1")
    with pytest.raises(RecordsError, match="no run with id 99"):
        records.record_result(99, make_result("IMU-1"))
    with pytest.raises(RecordsError, match="no result with id 42"):
        records.review(42, "bo", approved=True)
    with pytest.raises(RecordsError, match="no station 'lab 9'"):
        records.record_run(station="lab 9")
    assert records.units() == ["IMU-1"]
    assert records.get_or_create_unit("IMU-1") == 1
    assert records.verify() == []


def test_a_parameter_that_was_not_estimated_is_left_out_of_the_rows(tmp_path):
    """A procedure may report a quantity as NaN (not estimated): SQLite would store NULL."""
    from imucalib.models.decision import Decision
    from imucalib.models.procedure_result import ResultDefaults
    from imucalib.models.reported import ReportedParameter
    from imucalib.records import open_records

    class P3Like(ResultDefaults):
        procedure, unit, fit_quality, notes = "p3", "T-1", (), ()
        decision = Decision(passed=True, rule="r")

        def parameter_rows(self):
            nan = float("nan")
            return [ReportedParameter("K2", 7e-6, 1.5e-8, "1/(m/s^2)", 1.5e-8),
                    ReportedParameter("nominal_radius", nan, nan, "m", nan)]

        def to_dict(self):
            return {}

    result = P3Like()
    with open_records(str(tmp_path / "r.db")) as records:
        run = records.record_run(procedure="p3")
        rid = records.record_result(run, result, passed=True)
        assert rid > 0
        assert len(records.drift("T-1", "K2")) == 1
        with pytest.raises(RecordsError, match="carries parameter 'nominal_radius'; they carry K2"):
            records.drift("T-1", "nominal_radius")
        assert records.verify() == []


def test_a_misfit_result_is_recorded_with_its_birge_scaled_sigma(records, make_result):
    """The records keep the σ the result reports: Birge-scaled where a fit is a misfit."""
    import dataclasses

    from imucalib.models.fit_quality import assess_fit

    res = dataclasses.replace(make_result("IMU-9"),
                              fit_quality=(assess_fit("accel", 90.0, 10),))
    assert res.misfit
    rid = records.record_result(records.record_run(plan_name="p1"), res)
    scaled, noise = res.std(scaled=True), res.std()
    for p in records.result(rid).parameters:
        assert p.std == scaled[p.name]
        if p.name.startswith("accel"):
            assert p.std == pytest.approx(noise[p.name] * 3.0)  # √(90/10)
        else:
            assert p.std == noise[p.name]
