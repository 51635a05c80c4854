"""SIGKILL of `imucalib run` mid-plan, then `imucalib run --resume`: nothing lost or repeated."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from imucalib.errors import RecordingError
from imucalib.io import open_recording
from imucalib.plan import write_plan
from imucalib.station.runner import find_resume_point, resume_run, run_plan
from imucalib.station.sim import SimStation

from .conftest import small_p1

CLI = [sys.executable, "-m", "imucalib.cli"]


def done_counts(path: Path) -> list[tuple[int, str, int]]:
    with open_recording(path) as rec:
        return [(s.commanded["plan_step"], s.kind,
                 len(rec.read_step(s.index, "imu", "IMU-0001")) if s.has_valid_window else 0)
                for s in rec.steps if s.status == "done"]


def wait_for_steps(path: Path, n_done: int, proc: subprocess.Popen, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        assert proc.poll() is None, "the run ended before it could be killed"
        if path.exists():
            try:
                with open_recording(path) as rec:
                    if sum(s.status == "done" for s in rec.steps) >= n_done:
                        return
            except RecordingError:
                pass  # caught between creation and the first flush
        time.sleep(0.05)
    raise AssertionError(f"{n_done} steps not done within {timeout_s} s")


@pytest.mark.slow
def test_sigkill_then_resume_matches_an_uninterrupted_run(tmp_path):
    plan = small_p1(static_s=1500.0, name="killme")
    plan_file = write_plan(plan, tmp_path / "plan.toml")
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen([*CLI, "run", str(plan_file), "--station", "sim", "--out", str(out),
                             "--yes", "--no-live", "--tick-s", "0.5"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    try:
        deadline = time.monotonic() + 60
        while not (out.exists() and list(out.glob("killme-*.h5"))):
            assert time.monotonic() < deadline and proc.poll() is None, proc.stderr
            time.sleep(0.02)
        path = next(out.glob("killme-*.h5"))
        wait_for_steps(path, 9, proc, 60)  # steps 0–8 done: inside the level static record
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    with open_recording(path) as rec:
        assert rec.was_open_for_write
        n_before = sum(s.status == "done" for s in rec.steps)
    point = find_resume_point(path)
    assert point.first_step == n_before  # steps are sequential: the first not done
    resumed = subprocess.run([*CLI, "run", "--resume", str(path), "--yes", "--no-live"],
                             capture_output=True, text=True, timeout=300, env=env, check=False)
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert path.with_name(f"{path.stem}.crashed.h5").exists()  # the original is kept
    reference = run_plan(plan, SimStation(plan.twin), tmp_path / "ref.h5")
    assert reference.status == "done"
    got, ref = done_counts(path), done_counts(tmp_path / "ref.h5")
    assert [g[:2] for g in got] == [r[:2] for r in ref]  # every step once, in order
    for g, r in zip(got, ref, strict=True):
        assert abs(g[2] - r[2]) <= (2 if g[1] == "rate" else 1), (g, r)
    with open_recording(path) as rec:
        assert not rec.was_open_for_write
        statuses = [s.status for s in rec.steps]
        assert statuses.count("aborted") <= 1  # the step the kill interrupted, if any
        assert any("run resumed at step" in e.message for e in rec.log)
        times = rec.read_stream("imu", "IMU-0001", ["counter"]).time_s
        assert (times[1:] >= times[:-1]).all()  # one time base across the resume


def test_resume_of_a_finished_run_is_refused(tmp_path):
    plan = small_p1(static_s=5.0)
    run_plan(plan, SimStation(plan.twin), tmp_path / "done.h5")
    with pytest.raises(RecordingError, match="every step of plan 'small-p1' is already done"):
        resume_run(tmp_path / "done.h5", lambda p, t: SimStation(p.twin, start_time_s=t))


def test_resume_after_a_stopped_run_continues_where_it_stopped(tmp_path):
    plan = small_p1(static_s=5.0)
    station = SimStation(plan.twin)
    station.at(40.0, lambda: station.table.drop_connection(permanent=True))
    first = run_plan(plan, station, tmp_path / "r.h5")
    assert first.status == "aborted"
    point = find_resume_point(tmp_path / "r.h5")
    summary = resume_run(tmp_path / "r.h5",
                         lambda p, t: SimStation(p.twin, start_time_s=t))
    assert summary.status == "done"
    got = done_counts(tmp_path / "r.h5")
    assert [g[0] for g in got] == list(range(len(plan.steps)))
    assert summary.start_s > first.end_s and point.first_step > 0
