"""The signals a run's steps raise: a guard trip (retried) and a stop (not retried).

Raised by :class:`~imucalib.station.session.RunSession` (its acquisition and guards) and by the
step executors (:mod:`imucalib.station.executors`); caught by the session's step loop and the
runner (:mod:`imucalib.station.runner`).
"""

from __future__ import annotations

__all__ = ["StepStop", "StepTrip"]


class StepTrip(Exception):  # noqa: N818 - a signal between the session and the runner
    """A guard tripped inside a step (the runner stops safely, marks it invalid, retries)."""


class StepStop(Exception):  # noqa: N818 - a signal between the session and the runner
    """The run stops without a retry (operator declined, retries exhausted)."""
