"""The worker's side of a supervised run: its state, events and commands, tick by tick.

:class:`RunReporter` is the runner's ``on_status`` callback in the worker process
(:mod:`imucalib.web.run_worker`). After every tick of the runner it

1. takes the supervisor's commands (:meth:`~imucalib.web.run_files.RunFiles.take_commands`):
   an abort is accepted (the supervisor checked its step against the run when the page sent it;
   stopping is always safe, so a step that ended while the command was on its way does not
   undo it); a prompt answer is kept for the operator check that waits, one for another prompt
   is refused as stale;
2. raises :class:`RunAborted` once an abort was accepted: the runner then stops the equipment
   safely and closes its Recording, as after Ctrl-C in ``imucalib run``;
3. follows the steps (running, done), the trips and the station's latest values
   (:class:`~imucalib.web.run_tap.SignalTap`), paces a twin to wall time when asked, and writes
   ``state.json`` at most :data:`STATE_HZ` times a second (at once on a change of status, step
   or prompt) and ``events.jsonl`` at every change (docs/web-runs.md);
4. for the live view (:class:`~imucalib.web.live_follow.LiveFollower`): at the end of each
   recorded step a ``window`` event with each unit's mean and σ over the step's valid window;
   during a soak the plan's criterion and where the run stands (``signals["soak"]``); a
   decimated ``trace`` event of the temperatures (docs/web.md, "Live view").
"""

from __future__ import annotations

import sys
import time
import traceback
from collections import deque
from collections.abc import Callable, Mapping
from datetime import UTC, datetime
from typing import IO, Any, TypeVar

from imucalib.plan.schema import OperatorCheckStep, Plan, step_min_duration_s
from imucalib.station.session import RunStatus
from imucalib.web.live_follow import LiveFollower
from imucalib.web.run_files import LOG_TAIL, RunFiles, to_json, write_json_atomic
from imucalib.web.run_tap import SignalTap

__all__ = ["COMMAND_POLL_S", "LOG_TAIL", "STATE_HZ", "RunAborted", "RunReporter"]

_T = TypeVar("_T")
#: Most ``state.json`` writes (and so live-sample events) a second.
STATE_HZ = 5.0
#: Wall time between two looks at the commands folder. [s]
COMMAND_POLL_S = 0.05


class RunAborted(KeyboardInterrupt):
    """The operator's abort, raised from the runner's status callback.

    A :class:`KeyboardInterrupt`, so that the runner treats it exactly as Ctrl-C in
    ``imucalib run``: the equipment is stopped safely (table to rest, centrifuge braked, chamber
    to standby), the running step is marked ``aborted`` and the Recording closed, resumable.
    """


def _utc() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


class RunReporter:
    """The state of the run in the worker, written for the supervisor (module docstring).

    Parameters
    ----------
    files : RunFiles
    plan : Plan
    operator : str
        Who started (or resumed) the run.
    tap : SignalTap
        The station's latest values.
    first_step : int
        The first step this worker runs (a resume's first step not done; the steps before it
        are shown done).
    pace : float, optional
        Wall seconds per station second (1: real time); None runs a twin as fast as it goes.
    prompt_seq : int
        The last prompt id of an earlier worker of the run (ids keep rising across resumes).
    resumed : int
        How often the run was resumed (this worker included).
    """

    def __init__(self, files: RunFiles, plan: Plan, operator: str, tap: SignalTap, *,
                 first_step: int = 0, pace: float | None = None, prompt_seq: int = 0,
                 resumed: int = 0) -> None:
        self.files, self.plan, self.tap, self.pace = files, plan, tap, pace
        n = len(plan.steps)
        self.durations = [step_min_duration_s(s) for s in plan.steps]
        self.steps = ["done" if i < first_step else "pending" for i in range(n)]
        self.next_index = first_step  # the first step not done
        self.current = first_step - 1
        self.step_start_s = 0.0
        self.time_s = 0.0
        self.done_seen = 0
        self.invalid_seen = 0
        self.last_event = ""
        self.log_tail: deque[str] = deque(maxlen=LOG_TAIL)
        self.status_text = "starting"
        self.error: str | None = None
        self.operator = operator
        self.prompt: dict[str, Any] | None = None
        self.prompt_seq = prompt_seq
        self.answer: dict[str, Any] | None = None
        self.abort: dict[str, Any] | None = None
        self.resumed = resumed
        self.phase = ""
        self.seq = 0
        self._last_write = 0.0
        self._last_poll = 0.0
        self._t0: tuple[float, float] | None = None  # (wall, station time) of the first tick
        self._events: IO[str] = files.events.open("a", encoding="utf-8")
        self.extra: dict[str, Any] = {}
        self._status: RunStatus | None = None
        self._reporting_failed = False
        self.live = LiveFollower(plan, tap)
        self._live_failed = False
        tap.on_safe_stop = self._safe_stop
        self._stopped_after_abort: set[str] = set()

    def _live(self, work: Callable[[], _T]) -> _T | None:
        """Return `work()`, or None when the live view's own bookkeeping fails.

        The live view's extras (window means, the soak, the trace) never stop the run's state
        and events: a failure is written to the worker's log once.
        """
        try:
            return work()
        except Exception:
            if not self._live_failed:
                self._live_failed = True
                traceback.print_exc(file=sys.stderr)
            return None

    # --- output -----------------------------------------------------------------------------
    def event(self, event_type: str, /, **fields: Any) -> None:
        """Append one event of type `event_type` to ``events.jsonl``."""
        body = {"type": event_type, "run_id": self.files.run_id, "utc": _utc(), **fields}
        self._events.write(to_json(body) + "\n")
        self._events.flush()

    def log(self, line: str, level: str = "info") -> None:
        """Add a line to the run's log (state tail and a ``log`` event)."""
        text = f"{datetime.now(UTC):%H:%M:%S} {level}: {line}"
        self.log_tail.append(text)
        self.event("log", line=text, level=level)

    def on_recording_log(self, time_s: float, level: str, source: str, message: str) -> None:
        """Add a line the runner wrote to the Recording's event log (the runner's ``on_log``).

        The line names its station time and source, as ``imucalib inspect`` lists the log.
        """
        self.log(f"[t={time_s:.1f} s, {source}] {message}", level)

    def set_status(self, status: str, error: str | None = None) -> None:
        """Change the run's status (written at once)."""
        self.status_text = status
        if error is not None:
            self.error = error
        self.event("status", status=status, error=self.error)
        self.write(force=True)

    def set_step(self, index: int, state: str) -> None:
        """Change a step's state (written at once)."""
        if 0 <= index < len(self.steps) and self.steps[index] != state:
            self.steps[index] = state
            if state == "running":
                self.current, self.step_start_s = index, self.time_s
                self._live(lambda: self.live.step_started(index))
                self.log(f"step {index} ({self.plan.step_label(index)}) started")
            self.event("step", index=index, state=state, label=self.plan.step_label(index),
                       kind=self.plan.steps[index].kind)
            self.write(force=True)

    def time_left_s(self) -> float:
        """Return the plan's least station time left. [s]"""
        cur = self.current if 0 <= self.current < len(self.steps) and \
            self.steps[self.current] == "running" else self.next_index
        if cur >= len(self.durations):
            return 0.0
        now = max(0.0, self.durations[cur] - (self.time_s - self.step_start_s)) \
            if self.steps[cur] == "running" else self.durations[cur]
        return float(now + sum(self.durations[cur + 1:]))

    def signals(self, status: RunStatus | None = None) -> dict[str, Any]:
        """Return the latest decimated values (``RunView.signals``)."""
        imus: dict[str, Any] = {}
        for name, values in self.tap.imus.items():
            imus[name] = {**values}
            if status is not None:
                imus[name]["rate_hz"] = status.imu_rate_hz.get(name)
                imus[name]["error"] = status.imu_errors.get(name) or None
        chamber = dict(self.tap.chamber)
        if imus:
            chamber["unit_degc"] = {k: v.get("temperature_degc") for k, v in imus.items()}
        soak = (self._live(lambda: self.live.soak(self.current, self.time_s))
                if 0 <= self.current < len(self.steps) and self.steps[self.current] == "running"
                else None)
        return {"time_s": self.time_s, "phase": self.phase,
                "table": dict(self.tap.table), "centrifuge": dict(self.tap.centrifuge),
                "chamber": chamber, "imus": imus, "soak": soak,
                "guards": {"trips": self.invalid_seen, "last_event": self.last_event,
                           "faults": dict(self.tap.faults)}}

    def write(self, force: bool = False, status: RunStatus | None = None) -> None:
        """Write ``state.json`` (at most :data:`STATE_HZ` a second unless `force`)."""
        status = status or self._status
        now = time.monotonic()
        if not force and now - self._last_write < 1.0 / STATE_HZ:
            return
        self._last_write = now
        self.seq += 1
        prompt = self.prompt if self.status_text == "waiting" else None
        write_json_atomic(self.files.state, {
            "seq": self.seq, "pid": _pid(), "status": self.status_text, "error": self.error,
            "operator": self.operator, "step_index": self.current, "steps": self.steps,
            "time_left_s": self.time_left_s(), "prompt": prompt, "prompt_seq": self.prompt_seq,
            "log_tail": list(self.log_tail), "signals": {**self.signals(status),
                                                           "wall_unix": time.time()},
            "resumed": self.resumed, "updated_utc": _utc(), **self.extra})

    def close(self) -> None:
        """Close ``events.jsonl``."""
        self._events.close()

    # --- the runner's callback --------------------------------------------------------------
    def on_status(self, status: RunStatus) -> None:
        """Follow the run after a tick or a step; raise :class:`RunAborted` on an abort.

        A failure of the reporting itself (a full disk under the run's folder) is written to
        the worker's log and never stops the run; only an abort does.
        """
        try:
            self._follow(status)
        except Exception:
            if not self._reporting_failed:
                self._reporting_failed = True
                traceback.print_exc(file=sys.stderr)
        self.check_abort()
        if self.pace:
            self._keep_pace(status.time_s)

    def _follow(self, status: RunStatus) -> None:
        self._status = status
        self.time_s = status.time_s
        self.phase = status.phase
        self._live(lambda: self.live.tick(status.time_s, status.step_index))
        if status.steps_done > self.done_seen:
            self.done_seen = status.steps_done
            window = self._live(lambda: self.live.window_event(status.step_index))
            if window is not None:
                self.event("window", **window)
            self.set_step(status.step_index, "done")
            self.next_index = max(self.next_index, status.step_index + 1)
        elif 0 <= status.step_index < len(self.steps) and self.steps[status.step_index] != "done":
            self.set_step(status.step_index, "running")
        if status.steps_invalid > self.invalid_seen:
            self.invalid_seen = status.steps_invalid
        if status.last_event and status.last_event != self.last_event:
            self.last_event = status.last_event
            self.log(status.last_event, "warning" if status.last_event.startswith("trip")
                     else "info")
        point = self._live(lambda: self.live.trace_point(status.time_s, status.step_index))
        if point is not None:
            self.event("trace", **point)
        self.poll_commands()
        self.write(status=status)

    def check_abort(self) -> None:
        """Raise :class:`RunAborted` when an abort was accepted."""
        if self.abort is not None:
            raise RunAborted(f"aborted by {self.abort.get('who', '?')}")

    def request_abort(self, who: str, sent_unix: float | None = None) -> None:
        """Accept an abort (a command, or a signal to the worker)."""
        if self.abort is None:
            self.abort = {"who": who, "sent_unix": sent_unix or time.time()}
            self.log(f"abort requested by {who}; stopping the equipment safely", "warning")
            self.set_status("aborting")

    def _keep_pace(self, time_s: float) -> None:
        if not self.pace:
            return
        now = time.monotonic()
        if self._t0 is None:
            self._t0 = (now, time_s)
        due = self._t0[0] + (time_s - self._t0[1]) * self.pace
        while (wait := due - time.monotonic()) > 0:
            time.sleep(min(wait, COMMAND_POLL_S))
            self.poll_commands(force=True)
            self.check_abort()

    def _safe_stop(self, device: str, wall: float) -> None:
        sent = self.abort.get("sent_unix") if self.abort else None
        latency = wall - sent if isinstance(sent, float | int) else None
        self.event("safe_stop", device=device, latency_s=latency)
        self.log(f"{device} stopped safely" + (f" ({latency:.3f} s after the abort)"
                                               if latency is not None else ""), "warning")
        if self.abort is None or "safe_stopped_unix" in self.extra:
            return
        self._stopped_after_abort.add(device)
        if self._stopped_after_abort >= self.tap.stoppable:
            # the supervisor's abort watch gives the close its own time from here
            # (imucalib.web.abort_watch)
            self.extra["safe_stopped_unix"] = wall
            self.event("safe_stop_done", latency_s=latency)
            self.write(force=True)

    # --- commands ---------------------------------------------------------------------------
    def poll_commands(self, force: bool = False) -> None:
        """Take the waiting commands (at most every :data:`COMMAND_POLL_S` unless `force`)."""
        now = time.monotonic()
        if not force and now - self._last_poll < COMMAND_POLL_S:
            return
        self._last_poll = now
        for cmd in self.files.take_commands():
            kind = cmd.get("type")
            if kind == "abort":  # checked against the page by the supervisor; stopping is
                # always safe, so one the run outran in transit is honoured all the same
                self.request_abort(str(cmd.get("who", "?")), cmd.get("sent_unix"))
            elif kind == "answer":
                p = self.prompt
                if p is None or self.status_text != "waiting" or \
                        cmd.get("prompt_id") != p["prompt_id"] or \
                        cmd.get("step_index") != p["step_index"]:
                    self._reject(cmd, f"answer to prompt {cmd.get('prompt_id')}, which is not "
                                      "the open one")
                else:
                    self.answer = cmd
            else:
                self._reject(cmd, f"unknown command {kind!r}")

    def _reject(self, cmd: Mapping[str, Any], reason: str) -> None:
        self.event("command_rejected", command=dict(cmd), reason=reason)
        self.log(f"command refused: {reason}", "warning")

    # --- prompts ----------------------------------------------------------------------------
    def open_prompt(self, item: str) -> dict[str, Any]:
        """Open the prompt of the operator check `item` (the next such step); return it."""
        index = next((i for i in range(max(self.next_index, 0), len(self.plan.steps))
                      if isinstance(s := self.plan.steps[i], OperatorCheckStep)
                      and s.item == item), self.next_index)
        step = self.plan.steps[index] if 0 <= index < len(self.plan.steps) else None
        details: dict[str, Any] = {}
        if isinstance(step, OperatorCheckStep):
            for key in ("remount", "remount_yaw_deg", "swap_units", "centrifuge_load_kg"):
                value = getattr(step, key)
                if value is not None and not (key == "remount_yaw_deg" and step.remount is None):
                    details[key] = list(value) if isinstance(value, tuple) else value
        self.prompt_seq += 1
        self.prompt = {"prompt_id": self.prompt_seq, "step_index": index, "text": item,
                       "details": details}
        self.answer = None
        self.set_step(index, "running")
        self.event("prompt", **self.prompt)
        self.log(f"operator check, step {index}: {item}")
        self.set_status("waiting")
        return self.prompt

    def close_prompt(self, confirmed: bool, who: str) -> None:
        """Close the open prompt (answered)."""
        if self.prompt is not None:
            self.event("prompt_closed", prompt_id=self.prompt["prompt_id"],
                       step_index=self.prompt["step_index"], confirmed=confirmed, who=who)
            self.log(f"operator check {'confirmed' if confirmed else 'refused'} by {who}",
                     "info" if confirmed else "warning")
        self.prompt, self.answer = None, None
        self._t0 = None  # a paced twin does not race to make up for the wait
        self.set_status("running")


def _pid() -> int:
    import os

    return os.getpid()
