"""The errors of the run supervisor (:mod:`imucalib.web.supervisor`).

Each names the run and what was expected; the web server turns them into its answers (an unknown
run: not found; a stale command or a run in the wrong state: a conflict).
"""

from __future__ import annotations

from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["RunStateError", "StaleCommandError", "UnknownRunError"]


class UnknownRunError(InvalidInputError):
    """A run id that is malformed or names no run of the supervisor's runs folder."""


class StaleCommandError(CalibrationError):
    """A command for a prompt or a step that is no longer the run's current one.

    A page sends, with every command, the run id and the prompt and step it was shown; when the
    run has moved on, the command is refused rather than applied to a state the operator did not
    see (docs/web-runs.md, "Commands").
    """


class RunStateError(CalibrationError):
    """A command the run's state does not allow (resuming a live run, aborting a finished one)."""
