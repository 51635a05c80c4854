"""An abort whose safe stop hangs: the supervisor ends the worker (docs/web-runs.md, "Abort").

The worker runs the real run worker with one change: the twin's table hangs (sleeps an hour) in
``poll`` or in ``safe_stop`` once the test asks it to, as a driver waiting for an answer that
never comes. An abort then cannot complete: after the supervisor's bound (2 s here, 10 s by
default) the worker is ended — SIGTERM, then SIGKILL — and the run is ``failed`` with one line
saying why, and resumable; resumed (without the hang), it finishes. An abort that completes is
never escalated. The close bound is checked on the watch itself.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from imucalib.web.abort_watch import watch_abort
from imucalib.web.run_files import RunFiles, pid_alive, write_json_atomic
from imucalib.web.supervisor import RunSupervisor

ESCALATE_S = 2.0
_HANGING_WORKER = '''
import sys, time
from pathlib import Path

folder = Path([a for a in sys.argv[1:] if not a.startswith("--")][0])
import imucalib.drivers.station_spec as spec

real = spec.make_station


def make_station(*args, **kwargs):
    station, toml = real(*args, **kwargs)
    table = station.table
    for name in ("poll", "safe_stop"):
        def hanging(*a, _inner=getattr(table, name), _name=name, **k):
            flag = folder / "HANG"
            if flag.exists() and flag.read_text() == _name:
                (folder / "HUNG").write_text(_name)
                time.sleep(3600)
            return _inner(*a, **k)
        setattr(table, name, hanging)
    return station, toml


spec.make_station = make_station
from imucalib.web.run_worker import main

sys.exit(main(sys.argv[1:]))
'''


@pytest.fixture
def hanging_python(tmp_path: Path) -> str:
    """An 'interpreter' for the supervisor that runs the worker with a table that can hang."""
    script = tmp_path / "hanging_worker.py"
    script.write_text(_HANGING_WORKER, encoding="utf-8")
    wrapper = tmp_path / "python-hanging"
    # the supervisor runs `PYTHON -m imucalib.web.run_worker FOLDER [--resume]`
    wrapper.write_text(f'#!/bin/sh\nshift 2\nexec "{sys.executable}" "{script}" "$@"\n',
                       encoding="utf-8")
    wrapper.chmod(0o755)
    return str(wrapper)


def _wait(predicate, timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, what
        time.sleep(0.05)


def _answer_prompts(sup: RunSupervisor, run_id: str, answered: set[int]) -> None:
    p = sup.view(run_id).prompt
    if p is not None and p.prompt_id not in answered:
        sup.answer(run_id, p.prompt_id, p.step_index, True, "alice")
        answered.add(p.prompt_id)


@pytest.mark.parametrize("hang", ["poll", "safe_stop", None])
def test_an_abort_that_hangs_ends_the_worker_and_leaves_the_run_resumable(
        tmp_path, p1_tools, hanging_python, hang):
    plan = p1_tools.small_plan_file(tmp_path)
    sup = RunSupervisor(tmp_path / "runs", record=False, python=hanging_python,
                        abort_escalate_s=ESCALATE_S)
    try:
        run_id = sup.start(plan, station="sim", serials=[], operator="alice", pace=1.0)
        folder = sup.runs_dir / run_id
        answered: set[int] = set()

        def running() -> bool:
            _answer_prompts(sup, run_id, answered)
            v = sup.view(run_id)
            return v.status == "running" and v.step_index >= 1

        _wait(running, 60, "the run did not get going")
        pid = int((folder / "worker.pid").read_text())
        if hang is not None:
            (folder / "HANG").write_text(hang)
        if hang == "poll":  # stuck in the device call before the abort comes
            _wait((folder / "HUNG").exists, 10, "the table's poll did not hang")
        sent = time.monotonic()
        sup.abort(run_id, None, "alice")

        def ended() -> bool:
            v = sup.view(run_id)
            if hang is None:
                return v.status not in ("running", "aborting", "waiting")
            # the worker is gone a moment before the supervisor has written why
            return v.status == "failed" and "did not complete" in (v.error or "")

        _wait(ended, 30, "the run did not end after the abort")
        took_s = time.monotonic() - sent
        v = sup.view(run_id)
        print(f"hang={hang}: ended {v.status} {took_s:.2f} s after the abort")
        if hang is None:  # a safe stop that completes is never escalated
            assert v.status == "stopped" and took_s < ESCALATE_S, (v.status, took_s, v.error)
            events = [json.loads(x) for x in (folder / "events.jsonl").read_text().splitlines()]
            assert any(e["type"] == "safe_stop_done" for e in events)
            return
        assert (folder / "HUNG").read_text() == hang
        assert v.status == "failed", v.error
        assert ESCALATE_S <= took_s < ESCALATE_S + 10, took_s
        assert v.error is not None and f"did not complete within {ESCALATE_S:g} s" in v.error
        assert "check the station" in v.error and "resume" in v.error
        assert not pid_alive(pid, str(folder.resolve()))
        events = [json.loads(x) for x in (folder / "events.jsonl").read_text().splitlines()]
        assert events[-1]["type"] == "end" and events[-1]["status"] == "failed"
        assert [r.run_id for r in sup.resumable()] == [run_id]
        if hang == "safe_stop":
            return
        # the recording was crash-safe: resumed without the hang (and unpaced), it finishes
        (folder / "HANG").unlink()
        cfg = json.loads((folder / "run.json").read_text())
        write_json_atomic(folder / "run.json", {**cfg, "pace": None})
        sup.resume(run_id, "alice")

        def resumed_ended() -> bool:
            _answer_prompts(sup, run_id, answered)
            return sup.view(run_id).status in ("finished", "stopped", "failed")

        _wait(resumed_ended, 120, "the resumed run did not end")
        assert sup.view(run_id).status == "finished", sup.view(run_id).error
    finally:
        sup.close()
        if "run_id" in locals():
            try:
                os.kill(int((sup.runs_dir / run_id / "worker.pid").read_text()), 9)
            except (OSError, ValueError):
                pass


def test_the_close_of_the_recording_gets_its_own_bound(tmp_path):
    files = RunFiles(tmp_path / "20261129T120000Z-abcdef")
    files.folder.mkdir()
    write_json_atomic(files.state, {"seq": 3, "status": "aborting", "steps": ["done", "running"],
                                    "safe_stopped_unix": time.time()})
    worker = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)",
                               str(files.folder.resolve())])
    try:
        sent = time.monotonic()
        escalated = watch_abort(files, lambda: worker.poll() is None, lambda: worker.pid,
                                escalate_s=0.5, close_s=1.0, who="alice", sent_at=sent,
                                wait=lambda pid, t: None)
        took_s = time.monotonic() - sent
    finally:
        worker.kill()
        worker.wait()
    assert escalated and 1.5 <= took_s < 5.0, took_s   # 0.5 s for the stop, 1 s for the close
    state = files.read_state()
    assert state is not None and state["status"] == "failed" and state["steps"][1] == "failed"
    assert "did not close within 1 s of the safe stop" in state["error"]
    assert worker.returncode == -15                        # SIGTERM was enough


def test_a_run_that_ends_by_itself_is_left_alone(tmp_path):
    files = RunFiles(tmp_path / "20261129T120000Z-abcdef")
    files.folder.mkdir()
    write_json_atomic(files.state, {"status": "stopped"})
    ends = iter([True, True, False])
    assert not watch_abort(files, lambda: next(ends), lambda: None, escalate_s=5.0, who="a",
                           sent_at=time.monotonic())
    assert files.read_state() == {"status": "stopped"}
