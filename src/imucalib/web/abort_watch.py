"""An abort whose safe stop does not complete: the supervisor ends the worker (docs/web-runs.md).

An abort is carried out by the worker at the runner's next tick (the runner's safe stop, then
the Recording closed). A device call that hangs — a driver waiting for an answer that never
comes — keeps the runner from reaching that tick, or hangs the safe stop itself. The supervisor
therefore watches every abort it sends: when the run has not ended within a bounded time
(:data:`ABORT_ESCALATE_S`, configurable), it escalates — SIGTERM to the worker, SIGKILL after
:data:`KILL_GRACE_S` if it is still there — and marks the run ``failed`` with one line saying
so. The Recording is crash-safe (docs/recording-format.md, "Crash safety"): what was flushed is
kept and a resume recovers the file and continues at the first step not done. The equipment of
a hung driver may not have been stopped: the line says to check the station.
"""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Callable
from datetime import UTC, datetime
from typing import Any, Final

from imucalib.web.run_files import LOG_TAIL, RunFiles, pid_alive, to_json, write_json_atomic

__all__ = ["ABORT_ESCALATE_S", "CLOSE_BOUND_S", "KILL_GRACE_S", "escalate", "watch_abort"]

#: Wall time an abort's safe stop may take before the worker is ended. [s]
ABORT_ESCALATE_S: Final = 10.0
#: Wall time the Recording's close (its compression) may take once the equipment stopped. [s]
CLOSE_BOUND_S: Final = 600.0
#: Wall time between SIGTERM and SIGKILL to a worker that does not end. [s]
KILL_GRACE_S: Final = 2.0
#: How often the watch looks at the run. [s]
_LOOK_S: Final = 0.05


def watch_abort(files: RunFiles, is_live: Callable[[], bool], pid: Callable[[], int | None],
                *, escalate_s: float, who: str, sent_at: float,
                wait: Callable[[int, float], None] | None = None,
                close_s: float = CLOSE_BOUND_S) -> bool:
    """Wait for an aborted run to end; escalate when it has not after `escalate_s`.

    The bound is on the safe stop: once the worker has stopped every device (its state's
    ``safe_stopped_unix``), the close of the Recording (which compresses it) gets `close_s`
    more before the worker is ended all the same.

    Parameters
    ----------
    files : RunFiles
        The run's folder.
    is_live : callable
        Whether the run is still live (its status live and its worker there).
    pid : callable
        The worker's process id (None: unknown).
    escalate_s : float
        The bound on the safe stop. [s]
    who : str
        Who aborted (named in the run's log).
    sent_at : float
        ``time.monotonic()`` when the abort was sent.
    wait : callable, optional
        ``wait(pid, timeout_s)`` reaps the worker if it is the caller's child.

    Returns
    -------
    bool
        True when the worker was ended (the run marked ``failed``), False when the run ended by
        itself.
    """
    stopped = False
    while time.monotonic() - sent_at < escalate_s + (close_s if stopped else 0.0):
        if not is_live():
            return False
        stopped = stopped or bool((files.read_state() or {}).get("safe_stopped_unix"))
        time.sleep(_LOOK_S)
    if not is_live():
        return False
    what = (f"the Recording did not close within {close_s:g} s of the safe stop" if stopped
            else f"the safe stop did not complete within {escalate_s:g} s (a device call "
                 "hung)")
    escalate(files, pid(), what=what, who=who, wait=wait)
    return True


def _end(files: RunFiles, worker: int | None, wait: Callable[[int, float], None] | None
         ) -> str:
    """Send SIGTERM, then SIGKILL, to the worker; return what was done."""
    tag = str(files.folder.resolve())
    if worker is None or not pid_alive(worker, tag):
        return "the worker was already gone"
    done = "SIGTERM"
    for sig, grace in ((signal.SIGTERM, KILL_GRACE_S), (signal.SIGKILL, 5.0)):
        try:
            os.kill(worker, sig)
        except ProcessLookupError:
            break
        done = signal.Signals(sig).name
        deadline = time.monotonic() + grace
        if wait is not None:
            wait(worker, grace)
        while pid_alive(worker, tag) and time.monotonic() < deadline:
            time.sleep(_LOOK_S)
        if not pid_alive(worker, tag):
            break
    return f"the worker (pid {worker}) was ended with {done}"


def escalate(files: RunFiles, worker: int | None, *, what: str, who: str,
             wait: Callable[[int, float], None] | None = None) -> str:
    """End the worker of a run whose safe stop did not complete; mark the run ``failed``.

    Parameters
    ----------
    what : str
        What did not complete, for the error line.

    Returns
    -------
    str
        The run's error line.
    """
    how = _end(files, worker, wait)
    error = (f"aborted by {who}, but {what}; {how}. The equipment may not have been stopped: "
             "check the station. The recording is kept up to its last flush; resume recovers "
             "it")
    state: dict[str, Any] = files.read_state() or {}
    steps = ["failed" if s == "running" else s for s in state.get("steps") or []]
    now = datetime.now(UTC)
    line = f"{now:%H:%M:%S} error: {error}"
    tail = [*(state.get("log_tail") or []), line][-LOG_TAIL:]
    write_json_atomic(files.state, {**state, "seq": int(state.get("seq", 0)) + 1,
                                    "status": "failed", "error": error, "prompt": None,
                                    "steps": steps, "log_tail": tail,
                                    "updated_utc": f"{now:%Y-%m-%dT%H:%M:%SZ}"})
    utc = f"{now:%Y-%m-%dT%H:%M:%SZ}"
    with files.events.open("a+b") as out:   # a killed worker may have left half a line
        out.seek(0, os.SEEK_END)
        if out.tell() > 0:
            out.seek(-1, os.SEEK_END)
            if out.read(1) != b"\n":
                out.write(b"\n")
        for body in ({"type": "log", "line": line, "level": "error"},
                     {"type": "status", "status": "failed", "error": error},
                     {"type": "end", "status": "failed", "error": error}):
            out.write((to_json({**body, "run_id": files.run_id, "utc": utc}) + "\n").encode())
    return error
