"""The runner's event-log lines to a watcher as well: the ``on_log`` hook of a run.

Everything the runner, its session and its step executors write to the Recording's event log
(``/log``, docs/recording-format.md) goes through the writer's
:meth:`~imucalib.io.recording.RecordingWriter.log_event` (station events too:
:meth:`~imucalib.io.recording.RecordingWriter.log_station_event` calls it). :func:`tee_log`
makes that method also hand each line, once written, to a callback — the web page's live log
(docs/web-runs.md, "Events") — so a watcher sees exactly the lines the recording keeps. A
callback that fails never stops the run: its error is logged at debug level and the run goes
on (a ``KeyboardInterrupt``, the abort path, does pass through).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

__all__ = ["LogHook", "tee_log"]

#: ``on_log(time_s, level, source, message)``: one line of the Recording's event log.
LogHook = Callable[[float, str, str, str], None]
_log = logging.getLogger(__name__)


def tee_log(writer: Any, on_log: LogHook | None) -> None:
    """Make `writer`'s ``log_event`` call `on_log` after each line it writes (None: nothing).

    Parameters
    ----------
    writer : RecordingWriter
        The open writer of the run (its method is replaced on this instance only).
    on_log : callable or None
        Called with the line's station time [s], level, source and message.
    """
    if on_log is None:
        return
    write = writer.log_event

    def log_event(time_s: float, level: str, source: str, message: str) -> None:
        write(time_s, level, source, message)
        try:
            on_log(time_s, level, source, message)
        except Exception as exc:  # a watcher's failure must never stop the run
            _log.debug("the on_log hook failed: %s", exc)

    writer.log_event = log_event
