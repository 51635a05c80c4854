"""The live events of a supervised run, and the bounded queue a subscriber reads them from.

Every event is a JSON-serialisable dict with a ``"type"`` and the ``"run_id"``
(docs/web-runs.md, "Events"):

``snapshot``
    The whole :class:`~imucalib.web.run_view.RunView` (``"view"``): the first event of every
    subscription.
``status``
    The run's status changed (``"status"``, ``"error"``).
``step``
    A step changed state (``"index"``, ``"state"``: running, done, failed).
``prompt`` / ``prompt_closed``
    An operator check waits for an answer (``"prompt_id"``, ``"step_index"``, ``"text"``,
    ``"details"``) / was answered (``"confirmed"``, ``"who"``).
``log``
    One line of the run's log (``"line"``).
``safe_stop``
    The runner stopped a device safely (``"device"``, ``"latency_s"`` from the abort command
    when there was one).
``command_rejected``
    The worker refused a command that had gone stale on its way (``"reason"``).
``signals``
    Decimated live values (``"signals"``, ``"time_s"``, ``"step_index"``, ``"time_left_s"``; the
    signals carry ``"soak"``, the running soak's criterion and progress, and ``"wall_unix"``); at
    most a few a second.
``window``
    A recorded window ended: its step, start and end, what was commanded, and per unit the
    count, mean, σ and σ/√n of each axis.
``trace``
    The temperatures for the soak chart (time, air, set point, units), about one per 5 s of
    station time and at most two a wall second.

``signals`` and ``trace`` (:data:`DROPPABLE`) are the kinds a slow subscriber loses, the oldest
first.
``end``
    The worker ended (``"status"``).
"""

from __future__ import annotations

import asyncio
import queue
from typing import Any

__all__ = ["DROPPABLE", "MAX_SAMPLES", "MAX_TOTAL", "SubscriberQueue"]

#: Event types a subscriber that falls behind may lose (the oldest first): live samples.
DROPPABLE = frozenset({"signals", "trace"})
#: Live-sample events a subscriber's queue holds at most.
MAX_SAMPLES = 50
#: Events a subscriber's queue holds at most; beyond it the oldest log lines go too (state,
#: step and prompt events are never dropped).
MAX_TOTAL = 2000


class SubscriberQueue(queue.Queue[dict[str, Any]]):
    """A queue of events that drops the oldest live samples, never a state or prompt event.

    Readers use it as any :class:`queue.Queue` (``get``, ``get_nowait``); the supervisor adds
    events with :meth:`publish`. ``dropped`` counts the events lost.

    Parameters
    ----------
    max_samples : int
        Live-sample events (:data:`DROPPABLE`) kept at most.
    max_total : int
        Events kept at most before log lines are dropped too.
    """

    def __init__(self, max_samples: int = MAX_SAMPLES, max_total: int = MAX_TOTAL) -> None:
        super().__init__()
        self.max_samples = max_samples
        self.max_total = max_total
        self.dropped = 0
        self._loop: asyncio.AbstractEventLoop | None = None
        self._wake: asyncio.Event | None = None

    async def next_event(self, timeout_s: float) -> dict[str, Any] | None:
        """Return the next event, waiting up to `timeout_s` on the running event loop (None).

        The waiting costs no thread: :meth:`publish`, from the supervisor's thread, wakes the
        loop (a blocking :meth:`get` in a worker thread per page, as before, made the server's
        memory creep with the thread pool's churn; docs/web.md, "Bounded memory").
        """
        if self._wake is None:
            self._loop, self._wake = asyncio.get_running_loop(), asyncio.Event()
        try:
            return self.get_nowait()
        except queue.Empty:
            pass
        self._wake.clear()
        try:                                    # published between the look and the clear
            return self.get_nowait()
        except queue.Empty:
            pass
        try:
            await asyncio.wait_for(self._wake.wait(), timeout_s)
        except TimeoutError:
            return None
        try:
            return self.get_nowait()
        except queue.Empty:
            return None

    def publish(self, event: dict[str, Any]) -> None:
        """Add `event`, first dropping the oldest sample (or log line) when the queue is full."""
        with self.mutex:
            items = self.queue
            if event.get("type") in DROPPABLE:
                samples = [e for e in items if e.get("type") in DROPPABLE]
                if len(samples) >= self.max_samples:
                    items.remove(samples[0])
                    self.dropped += 1
                    self.unfinished_tasks -= 1
            if len(items) >= self.max_total:
                for kind in (DROPPABLE, frozenset({"log"})):
                    oldest = next((e for e in items if e.get("type") in kind), None)
                    if oldest is not None:
                        items.remove(oldest)
                        self.dropped += 1
                        self.unfinished_tasks -= 1
                        break
            items.append(event)
            self.unfinished_tasks += 1
            self.not_empty.notify()
            loop, wake = self._loop, self._wake
        if loop is not None and wake is not None:
            try:
                loop.call_soon_threadsafe(wake.set)
            except RuntimeError:                # the page's loop has closed: nobody waits
                pass
