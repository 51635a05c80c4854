"""Disk budget: the estimate's arithmetic, its station facts, the free-space check, real files."""

from __future__ import annotations

import itertools
import math
import os
import re
from collections import namedtuple

import h5py
import pytest

from imucalib.errors import ConfigurationError, LimitExceededError
from imucalib.io.recover import compact_recording
from imucalib.plan import Plan, describe_plan
from imucalib.plan import budget as budget_module
from imucalib.plan.budget import (
    CLOSED_IMU_ROW_BYTES,
    CLOSED_MOTION_AXIS_BYTES,
    CLOSED_TIME_BYTES,
    METADATA_BYTES,
    MIN_SETTLE_PHASE_S,
    MOVE_ALLOWANCE_S,
    StationFacts,
    check_free_space,
    estimate_plan_recording,
    estimate_recording,
    estimate_recording_bytes,
    format_bytes,
    plan_run_duration_s,
)
from imucalib.plan.equipment import ImuConfig, TableConfig
from imucalib.plan.schema import StaticStep
from imucalib.procedures import generate_p1_plan
from imucalib.sim.scenario import Scenario
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation
from imucalib.station.simulate import estimate_scenario_recording, simulate_scenario

CHUNK = 65536
STEPS_TABLE = 64 * (8 + 64 + 256 + 8192 + 4 * 8 + 32 + 2048 + 512 + 4096 + 2048)  # one chunk
LOG_TABLE = 256 * (8 + 16 + 128 + 4096)  # one chunk of the event log


@pytest.mark.parametrize(("n", "text"), [(0, "0 B"), (999, "999 B"), (1500, "1.5 kB"),
                                         (107913512, "108 MB"), (1408433271, "1.41 GB"),
                                         (9.8e12, "9.8 TB")])
def test_format_bytes(n, text):
    assert format_bytes(n) == text


def test_rows_are_stored_in_whole_chunks():
    facts = StationFacts(imu_sample_rates_hz=(1000.0, 200.0), table_axes=2, chamber=True)
    est = estimate_recording(100.0, 5, facts)
    assert [(s.name, s.rows, s.row_bytes) for s in est.streams] == [
        ("imu/IMU-0001", 100001, 81), ("imu/IMU-0002", 20001, 81), ("table/main", 10001, 40),
        ("chamber/main", 101, 24)]
    assert [s.bytes for s in est.streams] == [2 * CHUNK * 81, CHUNK * 81, CHUNK * 40,
                                              CHUNK * 24]
    assert est.tables_bytes == STEPS_TABLE + LOG_TABLE + METADATA_BYTES
    assert est.total_bytes == sum(s.bytes for s in est.streams) + est.tables_bytes
    # closed: compressed chunks are stored at their size, so rows × the measured bytes per row
    assert [s.closed_bytes for s in est.streams] == [
        math.ceil(100001 * CLOSED_IMU_ROW_BYTES), math.ceil(20001 * CLOSED_IMU_ROW_BYTES),
        math.ceil(10001 * (CLOSED_TIME_BYTES + 2 * CLOSED_MOTION_AXIS_BYTES)), 101 * 24]
    assert est.closed_bytes == sum(s.closed_bytes for s in est.streams) + est.tables_bytes
    assert est.describe().startswith("about 22.8 MB of disk, 4.12 MB once closed (gzip), over "
                                     "100 s (0.03 h): imu/IMU-0001 100,001 rows × 81 B at "
                                     "1000 Hz")


def test_station_facts_are_checked():
    with pytest.raises(ConfigurationError, match=re.escape(
            "station rates and time constants must be finite and > 0; got IMUs [nan] Hz, "
            "feedback 100.0 Hz, chamber 1.0 Hz and 5.0 °C/min, IMU thermal time constant "
            "600.0 s")):
        StationFacts(imu_sample_rates_hz=(math.nan,))
    with pytest.raises(ConfigurationError, match="`duration_s` must be finite and ≥ 0"):
        estimate_recording(math.inf, 1, StationFacts(imu_sample_rates_hz=(100.0,)))


def test_a_plan_with_station_facts():
    plan = generate_p1_plan(repetitions=1, static_s=600.0)
    one = estimate_recording_bytes(plan, imu_sample_rate_hz=2000.0, table_axes=2)
    two = estimate_recording_bytes(plan, imu_sample_rate_hz=2000.0, n_imus=2, table_axes=2)
    per_imu = estimate_recording_bytes(plan, imu_sample_rate_hz=[2000.0, 2000.0], table_axes=2)
    assert two == per_imu > one
    est = estimate_plan_recording(plan)  # its [twin]: one tactical IMU at 1 kHz, two axes
    assert plan.twin is not None
    assert est.duration_s == plan_run_duration_s(plan, StationFacts.of_twin(plan.twin))
    assert est.duration_s > sum(r.min_duration_s for r in describe_plan(plan))
    assert [s.rate_hz for s in est.streams] == [1000.0, 100.0]


def test_the_run_duration_step_by_step():
    plan = Plan.model_validate({"name": "d", "steps": [
        {"kind": "operator-check", "item": "x"},
        {"kind": "warm-up", "duration_s": 10.0, "window_s": 60.0},
        {"kind": "position", "angles_deg": [0.0], "settle_s": 2.0, "record_s": 5.0},
        {"kind": "rate", "axis": 0, "rate_dps": 90.0, "settle_s": 30.0, "revolutions": 1},
        {"kind": "soak", "temperature_degc": 40.0, "stable_for_s": 100.0},
        {"kind": "soak", "temperature_degc": 41.0, "stable_for_s": 100.0, "timeout_s": 105.0},
        {"kind": "static", "duration_s": 7.0}]})
    facts = StationFacts(imu_sample_rates_hz=(100.0,), initial_temperature_degc=20.0,
                         chamber_ramp_degc_per_min=5.0, imu_thermal_time_constant_s=600.0)
    soak = 20.0 / 5.0 * 60.0 + 600.0 * math.log(20.0 * -math.expm1(-100.0 / 600.0) / 0.2) + 100.0
    expected = (0.0 + 60.0 + (MIN_SETTLE_PHASE_S + 5.0 + MOVE_ALLOWANCE_S)
                + (30.0 + 4.0 + MOVE_ALLOWANCE_S) + soak + 105.0 + 7.0)  # 12 + 100 > 105
    assert plan_run_duration_s(plan, facts) == pytest.approx(expected)


def test_a_plan_without_twin_uses_its_least_acquisition_rate():
    plan = Plan.model_validate({
        "name": "no-twin", "equipment": {"acquisition_rate_min_hz": 400.0},
        "steps": [{"kind": "static", "duration_s": 100.0},
                  {"kind": "soak", "temperature_degc": 20.0, "stable_for_s": 100.0},
                  {"kind": "rate", "axis": 0, "rate_dps": 90.0, "revolutions": 1}]})
    est = estimate_plan_recording(plan)
    assert [(s.name, s.rate_hz) for s in est.streams] == [
        ("imu/IMU-0001", 400.0), ("table/main", 100.0), ("chamber/main", 1.0)]
    assert est.duration_s == pytest.approx(100.0 + 100.0 + 20.0 + 4.0 + MOVE_ALLOWANCE_S)


def test_a_twin_imu_without_a_rate_uses_its_grades():
    sc = Scenario(name="x", imus=(ImuConfig(name="A", grade="consumer"),),
                  steps=(StaticStep(kind="static", duration_s=10.0),), store_truth_streams=True)
    est = estimate_scenario_recording(sc)
    assert [s.name for s in est.streams] == ["imu/IMU-0001", "imu/IMU-0001"]
    assert est.streams[0].rate_hz > 0 and est.streams[1].row_bytes == 9 * 8


Usage = namedtuple("Usage", "total used free")


def test_free_space_is_checked(tmp_path, monkeypatch):
    monkeypatch.setattr(budget_module.shutil, "disk_usage", lambda p: Usage(0, 0, 2_500_000))
    target = tmp_path / "new" / "deeper" / "r.h5"
    assert check_free_space(2_000_000, target) == 2_500_000
    with pytest.raises(LimitExceededError, match="^" + re.escape(
            f"the recording needs about 3 MB but {tmp_path} has only 2.5 MB free; free some "
            "space, write elsewhere (--out) or shorten the steps") + "$"):
        check_free_space(3_000_000, target)
    assert check_free_space(3_000_000, target, replaced_bytes=1_000_000) == 3_500_000


def _bounds_the_run(est, path) -> None:
    """The estimate covers the peak of a run (the file as written plus its compressed copy at
    close) and is close to the file as written: float64 samples assumed, int32 counts written.
    The closed file's estimate is close to the file the run closed (gzip by default)."""
    estimate = est.total_bytes
    compressed = os.path.getsize(path)
    with h5py.File(path, "r") as f:
        assert f["streams/imu"][next(iter(f["streams/imu"]))]["time_s"].compression == "gzip"
    compact_recording(path, None)  # the file as it was written, before the close compressed it
    written = os.path.getsize(path)
    assert written + compressed <= estimate
    assert 1.0 <= estimate / written < 1.8
    assert estimate / compressed >= 3.0
    assert 0.9 <= est.closed_bytes / compressed <= 2.0


def test_the_estimate_matches_a_simulated_file(tmp_path):
    sc = Scenario(name="budget", seed=2, table=TableConfig(kind="single-axis"),
                  imus=(ImuConfig(name="A", sample_rate_hz=1000.0),),
                  steps=(StaticStep(kind="static", duration_s=200.0),))
    path = tmp_path / "s.h5"
    simulate_scenario(sc, path)
    _bounds_the_run(estimate_scenario_recording(sc), path)


def test_the_estimate_matches_a_station_run(tmp_path):
    plan = generate_p1_plan(name="budget", grade="consumer", rates_dps=(-90.0, 0.0, 90.0),
                            held_out_rates_dps=(), revolutions=1, static_s=200.0, settle_s=2.0,
                            record_s=2.0, rate_settle_s=2.0, repetitions=1, warm_up_s=2.0,
                            sample_rate_hz=1000.0, seed=3)
    assert plan.twin is not None
    path = tmp_path / "run.h5"
    summary = run_plan(plan, SimStation(plan.twin), path, options=RunOptions(tick_s=2.0))
    assert summary.status == "done", summary.reason
    _bounds_the_run(estimate_plan_recording(plan), path)


def test_each_steps_start_is_the_duration_of_the_plan_before_it():
    """``plan_step_starts_s`` in one pass equals the cut plans' durations, bit for bit."""
    from imucalib.plan.budget import plan_facts, plan_step_starts_s
    from imucalib.procedures.p2.plan import generate_p2_plan

    for plan in (generate_p1_plan(), generate_p2_plan()):
        starts = plan_step_starts_s(plan, plan_facts(plan))
        assert len(starts) == len(plan.steps) + 1 and starts[0] == 0.0
        cut = [estimate_plan_recording(plan.model_copy(update={"steps": plan.steps[:i]}),
                                       plan_facts(plan)).duration_s
               for i in range(1, len(plan.steps) + 1)]
        assert list(starts[1:]) == cut
        assert starts[-1] == estimate_plan_recording(plan).duration_s
        assert all(b >= a for a, b in itertools.pairwise(starts))
