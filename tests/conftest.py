"""Shared fixtures: twin runs of small P1 plans (session-scoped), used by several test folders."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import pytest

from imucalib.plan import Plan
from imucalib.procedures import generate_p1_plan
from imucalib.station.runner import RunOptions, run_plan
from imucalib.station.sim import SimStation


def p1_plan(grade: str = "tactical", seed: int = 1, *, repetitions: int = 1,
            ideal: bool = True, static_s: float = 300.0, **kwargs) -> Plan:
    """A short P1 plan at 200 Hz; `ideal`: an ideal table and a linear IMU (truth comparable)."""
    args = dict(grade=grade, seed=seed, repetitions=repetitions, static_s=static_s,
                warm_up_s=10.0, sample_rate_hz=200.0, revolutions=2, settle_s=5.0,
                rate_settle_s=3.0, record_s=10.0)
    args.update(kwargs)
    plan = generate_p1_plan(**args)
    if ideal:
        tw = plan.twin
        assert tw is not None
        tw = tw.model_copy(update={
            "table": tw.table.model_copy(update={"grade": "ideal"}),
            "imus": tuple(i.model_copy(update={"nonlinear": False}) for i in tw.imus)})
        plan = plan.model_copy(update={"twin": tw})
    return plan


def run_twin(plan: Plan, path: Path) -> Path:
    assert plan.twin is not None
    station = SimStation(plan.twin)
    summary = run_plan(plan, station, path, options=RunOptions(tick_s=2.0, truth=station.truth))
    assert summary.status == "done", summary.reason
    return path


def write_planless_recording(path: Path) -> Path:
    """Write a Recording of the twin's IMU at rest that holds no plan (two seconds, one step).

    ``imucalib simulate`` runs its scenario as a plan, so its recordings hold one; this is what
    a recording made without a plan (an import, another tool) looks like to the analysis.
    """
    from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS
    from imucalib.io.recording import RecordingWriter
    from imucalib.io.streams import DEVICE_IMU, imu_stream_spec
    from imucalib.sim.scenario import load_scenario

    station = SimStation(load_scenario("dual-axis-p1").equipment)
    station.clock.sleep(2.0)
    src = station.imus[0]
    block = src.read()
    cols = {"time_s": block.time_s, "device_time_s": block.device_time_s,
            "counter": block.counter, "temperature_degc": block.temperature_degc,
            "saturated": block.saturated}
    for j, c in enumerate(GYRO_COLUMNS):
        cols[c] = block.gyro_rps[:, j]
    for j, c in enumerate(ACCEL_COLUMNS):
        cols[c] = block.accel_mps2[:, j]
    with RecordingWriter(path, streams=[imu_stream_spec(src.name)]) as writer:
        writer.append(DEVICE_IMU, src.name, cols)
        row = writer.begin_step("static", "at rest", 0.0)
        writer.update_step(row, t_end_s=2.0, status="done", valid_start_s=0.0, valid_end_s=2.0)
    return path


@pytest.fixture(scope="session")
def tactical_run(tmp_path_factory) -> Path:
    return run_twin(p1_plan("tactical", 3, repetitions=2), tmp_path_factory.mktemp("p1") / "t.h5")


@pytest.fixture(scope="session")
def consumer_run(tmp_path_factory) -> Path:
    return run_twin(p1_plan("consumer", 5), tmp_path_factory.mktemp("p1") / "c.h5")


@pytest.fixture(scope="session")
def p1_tools() -> SimpleNamespace:
    """The helpers above, for test modules (which cannot import conftest by name)."""
    return SimpleNamespace(p1_plan=p1_plan, run_twin=run_twin,
                           write_planless_recording=write_planless_recording)
