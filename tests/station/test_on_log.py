"""The runner's ``on_log`` hook: every line of the Recording's event log, to a watcher too.

The web page's live log shows the runner's own lines through it (docs/web-runs.md). A run and a
resume on the twin must hand the hook exactly the lines the recording keeps, in order (station
events included); a hook that raises must not stop the run.
"""

from __future__ import annotations

from pathlib import Path

from imucalib.io import open_recording
from imucalib.station.operator import OperatorAnswer
from imucalib.station.runner import RunOptions, resume_run, run_plan
from imucalib.station.sim import SimStation

from .conftest import small_p1


def _lines(path: Path) -> list[tuple[float, str, str, str]]:
    with open_recording(path) as rec:
        return [(float(e.time_s), e.level, e.source, e.message) for e in rec.log]


class _RefuseFirst:
    """Refuses the first operator check (a safe stop), confirms the rest."""

    def __init__(self) -> None:
        self.asked = 0

    def confirm(self, item: str) -> OperatorAnswer:
        self.asked += 1
        return OperatorAnswer(self.asked > 1, "test")


def test_the_hook_gets_every_line_the_recording_keeps_across_a_resume(tmp_path):
    plan = small_p1(static_s=5.0)
    got: list[tuple[float, str, str, str]] = []
    hook = lambda t, level, source, message: got.append((t, level, source, message))  # noqa: E731
    operator = _RefuseFirst()
    path = tmp_path / "run.h5"
    first = run_plan(plan, SimStation(plan.twin), path,
                     options=RunOptions(tick_s=2.0, operator=operator, on_log=hook))
    assert first.status != "done"                 # the refusal stopped it
    before = _lines(path)
    assert got == before and len(before) >= 3
    assert any("refused" in m or "run stopped" in m for *_x, m in before)
    got.clear()
    resumed = resume_run(path, lambda p, t: SimStation(p.twin, start_time_s=t),
                         options=RunOptions(tick_s=2.0, operator=operator, on_log=hook))
    assert resumed.status == "done"
    after = _lines(path)
    assert after[:len(before)] == before
    assert got == after[len(before):]
    assert any("run resumed at step" in m for *_x, m in got)
    assert any("completed" in m for *_x, m in got)


def test_a_failing_hook_never_stops_the_run(tmp_path):
    plan = small_p1(static_s=5.0)
    calls = []

    def hook(t: float, level: str, source: str, message: str) -> None:
        calls.append(message)
        raise RuntimeError("the watcher fell over")

    summary = run_plan(plan, SimStation(plan.twin), tmp_path / "run.h5",
                       options=RunOptions(tick_s=2.0, on_log=hook))
    assert summary.status == "done"
    assert calls == [m for *_x, m in _lines(tmp_path / "run.h5")]
