"""A stand-in for :class:`imucalib.web.supervisor.RunSupervisor` with its interface.

It runs nothing: a started run waits at an operator check on step 1, so the page's commands
(answer, abort, resume) can be tried against a known state. Import it by its path.
"""

from __future__ import annotations

import queue
from dataclasses import replace
from pathlib import Path
from typing import Any

from imucalib.web.run_errors import RunStateError, StaleCommandError, UnknownRunError
from imucalib.web.run_view import PromptView, RunView, StepView

RUN_ID = "20261129T120000Z-abcdef"


class FakeSupervisor:
    def __init__(self, runs_dir: Path) -> None:
        self.runs_dir = runs_dir
        self.calls: list[tuple[str, Any]] = []
        self._views: dict[str, RunView] = {}
        self._queues: dict[str, list[queue.Queue[dict[str, Any]]]] = {}
        self.closed = False

    def add(self, run_id: str = RUN_ID, status: str = "waiting", operator: str = "Oli") -> str:
        steps = (StepView(0, "position", "pose 1", "done"),
                 StepView(1, "operator-check", "remount", "running"),
                 StepView(2, "static", "static 2", "pending"))
        prompt = (PromptView(7, 1, "turn the cube so that its +y face points up")
                  if status == "waiting" else None)
        self._views[run_id] = RunView(
            run_id=run_id, plan_name="p1-short", status=status, recording_path="/tmp/x.h5",
            operator=operator, started_utc="2026-11-29T12:00:00Z", step_index=1, n_steps=3,
            steps=steps, time_left_s=120.0, prompt=prompt, error=None, log_tail=("started",),
            signals={"table": {"angle_deg": [0.0, 90.0]}})
        return run_id

    def _get(self, run_id: str) -> RunView:
        if run_id not in self._views:
            raise UnknownRunError(f"no run {run_id!r}")
        return self._views[run_id]

    def start(self, plan_path: Path, *, station: str, serials: list[str], operator: str) -> str:
        self.calls.append(("start", (plan_path, station, serials, operator)))
        return self.add(f"20261129T12000{len(self.calls) % 10}Z-000000", operator=operator)

    def view(self, run_id: str) -> RunView:
        return self._get(run_id)

    def runs(self) -> list[RunView]:
        return list(self._views.values())

    def answer(self, run_id: str, prompt_id: int, step_index: int, confirmed: bool, who: str,
               note: str = "") -> None:
        view = self._get(run_id)
        if view.prompt is None or (view.prompt.prompt_id, view.prompt.step_index) != (
                prompt_id, step_index):
            raise StaleCommandError(f"prompt {prompt_id} of step {step_index} is not the "
                                    f"current one of run {run_id}")
        self.calls.append(("answer", (run_id, prompt_id, step_index, confirmed, who, note)))
        self._views[run_id] = replace(view, prompt=None, status="running" if confirmed
                                      else "stopped")
        self._publish(run_id, {"type": "prompt_closed", "run_id": run_id,
                               "confirmed": confirmed, "who": who})

    def abort(self, run_id: str, step_index: int | None, who: str) -> None:
        view = self._get(run_id)
        if step_index is not None and step_index != view.step_index:
            raise StaleCommandError(f"step {step_index} is not run {run_id}'s current step")
        if view.status in ("stopped", "finished", "failed"):
            raise RunStateError(f"run {run_id} is {view.status}: nothing to abort")
        self.calls.append(("abort", (run_id, step_index, who)))
        self._views[run_id] = replace(view, status="stopped", prompt=None)
        self._publish(run_id, {"type": "status", "run_id": run_id, "status": "stopped",
                               "error": None})

    def subscribe(self, run_id: str) -> queue.Queue[dict[str, Any]]:
        view = self._get(run_id)
        q: queue.Queue[dict[str, Any]] = queue.Queue(maxsize=100)
        q.put({"type": "snapshot", "run_id": run_id, "view": view.to_dict()})
        self._queues.setdefault(run_id, []).append(q)
        return q

    def unsubscribe(self, run_id: str, q: Any) -> None:
        if q in self._queues.get(run_id, []):
            self._queues[run_id].remove(q)

    def _publish(self, run_id: str, event: dict[str, Any]) -> None:
        for q in self._queues.get(run_id, []):
            q.put(event)

    def resumable(self) -> list[RunView]:
        return [v for v in self._views.values() if v.status in ("stopped", "failed")]

    def resume(self, run_id: str, who: str) -> None:
        view = self._get(run_id)
        if view.status not in ("stopped", "failed"):
            raise RunStateError(f"run {run_id} is {view.status}: only a stopped run resumes")
        self.calls.append(("resume", (run_id, who)))
        self._views[run_id] = replace(view, status="running")

    def close(self) -> None:
        self.closed = True
