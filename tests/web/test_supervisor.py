"""The run supervisor of the web page (docs/web-runs.md): runs on the twin in worker processes.

Each test starts a small P1 plan (``small_plan_file``: an operator check, then a few minutes of
station time) through :class:`RunSupervisor`; the worker is a real process running the runner
of ``imucalib run``. The runs record into the test's own records database, never the user's.
The tests that only read a run answered and followed to its end share one (``answered``, made
once per module): each worker process costs seconds of interpreter start and imports.
"""

from __future__ import annotations

import os
import queue
import signal
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from imucalib.errors import ConfigurationError
from imucalib.io import open_recording
from imucalib.station.runner import find_resume_point
from imucalib.web.events import SubscriberQueue
from imucalib.web.supervisor import (
    RunStateError,
    RunSupervisor,
    StaleCommandError,
    UnknownRunError,
)

#: Wall seconds per station second for the runs an abort must catch midway (the small plan is
#: about 330 s of station time: some 3 s of wall time at this pace, the abort or the kill comes
#: within a poll, 0.05 s, of the step the test waits for; the twin's own run takes about 1 s of
#: CPU time).
PACE = 0.01


@pytest.fixture
def plan_file(tmp_path: Path, p1_tools) -> Path:
    folder = tmp_path / "plans"
    folder.mkdir()
    return p1_tools.small_plan_file(folder)


def _supervisor(folder: Path) -> RunSupervisor:
    """A supervisor of runs under `folder`, recording into a records database of its own."""
    return RunSupervisor(folder / "runs", db=f"sqlite:///{folder / 'records.db'}")


def _stop(s: RunSupervisor) -> None:
    """Close `s` and kill the workers of its runs still live: never leave a worker behind."""
    s.close()
    for v in s.runs():
        pid_file = s.runs_dir / v.run_id / "worker.pid"
        if v.status in ("starting", "running", "waiting", "aborting") and pid_file.exists():
            try:
                os.kill(int(pid_file.read_text()), signal.SIGKILL)
            except ProcessLookupError:
                pass


@pytest.fixture
def sup(tmp_path: Path) -> Iterator[RunSupervisor]:
    s = _supervisor(tmp_path)
    yield s
    _stop(s)


def wait_for(check, timeout_s: float = 30.0, every_s: float = 0.05):
    """Poll `check()` until it returns something truthy; return it."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        got = check()
        if got:
            return got
        time.sleep(every_s)
    raise AssertionError(f"not reached within {timeout_s} s")


def prompt_of(sup: RunSupervisor, run_id: str):
    return wait_for(lambda: sup.view(run_id).prompt)


def ended(sup: RunSupervisor, run_id: str, timeout_s: float = 40.0):
    return wait_for(lambda: (v := sup.view(run_id)).status in ("stopped", "finished", "failed")
                    and v, timeout_s)


def why(sup: RunSupervisor, v) -> str:
    """What a failing assertion shows: the run's error, log and worker output."""
    log = (sup.runs_dir / v.run_id / "worker.log")
    return "\n".join([f"{v.status}: {v.error}", *v.log_tail,
                      log.read_text(errors="replace")[-3000:] if log.exists() else ""])


def drain(q: queue.Queue, until: str, timeout_s: float = 40.0) -> list[dict]:
    out = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            event = q.get(timeout=0.5)
        except queue.Empty:
            continue
        out.append(event)
        if event["type"] == until:
            return out
    raise AssertionError(f"no {until!r} event; got {[e['type'] for e in out]}")


def _raised(command: Callable[..., Any], *args: Any) -> Exception | None:
    """Return what `command(*args)` raised (None: nothing), for a test to check afterwards."""
    try:
        command(*args)
    except Exception as exc:  # the test asserts its type
        return exc
    return None


@pytest.fixture(scope="module")
def answered(tmp_path_factory: pytest.TempPathFactory, p1_tools: Any) -> SimpleNamespace:
    """One run of the small plan, its operator check answered by bob, followed to its end and
    calibrated; with what the stale commands tried while the prompt waited, and the commands
    tried once it had finished, raised.

    Made once per module for the tests that only read it, in a folder, a records database and
    key folders of its own (the autouse ``_isolated`` is per test, so this sets its own).
    """
    from imucalib.calibration import procedure_of

    folder = tmp_path_factory.mktemp("answered")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("XDG_CONFIG_HOME", str(folder / "config"))
        mp.delenv("IMUCALIB_RECORDS_SIGNING", raising=False)
        (folder / "plans").mkdir()
        plan = p1_tools.small_plan_file(folder / "plans")
        s = _supervisor(folder)
        try:
            run_id = s.start(plan, station="sim", serials=["IMU-0001"], operator="alice")
            q = s.subscribe(run_id)
            first = q.get(timeout=5)
            p = prompt_of(s, run_id)
            # commands for another prompt or step are stale
            stale = [_raised(s.answer, run_id, p.prompt_id + 1, p.step_index, True, "bob"),
                     _raised(s.answer, run_id, p.prompt_id, p.step_index + 1, True, "bob"),
                     _raised(s.abort, run_id, p.step_index + 3, "bob")]
            s.answer(run_id, p.prompt_id, p.step_index, True, "bob", note="checked")
            events = drain(q, "end")
            v = s.view(run_id)
            # the prompt is gone: answering it again is stale; a finished run is not aborted
            after = (_raised(s.answer, run_id, p.prompt_id, p.step_index, True, "bob"),
                     _raised(s.abort, run_id, None, "bob"))
            resumable = s.resumable()
            s.unsubscribe(run_id, q)
            calibration = (procedure_of(v.recording_path).analyze(v.recording_path).calibration
                           if v.status == "finished" else None)
        finally:
            _stop(s)
    return SimpleNamespace(plan=plan, run_id=run_id, first=first, prompt=p, stale=stale,
                           events=events, view=v, after=after, resumable=resumable,
                           calibration=calibration, why=why(s, v))


def test_a_run_streams_its_events_and_finishes_with_a_recording_that_calibrates(answered):
    run_id, p, v = answered.run_id, answered.prompt, answered.view
    first = answered.first
    assert first["type"] == "snapshot" and first["view"]["run_id"] == run_id
    assert p.step_index == 0 and p.text.startswith("IMU mounted")
    # commands for another prompt or step were stale
    assert all(isinstance(e, StaleCommandError) for e in answered.stale), answered.stale
    events = answered.events
    kinds = {e["type"] for e in events}
    assert {"prompt", "prompt_closed", "step", "signals", "log", "status", "end"} <= kinds
    assert all(e["run_id"] == run_id for e in events)
    sample = next(e for e in events if e["type"] == "signals" and e["signals"]["imus"])
    assert len(sample["signals"]["imus"]["IMU-0001"]["gyro_dps"]) == 3
    assert v.status == "finished" and v.error is None and v.prompt is None, answered.why
    assert [s.state for s in v.steps] == ["done"] * v.n_steps and v.time_left_s == 0.0
    assert v.signals["table"]["angle_deg"] and v.log_tail
    # the prompt gone, answering it again was stale; the finished run was not aborted
    stale_again, abort_finished = answered.after
    assert isinstance(stale_again, StaleCommandError), stale_again
    assert isinstance(abort_finished, RunStateError), abort_finished
    assert answered.resumable == []
    with open_recording(v.recording_path) as rec:
        assert not rec.was_open_for_write
        assert len(rec.steps) == v.n_steps and all(s.status == "done" for s in rec.steps)
        assert rec.steps[0].note.startswith("confirmed by bob at ")
        assert rec.metadata["run_operator"] == "alice"
    assert v.records_run_id is not None  # recorded as `imucalib run` records it
    assert answered.calibration is not None


def test_a_refused_or_aborted_prompt_stops_safely_and_the_run_resumes(sup, plan_file):
    run_id = sup.start(plan_file, station="sim", serials=[], operator="alice")
    p = prompt_of(sup, run_id)
    sup.answer(run_id, p.prompt_id, p.step_index, False, "bob", note="cable loose")
    v = ended(sup, run_id)
    assert v.status == "stopped" and "did not confirm" in v.error, why(sup, v)
    assert v.steps[0].state == "failed"
    with open_recording(v.recording_path) as rec:
        assert not rec.was_open_for_write
        assert rec.steps[0].status == "aborted"
    assert find_resume_point(v.recording_path).first_step == 0
    assert [r.run_id for r in sup.resumable()] == [run_id]
    sup.resume(run_id, "carol")
    with pytest.raises(RunStateError):
        sup.resume(run_id, "carol")  # already live
    p2 = prompt_of(sup, run_id)
    assert p2.prompt_id > p.prompt_id and p2.step_index == 0
    sup.abort(run_id, p2.step_index, "carol")  # an abort while the prompt waits
    v = ended(sup, run_id)
    assert v.status == "stopped" and "aborted by carol" in v.error, why(sup, v)
    assert v.prompt is None
    sup.resume(run_id, "carol")
    p3 = prompt_of(sup, run_id)
    assert p3.prompt_id > p2.prompt_id
    sup.answer(run_id, p3.prompt_id, p3.step_index, True, "carol")
    v = ended(sup, run_id)
    assert v.status == "finished", why(sup, v)
    assert v.resumed == 2 and sup.resumable() == []
    assert find_resume_point(v.recording_path).first_step == v.n_steps


def test_abort_mid_run_stops_the_equipment_and_the_recording_resumes(sup, plan_file):
    run_id = sup.start(plan_file, station="sim", serials=[], operator="alice", pace=PACE)
    q = sup.subscribe(run_id)
    p = prompt_of(sup, run_id)
    sup.answer(run_id, p.prompt_id, p.step_index, True, "alice")
    wait_for(lambda: sup.view(run_id).step_index >= 4)

    def abort_as_shown() -> bool:  # as a page does: the step it shows; again if it moved on
        try:
            sup.abort(run_id, sup.view(run_id).step_index, "alice")
        except StaleCommandError:
            return False
        return True

    wait_for(abort_as_shown)
    events = drain(q, "end")
    stops = {e["device"]: e["latency_s"] for e in events if e["type"] == "safe_stop"}
    assert "table" in stops and 0.0 <= stops["table"] < 5.0
    v = sup.view(run_id)
    assert v.status == "stopped" and "aborted by alice" in v.error, why(sup, v)
    point = find_resume_point(v.recording_path)
    assert 4 <= point.first_step < v.n_steps
    with open_recording(v.recording_path) as rec:
        assert not rec.was_open_for_write
        # the runner's Ctrl-C path: logged, and the step it cut short (if one ran) aborted
        assert any("run interrupted: RunAborted: aborted by alice" in e.message
                   for e in rec.log)
        assert all(s.status != "running" for s in rec.steps)
    assert [r.run_id for r in sup.resumable()] == [run_id]
    sup.resume(run_id, "alice")
    v = ended(sup, run_id)
    assert v.status == "finished", why(sup, v)
    with open_recording(v.recording_path) as rec:
        done = {s.commanded["plan_step"] for s in rec.steps if s.status == "done"}
    assert done == set(range(v.n_steps))


def test_a_new_supervisor_finds_the_running_run_and_a_killed_one_resumes(tmp_path, sup,
                                                                          plan_file):
    run_id = sup.start(plan_file, station="sim", serials=[], operator="alice", pace=PACE)
    prompt_of(sup, run_id)
    sup.close()  # the server goes: the run waits on
    again = RunSupervisor(tmp_path / "runs")
    try:
        [v] = again.runs()
        assert v.run_id == run_id and v.status == "waiting" and v.prompt is not None
        q = again.subscribe(run_id)
        assert q.get(timeout=5)["type"] == "snapshot"
        again.answer(run_id, v.prompt.prompt_id, v.prompt.step_index, True, "alice")
        wait_for(lambda: again.view(run_id).step_index >= 3)
        pid = int((tmp_path / "runs" / run_id / "worker.pid").read_text())
        os.kill(pid, signal.SIGKILL)  # the worker dies: its recording is left open
        v = wait_for(lambda: (v := again.view(run_id)).status == "failed" and v)
        assert "resumed" in v.error
        assert [r.run_id for r in again.resumable()] == [run_id]
        again.resume(run_id, "alice")
        v = ended(again, run_id)
        assert v.status == "finished", why(sup, v)
        assert Path(v.recording_path).with_name(
            Path(v.recording_path).stem + ".crashed.h5").exists()
    finally:
        again.close()


def test_bad_requests_are_refused_before_anything_starts(sup, plan_file, tmp_path):
    with pytest.raises(UnknownRunError):
        sup.view("../etc")
    with pytest.raises(UnknownRunError):
        sup.view("20260101T000000Z-abcdef")
    with pytest.raises(ConfigurationError, match="not the twin's units"):
        sup.start(plan_file, station="sim", serials=["SN-1"], operator="alice")
    with pytest.raises(ConfigurationError, match="not found"):
        sup.start(plan_file, station=str(tmp_path / "none.toml"), serials=[], operator="a")
    assert sup.runs() == []


def test_a_slow_subscriber_loses_old_samples_never_states_or_prompts():
    q = SubscriberQueue(max_samples=3, max_total=20)
    q.publish({"type": "status", "status": "running"})
    for i in range(10):
        q.publish({"type": "signals", "i": i})
    q.publish({"type": "prompt", "prompt_id": 1})
    for i in range(10, 40):
        q.publish({"type": "log", "i": i})
    got = [q.get_nowait() for _ in range(q.qsize())]
    kinds = [e["type"] for e in got]
    assert kinds.count("status") == 1 and kinds.count("prompt") == 1
    assert [e["i"] for e in got if e["type"] == "signals"] == []  # beyond max_total: dropped
    assert len(got) == 20 and q.dropped == 7 + 3 + 12
    q = SubscriberQueue(max_samples=3)
    for i in range(10):
        q.publish({"type": "signals", "i": i})
    assert [q.get_nowait()["i"] for _ in range(3)] == [7, 8, 9]


def test_the_page_and_imucalib_run_record_data_that_calibrate_identically(answered, tmp_path):
    """No second way of running a plan: the same plan on the twin, one run through the
    supervisor (``answered``) and one through ``imucalib run --yes``, calibrate to the same
    numbers."""
    import numpy as np
    from typer.testing import CliRunner

    from imucalib.calibration import procedure_of
    from imucalib.cli import app

    assert answered.view.status == "finished", answered.why
    result = CliRunner().invoke(app, ["run", str(answered.plan), "--station", "sim", "--out",
                                      str(tmp_path / "cli.h5"), "--yes", "--operator", "alice",
                                      "--no-record"])
    assert result.exit_code == 0, result.output
    web = answered.calibration
    cli = procedure_of(tmp_path / "cli.h5").analyze(tmp_path / "cli.h5").calibration
    assert web.param_names == cli.param_names
    np.testing.assert_array_equal(web.values, cli.values)
    np.testing.assert_array_equal(web.covariance, cli.covariance)
