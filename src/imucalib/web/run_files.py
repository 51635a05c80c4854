"""The files of one supervised run: how the supervisor and the run's worker process talk.

Every run has a folder ``RUNS/<run id>/`` (docs/web-runs.md, "Files"):

``run.json``
    What the run is (plan, station, serials, operator, recording, steps); written once by the
    supervisor before the worker starts.
``plan.toml``
    A copy of the plan as it was started.
``state.json``
    The worker's current state (status, steps, prompt, signals, log tail); replaced atomically,
    at most a few times a second and at every change of status, step or prompt.
``events.jsonl``
    The worker's discrete events (status, step, prompt, log, safe stop, end), one JSON object a
    line, appended and flushed one by one; the supervisor follows it.
``commands/``
    The supervisor's commands to the worker (prompt answers, abort), one JSON file each, written
    atomically (a temporary name, then renamed); the worker takes them in name order and removes
    them.
``worker.pid``
    The process id of the run's latest worker, written by the supervisor that started it.
``worker.log``
    The worker's stdout and stderr.
``<plan name>.h5``
    The run's Recording.

Files outlive both processes, so a new supervisor finds every run again, and a worker that
outlives its supervisor keeps running.
"""

from __future__ import annotations

import json
import math
import os
import re
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["LOG_TAIL", "RUN_ID_PATTERN", "RunFiles", "json_safe", "pid_alive", "read_json",
           "to_json", "write_json_atomic"]

#: Log lines a run's ``state.json`` keeps (the worker's and, after an escalated abort, the
#: supervisor's last words).
LOG_TAIL = 50

#: A run id: the UTC start time and six hex digits (also a safe folder name).
RUN_ID_PATTERN = re.compile(r"^[0-9]{8}T[0-9]{6}Z-[0-9a-f]{6}$")


def json_safe(value: Any) -> Any:
    """Return `value` with every non-finite float (NaN, ±inf) as None (strict JSON)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    return value


def to_json(value: Any) -> str:
    """Return `value` as strict JSON (:func:`json_safe`; anything else as its ``str``)."""
    return json.dumps(json_safe(value), allow_nan=False, default=str)


def write_json_atomic(path: Path, data: Any) -> None:
    """Write `data` as JSON to `path` through a temporary file and a rename (never half-written)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:6]}.tmp")
    tmp.write_text(to_json(data), encoding="utf-8")
    os.replace(tmp, path)


def read_json(path: Path) -> Any:
    """Return the JSON in `path`, or None when it does not exist (yet) or is unreadable."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def pid_alive(pid: int | None, tag: str = "") -> bool:
    """Return whether process `pid` runs (not a zombie) and, on Linux, has `tag` in its command.

    The tag (the run's folder) guards against a pid reused by another process after the worker
    ended while no supervisor watched.
    """
    if not pid or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return not tag  # someone else's process: ours only if nothing more can be checked
    proc = Path(f"/proc/{pid}")
    if not proc.exists():
        return True  # no /proc (not Linux): the signal test is all there is
    try:
        stat = (proc / "stat").read_text()
        if stat[stat.rindex(")") + 2:].startswith(("Z", "X")):
            return False
        if tag:
            cmd = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            return tag in cmd
    except (OSError, ValueError):
        return False
    return True


@dataclass(frozen=True)
class RunFiles:
    """The paths of one run's folder, and the reading and writing of its files."""

    folder: Path

    @property
    def run_id(self) -> str:
        """The run id (the folder's name)."""
        return self.folder.name

    @property
    def config(self) -> Path:
        """``run.json``."""
        return self.folder / "run.json"

    @property
    def plan(self) -> Path:
        """``plan.toml``."""
        return self.folder / "plan.toml"

    @property
    def state(self) -> Path:
        """``state.json``."""
        return self.folder / "state.json"

    @property
    def events(self) -> Path:
        """``events.jsonl``."""
        return self.folder / "events.jsonl"

    @property
    def commands(self) -> Path:
        """``commands/``."""
        return self.folder / "commands"

    @property
    def pid(self) -> Path:
        """``worker.pid``: the process id of the run's (latest) worker."""
        return self.folder / "worker.pid"

    @property
    def worker_log(self) -> Path:
        """``worker.log``."""
        return self.folder / "worker.log"

    # --- the run's description and state ----------------------------------------------------
    def read_config(self) -> dict[str, Any] | None:
        """Return ``run.json`` (None: not a run folder)."""
        data = read_json(self.config)
        return data if isinstance(data, dict) else None

    def read_state(self) -> dict[str, Any] | None:
        """Return ``state.json`` (None: the worker has written none yet)."""
        data = read_json(self.state)
        return data if isinstance(data, dict) else None

    # --- events -----------------------------------------------------------------------------
    def read_events(self, offset: int) -> tuple[list[dict[str, Any]], int]:
        """Return the complete event lines from byte `offset` on, and the offset after them."""
        try:
            with self.events.open("rb") as f:
                f.seek(offset)
                chunk = f.read()
        except OSError:
            return [], offset
        end = chunk.rfind(b"\n") + 1  # a line still being written waits for the next read
        out = []
        for line in chunk[:end].splitlines():
            try:
                event = json.loads(line)
            except ValueError:
                continue
            if isinstance(event, dict):
                out.append(event)
        return out, offset + end

    def events_size(self) -> int:
        """Return the size of ``events.jsonl`` (0 when there is none). [bytes]"""
        try:
            return self.events.stat().st_size
        except OSError:
            return 0

    # --- commands ---------------------------------------------------------------------------
    def send_command(self, command: dict[str, Any]) -> None:
        """Write one command for the worker (stamped with the wall time it was sent)."""
        self.commands.mkdir(exist_ok=True)
        stamp = time.time()
        body = {**command, "sent_unix": stamp}
        name = f"{time.time_ns():020d}-{uuid.uuid4().hex[:8]}.json"
        write_json_atomic(self.commands / name, body)

    def take_commands(self) -> Iterator[dict[str, Any]]:
        """Yield the waiting commands in the order they were sent, removing each."""
        try:
            names = sorted(p.name for p in os.scandir(self.commands)
                           if p.name.endswith(".json") and not p.name.startswith("."))
        except OSError:
            return
        for name in names:
            path = self.commands / name
            data = read_json(path)
            path.unlink(missing_ok=True)
            if isinstance(data, dict):
                yield data
