"""Drift across calibrations, units and equipment due, runs of a plan."""

from __future__ import annotations

from datetime import UTC, date, datetime

import pytest

from imucalib.errors import RecordsError


def _calibrate(records, make_result, serial, when, bias, *, passed=True, plan="p1"):
    run = records.record_run(plan_name=plan, plan_hash=plan.encode().hex().ljust(64, "0"),
                             started_utc=when)
    return records.record_result(run, make_result(serial, bias), passed=passed)


def test_drift_across_three_calibrations_with_an_amendment(records, make_result):
    dates = [datetime(2024, 3, 1, 8, tzinfo=UTC), datetime(2025, 3, 1, 8, tzinfo=UTC),
             datetime(2026, 3, 1, 8, tzinfo=UTC)]
    ids = [_calibrate(records, make_result, "IMU-3", d, b)
           for d, b in zip(dates, (0.010, 0.012, 0.015), strict=True)]
    fixed = records.amend(ids[1], make_result("IMU-3", 0.011), reason="temperature mislabelled")
    _calibrate(records, make_result, "OTHER", dates[0], 0.5)
    points = records.drift("IMU-3", "accel_b_x")
    assert [p.calibrated_utc for p in points] == dates
    assert [p.value for p in points] == [0.010, 0.011, 0.015]  # the amendment, not the original
    assert [p.result_id for p in points] == [ids[0], fixed, ids[2]]
    std = make_result("IMU-3").std()["accel_b_x"]
    assert all(p.std == std and p.unit == "m/s^2" for p in points)
    with pytest.raises(RecordsError, match=r"carries parameter 'accel_bias_x'.*accel_K_x"):
        records.drift("IMU-3", "accel_bias_x")


def test_units_due_by_default_and_own_interval(records, make_result):
    records.add_unit("NEVER")
    records.add_unit("SHORT", recal_interval_days=90)
    _calibrate(records, make_result, "SHORT", datetime(2026, 1, 1, tzinfo=UTC), 0.01)
    _calibrate(records, make_result, "OLD", datetime(2025, 1, 10, tzinfo=UTC), 0.01)
    _calibrate(records, make_result, "OLD", datetime(2025, 6, 1, tzinfo=UTC), 0.01, passed=False)
    _calibrate(records, make_result, "FRESH", datetime(2026, 2, 1, tzinfo=UTC), 0.01)
    due = {d.serial: d for d in records.due_units(date(2026, 4, 1))}
    assert set(due) == {"NEVER", "SHORT", "OLD"}
    assert due["NEVER"].last_calibrated is None
    assert due["SHORT"].due_on == date(2026, 4, 1) and due["SHORT"].interval_days == 90
    # the failed calibration does not count: the last passed one is 2025-01-10
    assert due["OLD"].last_calibrated == date(2025, 1, 10)
    assert due["OLD"].due_on == date(2026, 1, 10)
    assert {d.serial for d in records.due_units(date(2026, 3, 31))} == {"NEVER", "OLD"}
    assert {d.serial for d in records.due_units(date(2026, 4, 1), interval_days=30)} == {
        "NEVER", "SHORT", "OLD", "FRESH"}
    # every unit, due or not (`imucalib records list`)
    status = {d.serial: d for d in records.unit_status()}
    assert set(status) == {"NEVER", "SHORT", "OLD", "FRESH"}
    assert status["FRESH"].last_calibrated == date(2026, 2, 1)
    assert status["FRESH"].due_on == date(2027, 2, 1)
    assert status["NEVER"].due_on is None


def test_equipment_due_follows_the_current_certificate(records):
    lab = records.add_station("lab 1", location="bldg 4")
    table = records.add_equipment(lab, "rate table", "ACT 2000", "T-1", "C-17",
                                  date(2025, 1, 1), date(2026, 1, 1))
    records.add_equipment("lab 1", "chamber", "SU-262", "CH-2", "C-18",
                          date(2025, 6, 1), date(2026, 6, 1))
    assert [e.serial for e in records.due_equipment(date(2026, 2, 1))] == ["T-1"]
    renewed = records.recertify_equipment(table, "C-31", date(2026, 1, 5), date(2027, 1, 5))
    assert records.due_equipment(date(2026, 2, 1)) == []
    due = records.due_equipment(date(2026, 7, 1))
    assert [(e.serial, e.certificate, e.station) for e in due] == [("CH-2", "C-18", "lab 1")]
    everything = records.equipment(current_only=False)
    assert [e.certificate for e in everything] == ["C-17", "C-18", "C-31"]
    assert everything[2].equipment_id == renewed and everything[2].replaces == table
    with pytest.raises(RecordsError, match=f"already replaced by {renewed}"):
        records.recertify_equipment(table, "C-32", date(2026, 1, 6), date(2027, 1, 6))
    run = records.record_run(plan_name="p1", station="lab 1", equipment=[renewed, 2])
    assert records.run(run).equipment_ids == (2, renewed) and records.run(run).station == "lab 1"
    assert records.verify() == []


def test_runs_of_a_plan_by_hash_or_name(records, make_result):
    a = _calibrate(records, make_result, "U1", datetime(2026, 1, 1, tzinfo=UTC), 0.01, plan="A")
    _calibrate(records, make_result, "U2", datetime(2026, 1, 2, tzinfo=UTC), 0.01, plan="B")
    c = _calibrate(records, make_result, "U3", datetime(2026, 1, 3, tzinfo=UTC), 0.01, plan="A")
    by_name = records.runs_of_plan("A")
    assert [r.result_ids for r in by_name] == [(a,), (c,)]
    assert records.runs_of_plan(b"A".hex().ljust(64, "0")) == by_name
    assert records.runs_of_plan("C") == []
