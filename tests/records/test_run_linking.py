"""One calibration, one run: results attached to the run of their recording, re-analyses as
versions, the calibration date taken from the run and kept by amendments (docs/records.md)."""

from __future__ import annotations

from datetime import UTC, date, datetime, timedelta

import pytest

from imucalib.errors import RecordsError
from imucalib.io.hashing import file_sha256


def test_the_run_of_a_recording_is_found_by_its_bytes(records, recording_file, tmp_path):
    sha = file_sha256(recording_file)
    assert records.run_of_recording(sha) is None and records.run_of_recording("") is None
    first = records.record_run(plan_name="p1", plan_hash="ab" * 32, recording=recording_file,
                               operator="ana")
    found = records.run_of_recording(sha)
    assert found is not None and found.run_id == first and found.operator == "ana"
    # the same bytes elsewhere are the same recording; a second run of them (records from before
    # runs and results were linked) is taken when it is at the path asked about
    copy = tmp_path / "copy.h5"
    copy.write_bytes(recording_file.read_bytes())
    assert records.run_of_recording(sha, copy).run_id == first
    second = records.record_run(plan_name="p1", recording=copy)
    assert records.run_of_recording(sha, copy).run_id == second
    assert records.run_of_recording(sha, recording_file).run_id == first
    assert records.run_of_recording("0" * 64) is None


def test_a_reanalysis_is_the_next_version_of_the_result_in_the_same_run(records, make_result):
    run = records.record_run(plan_name="p1", started_utc=datetime(2026, 3, 1, 8, tzinfo=UTC))
    first, replaced = records.record_analysis(run, make_result("IMU-1", 0.01), passed=True)
    assert replaced is None and records.result(first).version == 1
    with pytest.raises(RecordsError, match="a re-analysis needs a reason"):
        records.record_analysis(run, make_result("IMU-1", 0.02), reason=" ")
    second, replaced = records.record_analysis(run, make_result("IMU-1", 0.02), passed=True,
                                               reason="re-analysis by ana: new lever arm")
    assert replaced == first
    entry = records.result(second)
    assert (entry.version, entry.replaces, entry.run_id) == (2, first, run)
    assert entry.amendment_reason == "re-analysis by ana: new lever arm"
    assert records.result(first).replaced_by == second
    third, replaced = records.record_analysis(run, make_result("IMU-1", 0.03), reason="again")
    assert replaced == second and records.result(third).version == 3
    # another unit, or another procedure's analysis of the same unit, starts at version 1
    other, replaced = records.record_analysis(run, make_result("IMU-2", 0.01))
    assert replaced is None and records.result(other).version == 1
    assert [p.value for p in records.drift("IMU-1", "accel_b_x")] == [0.03]
    noise, replaced = records.record_analysis(run, make_result("IMU-1", procedure="allan"))
    assert replaced is None and records.result(noise).version == 1
    assert records.run(run).result_ids == (first, second, third, other, noise)
    with pytest.raises(RecordsError, match="no run with id 99"):
        records.record_analysis(99, make_result("IMU-1"))
    assert records.verify() == []


def test_the_calibration_date_is_the_runs_and_an_amendment_keeps_it(records, make_result):
    started = datetime(2025, 1, 10, 9, tzinfo=UTC)
    run = records.record_run(plan_name="p1", started_utc=started,
                             ended_utc=started + timedelta(hours=5))
    rid, _ = records.record_analysis(run, make_result("IMU-5", 0.01), passed=True)
    fixed = records.amend(rid, make_result("IMU-5", 0.011), "wrong table offset", passed=True)
    assert records.result(rid).calibrated_utc == started
    assert records.result(fixed).calibrated_utc == started        # not the amendment's time
    assert [p.calibrated_utc for p in records.drift("IMU-5", "accel_b_x")] == [started]
    [status] = records.unit_status()
    assert (status.last_calibrated, status.due_on) == (date(2025, 1, 10), date(2026, 1, 10))
    assert status.result_id == fixed
    assert [d.serial for d in records.due_units(date(2026, 1, 10))] == ["IMU-5"]
    assert records.due_units(date(2026, 1, 9)) == []
    # a run with an end and no start is dated by its end
    ended = datetime(2025, 6, 1, 17, tzinfo=UTC)
    late = records.record_run(plan_name="p1", ended_utc=ended)
    other, _ = records.record_analysis(late, make_result("IMU-6", 0.01))
    assert records.result(other).calibrated_utc == ended


def test_a_run_without_times_is_dated_by_its_first_result(records, make_result):
    run = records.record_run(environment={"opened_by": "calibrate", "unplanned": True})
    assert records.run(run).unplanned and records.run(run).opened_by == "calibrate"
    rid, _ = records.record_analysis(run, make_result("LOG-1", 0.01), passed=True)
    first = records.result(rid)
    assert first.calibrated_utc == first.created_utc
    again, _ = records.record_analysis(run, make_result("LOG-1", 0.02), passed=True,
                                       reason="re-analysis with options noise=3")
    fixed = records.amend(again, make_result("LOG-1", 0.03), "typo", passed=True)
    for later in (again, fixed):
        entry = records.result(later)
        assert entry.created_utc > first.created_utc
        assert entry.calibrated_utc == first.calibrated_utc      # the recalibration clock stays
    [status] = records.unit_status()
    assert status.last_calibrated == first.created_utc.date() and status.result_id == fixed
    assert status.due_on == first.created_utc.date() + timedelta(days=365)
    runs = records.run(run)
    assert not records.run(records.record_run(plan_name="p1")).unplanned
    assert runs.result_ids == (rid, again, fixed)
