"""What every step executor takes and returns (:mod:`imucalib.station.executors`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeAlias

if TYPE_CHECKING:
    from imucalib.station.session import RunSession

__all__ = ["Executor", "StepOutcome"]


@dataclass(frozen=True)
class StepOutcome:
    """How a step ended, for its row in the Recording.

    Attributes
    ----------
    window : tuple of float, optional
        The valid window (start, end) in station time when the step records one. [s]
    note : str
        The row's note (an operator's answer), empty for none.
    """

    window: tuple[float, float] | None = None
    note: str = ""


#: An executor: (session, step, attempt, step row) → :class:`StepOutcome`. `attempt` counts the
#: retries of the step (0 first); `row` is the step's row in the Recording, for an executor that
#: ends the step itself (an operator who declines). It raises
#: :class:`~imucalib.station.signals.StepTrip` when a guard trips and
#: :class:`~imucalib.station.signals.StepStop` when the run must stop.
Executor: TypeAlias = Callable[["RunSession", Any, int, int], StepOutcome]
