"""The run supervisor of the web server: start, watch, answer, abort and resume runs.

:class:`RunSupervisor` is a library with no HTTP: the server (:mod:`imucalib.web`) calls it. Each
run has a folder under the supervisor's runs folder and a worker process
(:mod:`imucalib.web.run_worker`) that runs the plan with the runner of ``imucalib run``; the two
talk through the run's files (:mod:`imucalib.web.run_files`): the worker writes its state and
events, the supervisor writes commands. Nothing lives only in the supervisor: closing it (or the
server dying) leaves the workers running, and a new supervisor on the same folder finds them;
a run whose worker died unfinished is offered by :meth:`RunSupervisor.resumable`
(docs/web-runs.md).

Commands carry the run id and the prompt or step the page showed; one that no longer matches
the run raises :class:`~imucalib.web.run_errors.StaleCommandError` (and the worker checks again
when it takes it).
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from imucalib.errors import ConfigurationError, InvalidInputError, RecordingError
from imucalib.web.abort_watch import ABORT_ESCALATE_S, watch_abort
from imucalib.web.events import SubscriberQueue
from imucalib.web.run_errors import RunStateError, StaleCommandError, UnknownRunError
from imucalib.web.run_files import (
    RUN_ID_PATTERN,
    RunFiles,
    pid_alive,
    write_json_atomic,
)
from imucalib.web.run_view import LIVE_STATUSES, RunView, build_view

__all__ = ["RunStateError", "RunSupervisor", "RunView", "StaleCommandError", "UnknownRunError"]

#: Wall time between two looks of the supervisor at the runs it streams. [s]
FOLLOW_S = 0.1
#: Wall time a resume waits for the worker of an ended run to exit. [s]
EXIT_WAIT_S = 30.0


@dataclass
class _Follow:
    """Where the supervisor is in one run's files, and who listens."""

    files: RunFiles
    offset: int
    seq: int = -1
    status: str = ""
    queues: list[SubscriberQueue] = field(default_factory=list)


class RunSupervisor:
    """Start and watch runs, each in a worker process, under `runs_dir` (module docstring).

    Parameters
    ----------
    runs_dir : Path
        The folder of the runs (one sub-folder each, named by run id); created if need be.
    db : str, optional
        The records database the runs are recorded in (``imucalib run --db``; default
        ``$IMUCALIB_DB``, else the user's).
    record : bool
        Record each new run in the records database, as ``imucalib run`` does (its station's
        equipment due dates are checked all the same).
    tick_s : float, optional
        The runner's tick (``imucalib run --tick-s``; default 2 s on the twin, 0.5 s on
        equipment).
    python : str
        The interpreter of the workers.
    abort_escalate_s : float
        How long an abort's safe stop may take before the worker is ended and the run marked
        ``failed`` (:mod:`imucalib.web.abort_watch`). [s]
    """

    def __init__(self, runs_dir: Path, *, db: str | None = None, record: bool = True,
                 tick_s: float | None = None, python: str = sys.executable,
                 abort_escalate_s: float = ABORT_ESCALATE_S) -> None:
        if not abort_escalate_s > 0:
            raise InvalidInputError(f"`abort_escalate_s` must be > 0; got {abort_escalate_s!r}")
        self.runs_dir = Path(runs_dir)
        self.runs_dir.mkdir(parents=True, exist_ok=True)
        self.db, self.record, self.tick_s, self.python = db, record, tick_s, python
        self.abort_escalate_s = float(abort_escalate_s)
        self._watches: dict[str, threading.Thread] = {}
        self._procs: dict[str, subprocess.Popen[bytes]] = {}
        self._follows: dict[str, _Follow] = {}
        self._lock = threading.Lock()
        self._resume_lock = threading.Lock()
        self._points: dict[str, tuple[tuple[int, int], int | None]] = {}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # --- runs -------------------------------------------------------------------------------
    def start(self, plan_path: Path, *, station: str, serials: list[str], operator: str,
              pace: float | None = None, override_due: str | None = None) -> str:
        """Start a run of the plan at `plan_path`; return its run id.

        Parameters
        ----------
        plan_path : Path
            The plan (TOML); copied into the run's folder.
        station : str
            ``"sim"`` (the plan's twin) or a station file (``imucalib run --station``).
        serials : list of str
            The serials of the units mounted; when given they must be the station's units.
        operator : str
            Who starts the run (recorded).
        pace : float, optional
            Wall seconds per station second for the twin (1: real time; default: as fast as
            it goes).
        override_due : str, optional
            The reason to run on equipment overdue for calibration (``imucalib run
            --override-due``); without one such a station is refused by the worker.

        Raises
        ------
        InvalidInputError
            A plan that does not load, a station the plan cannot run on, serials that are not
            the station's units, no operator.
        """
        from imucalib.plan import load_plan
        from imucalib.plan.schema import step_min_duration_s

        if not operator.strip():
            raise InvalidInputError("a run needs the operator's name; got an empty one")
        if pace is not None and not pace > 0:
            raise InvalidInputError(f"`pace` must be > 0; got {pace!r}")
        plan = load_plan(Path(plan_path))
        if station == "sim":
            if plan.twin is None:
                raise ConfigurationError(f"plan {plan.name!r} has no [twin] table describing the "
                                         "simulated station; give a station file")
            names = [imu.name for imu in plan.twin.imus]
            if serials and sorted(serials) != sorted(names):
                raise ConfigurationError(f"the unit serials given {serials} are not the twin's "
                                         f"units {names}")
        elif not Path(station).is_file():
            raise ConfigurationError(f"station file {station!r} not found")
        run_id = f"{datetime.now(UTC):%Y%m%dT%H%M%SZ}-{secrets.token_hex(3)}"
        files = RunFiles(self.runs_dir / run_id)
        files.folder.mkdir()
        shutil.copyfile(plan_path, files.plan)
        stem = re.sub(r"[^A-Za-z0-9._-]+", "_", plan.name).strip("._") or "run"
        write_json_atomic(files.config, {
            "run_id": run_id, "plan_name": plan.name, "plan_source": str(plan_path),
            "station": station if station == "sim" else str(Path(station).resolve()),
            "serials": list(serials), "operator": operator.strip(),
            "started_utc": datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "recording": str(files.folder.resolve() / f"{stem}.h5"),
            "steps": [[s.kind, plan.step_label(i)] for i, s in enumerate(plan.steps)],
            "least_time_s": float(sum(step_min_duration_s(s) for s in plan.steps)),
            "tick_s": self.tick_s, "pace": pace, "db": self.db, "record": self.record,
            "override_due": (override_due or "").strip() or None})
        self._spawn(files, resume=False)
        return run_id

    def view(self, run_id: str) -> RunView:
        """Return what a page shows of run `run_id`.

        Raises
        ------
        UnknownRunError
        """
        files = self._files(run_id)
        cfg = files.read_config()
        if cfg is None:
            raise UnknownRunError(f"no run {run_id!r} in {self.runs_dir}")
        return build_view(cfg, files.read_state(), self._alive(files))

    def runs(self) -> list[RunView]:
        """Return every run of the runs folder, the newest first."""
        out = []
        for folder in sorted(self.runs_dir.iterdir(), reverse=True):
            if RUN_ID_PATTERN.match(folder.name) and (folder / "run.json").exists():
                try:
                    out.append(self.view(folder.name))
                except UnknownRunError:
                    continue
        return out

    def resumable(self) -> list[RunView]:
        """Return the runs that ended unfinished and whose recording can be resumed.

        A run is resumable when its worker is gone, it did not finish, and its recording holds
        a step not done yet (:func:`~imucalib.station.runner.find_resume_point`).
        """
        return [v for v in self.runs() if self._resume_point(v) is not None]

    def resume(self, run_id: str, who: str) -> None:
        """Continue run `run_id` in its own recording, in a new worker.

        Raises
        ------
        RunStateError
            The run is live, finished, or its recording cannot be resumed.
        """
        with self._resume_lock:  # two pages resuming at once start one worker
            self._resume(run_id, who)

    def _resume(self, run_id: str, who: str) -> None:
        v = self.view(run_id)
        if v.status in LIVE_STATUSES:
            raise RunStateError(f"run {run_id} is {v.status}; only an ended run is resumed")
        files = self._files(run_id)
        deadline = time.monotonic() + EXIT_WAIT_S
        while self._alive(files):  # an ended run's worker has its last words to write
            if time.monotonic() > deadline:
                raise RunStateError(f"run {run_id} is {v.status} but its worker is still there "
                                    f"after {EXIT_WAIT_S:g} s; try again")
            time.sleep(0.05)
        if self._resume_point(v) is None:
            raise RunStateError(f"run {run_id} ({v.status}) has nothing to resume: its "
                                f"recording {v.recording_path} is complete or unreadable")
        cfg = files.read_config() or {}
        write_json_atomic(files.config, {**cfg, "resumed_by": who})
        state = files.read_state() or {}
        write_json_atomic(files.state, {**state, "status": "starting", "error": None,
                                        "prompt": None, "operator": who})
        self._spawn(files, resume=True)

    # --- commands ---------------------------------------------------------------------------
    def answer(self, run_id: str, prompt_id: int, step_index: int, confirmed: bool, who: str,
               note: str = "") -> None:
        """Answer the open prompt `prompt_id` of step `step_index` (a refusal stops the run).

        Raises
        ------
        StaleCommandError
            The run has no open prompt, or another one.
        """
        v = self.view(run_id)
        p = v.prompt
        if p is None:
            raise StaleCommandError(f"run {run_id} has no open prompt (it is {v.status}); "
                                    f"prompt {prompt_id} was answered or is gone")
        if (p.prompt_id, p.step_index) != (prompt_id, step_index):
            raise StaleCommandError(f"run {run_id}: the open prompt is {p.prompt_id} of step "
                                    f"{p.step_index}, not {prompt_id} of step {step_index}")
        self._files(run_id).send_command({
            "type": "answer", "prompt_id": prompt_id, "step_index": step_index,
            "confirmed": bool(confirmed), "who": who, "note": note})

    def abort(self, run_id: str, step_index: int | None, who: str) -> None:
        """Stop run `run_id` safely at once (the runner's safe stop; the recording resumable).

        Parameters
        ----------
        step_index : int, optional
            The step the page showed as current; None aborts whatever step runs.

        Raises
        ------
        RunStateError
            The run has ended.
        StaleCommandError
            The run is at another step than `step_index`.

        Notes
        -----
        When the run has not ended `abort_escalate_s` after the first abort (a device call that
        hangs), the worker is ended and the run marked ``failed``, resumable
        (:mod:`imucalib.web.abort_watch`).
        """
        v = self.view(run_id)
        if v.status not in LIVE_STATUSES:
            raise RunStateError(f"run {run_id} is {v.status}; there is nothing to abort")
        if step_index is not None and step_index != v.step_index:
            raise StaleCommandError(f"run {run_id} is at step {v.step_index}, not {step_index}")
        self._files(run_id).send_command({"type": "abort", "step_index": step_index,
                                          "who": who})
        self._watch_abort(run_id, who)

    # --- live events ------------------------------------------------------------------------
    def subscribe(self, run_id: str) -> SubscriberQueue:
        """Return a queue of the run's live events, starting with a ``snapshot`` of its view.

        The queue is bounded: a reader that falls behind loses the oldest live samples, never
        a status, step or prompt event (:class:`~imucalib.web.events.SubscriberQueue`).
        """
        files = self._files(run_id)
        self.view(run_id)  # an unknown run: UnknownRunError, before anything is kept
        q = SubscriberQueue()
        with self._lock:
            follow = self._follows.get(run_id)
            if follow is None:
                follow = _Follow(files, files.events_size())
                self._follows[run_id] = follow
            v = self.view(run_id)
            q.publish({"type": "snapshot", "run_id": run_id, "view": v.to_dict()})
            follow.queues.append(q)
            follow.status = follow.status or v.status
        self._ensure_thread()
        return q

    def unsubscribe(self, run_id: str, q: Any) -> None:
        """Stop sending run `run_id`'s events to `q` (the run goes on)."""
        with self._lock:
            follow = self._follows.get(run_id)
            if follow is not None and q in follow.queues:
                follow.queues.remove(q)
                if not follow.queues:
                    del self._follows[run_id]

    def close(self) -> None:
        """Stop streaming; the runs go on in their workers (a new supervisor finds them)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        with self._lock:
            self._follows.clear()

    # --- internals --------------------------------------------------------------------------
    def _files(self, run_id: str) -> RunFiles:
        if not isinstance(run_id, str) or not RUN_ID_PATTERN.match(run_id):
            raise UnknownRunError(f"{run_id!r} is not a run id")
        return RunFiles(self.runs_dir / run_id)

    def _spawn(self, files: RunFiles, resume: bool) -> None:
        for old in files.commands.glob("*.json"):  # meant for an earlier worker
            old.unlink(missing_ok=True)
        cmd = [self.python, "-m", "imucalib.web.run_worker", str(files.folder.resolve())]
        if resume:
            cmd.append("--resume")
        with files.worker_log.open("ab") as log:
            proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=log,
                                    stderr=subprocess.STDOUT, start_new_session=True,
                                    env={**os.environ, "PYTHONUNBUFFERED": "1"})
        files.pid.write_text(str(proc.pid), encoding="utf-8")
        self._procs[files.run_id] = proc

    def _watch_abort(self, run_id: str, who: str) -> None:
        """Watch an abort's safe stop in a thread (one a run: the page resends aborts)."""
        with self._lock:
            known = self._watches.get(run_id)
            if known is not None and known.is_alive():
                return
            files = self._files(run_id)

            def is_live() -> bool:
                return self.view(run_id).status in LIVE_STATUSES

            thread = threading.Thread(
                target=watch_abort, name=f"imucalib-abort-{run_id}", daemon=True,
                args=(files, is_live, lambda: self._worker_pid(files)),
                kwargs={"escalate_s": self.abort_escalate_s, "who": who,
                        "sent_at": time.monotonic(), "wait": self._reap})
            self._watches[run_id] = thread
        thread.start()

    def _worker_pid(self, files: RunFiles) -> int | None:
        proc = self._procs.get(files.run_id)
        if proc is not None:
            return proc.pid
        try:
            return int(files.pid.read_text(encoding="utf-8").strip())
        except (OSError, ValueError):
            return None

    def _reap(self, pid: int, timeout_s: float) -> None:
        """Wait up to `timeout_s` for a worker this supervisor started to exit (no zombie)."""
        for proc in list(self._procs.values()):
            if proc.pid == pid:
                try:
                    proc.wait(timeout=timeout_s)
                except subprocess.TimeoutExpired:
                    pass

    def _alive(self, files: RunFiles) -> bool:
        proc = self._procs.get(files.run_id)
        if proc is not None:
            return proc.poll() is None
        try:
            pid = int(files.pid.read_text(encoding="utf-8").strip())
        except (OSError, ValueError):
            return False
        return pid_alive(pid, str(files.folder.resolve()))

    def _resume_point(self, v: RunView) -> int | None:
        """Return the first step to run of an ended, unfinished run (None: cannot resume)."""
        if v.status in LIVE_STATUSES or v.status == "finished":
            return None
        path = Path(v.recording_path)
        if not path.exists():
            return None
        from imucalib.station.runner import find_resume_point

        try:
            stat = path.stat()
            key = (stat.st_mtime_ns, stat.st_size)
            known = self._points.get(str(path))
            if known is not None and known[0] == key:  # the file has not changed since
                return known[1]
            try:
                first: int | None = find_resume_point(path).first_step
            except RecordingError:
                first = None
        except OSError:
            return None
        first = first if first is not None and first < v.n_steps else None
        self._points[str(path)] = (key, first)
        return first

    def _ensure_thread(self) -> None:
        with self._lock:
            if self._thread is None or not self._thread.is_alive():
                self._stop.clear()
                self._thread = threading.Thread(target=self._follow_loop, daemon=True,
                                                name="imucalib-run-follow")
                self._thread.start()

    def _follow_loop(self) -> None:
        while not self._stop.wait(FOLLOW_S):
            with self._lock:
                follows = list(self._follows.items())
            for run_id, follow in follows:
                try:
                    self._follow_once(run_id, follow)
                except Exception as exc:  # one run's unreadable file must not stop the rest
                    self._publish(follow, {"type": "log", "run_id": run_id,
                                           "line": f"supervisor: {type(exc).__name__}: {exc}",
                                           "level": "error"})

    def _follow_once(self, run_id: str, follow: _Follow) -> None:
        events, follow.offset = follow.files.read_events(follow.offset)
        for event in events:
            if event.get("type") == "status":
                follow.status = str(event.get("status"))
            self._publish(follow, event)
        state = follow.files.read_state()
        if state is not None and state.get("seq") != follow.seq:
            follow.seq = int(state.get("seq", -1))
            self._publish(follow, {"type": "signals", "run_id": run_id, "seq": follow.seq,
                                   "status": state.get("status"),
                                   "step_index": state.get("step_index"),
                                   "time_left_s": state.get("time_left_s"),
                                   "time_s": (state.get("signals") or {}).get("time_s"),
                                   "signals": state.get("signals")})
        if follow.status in LIVE_STATUSES and not self._alive(follow.files):
            v = self.view(run_id)
            if v.status == "failed":  # died without its last words
                follow.status = "failed"
                self._publish(follow, {"type": "status", "run_id": run_id, "status": "failed",
                                       "error": v.error})

    def _publish(self, follow: _Follow, event: dict[str, Any]) -> None:
        with self._lock:
            queues = list(follow.queues)
        for q in queues:
            q.publish(event)
