"""The executor of the static step: a record with the table holding its last position.

A retry after a safe stop first moves the table back to the position the record was made at
and waits until it holds and the accelerometers have settled.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from imucalib import units
from imucalib.plan.schema import StaticStep
from imucalib.station.executors.base import StepOutcome
from imucalib.station.guards import check_position_hold
from imucalib.station.signals import StepTrip

if TYPE_CHECKING:
    from imucalib.station.session import RunSession

__all__ = ["run_static"]


def run_static(session: RunSession, step: StaticStep, attempt: int = 0, row: int = -1
               ) -> StepOutcome:
    """Execute a static step; return its valid window."""
    s = session
    table = s.station.table
    names = table.axis_names if table is not None else ()
    tol = s.g.position_tolerance_arcsec * units.ARCSEC
    if table is not None and attempt > 0 and s.held_targets is not None:
        # a retry after a safe stop: back to the position the record was made at
        targets = s.held_targets
        t_cmd = s.now()
        for i, target in enumerate(targets):
            table.move_to(i, target)
        s.settle(t_cmd, 0.0, lambda: check_position_hold(
            s.motion_rows()[1], targets, names, tol) or s.accel_settled())
    held: list[float] | None = None
    if table is not None:
        _, angle, _ = s.motion_rows()
        held = list(angle[-1]) if angle.size else None

    def guard() -> None:
        if held is not None:
            angle, _ = s.latest_motion()
            reason = check_position_hold(angle, held, names, tol)
            if reason:
                raise StepTrip(reason)

    return StepOutcome(window=s.record_for(step.duration_s, guard))
