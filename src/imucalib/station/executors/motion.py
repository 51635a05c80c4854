"""The executor of the motion steps: position, rate and centrifuge.

A position step moves the table's axes to their angles, waits until they hold them and the
accelerometers have settled (re-commanding an axis found at rest off its target: the
"automatic correction" of docs/p1.md, calibration steps 1 and 3), then records for
``record_s`` with the position held. A rate step (and a centrifuge step at a rate) spins an
axis, waits until the rate holds, then records whole revolutions or ``record_s``. A centrifuge
step with ``arm_position_deg`` stops the arm, moves it there and records like a position.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from imucalib import units
from imucalib.plan.schema import CentrifugeStep, PositionStep, RateStep
from imucalib.station.executors.base import StepOutcome
from imucalib.station.guards import check_position_hold, check_rate_hold
from imucalib.station.signals import StepTrip

if TYPE_CHECKING:
    from imucalib.station.devices import MotionDevice
    from imucalib.station.session import RunSession

__all__ = ["run_motion"]


def run_motion(session: RunSession, step: PositionStep | RateStep | CentrifugeStep,
               attempt: int = 0, row: int = -1) -> StepOutcome:
    """Execute a position, rate or centrifuge step; return its valid window."""
    return StepOutcome(window=_run(session, step))


def _run(s: RunSession, step: PositionStep | RateStep | CentrifugeStep) -> tuple[float, float]:
    fuge = isinstance(step, CentrifugeStep)
    dev: MotionDevice | None = s.station.centrifuge if fuge else s.station.table
    assert dev is not None  # checked against the station before the run
    names = dev.axis_names
    pos_tol = s.g.position_tolerance_arcsec * units.ARCSEC
    hold_tol = s.g.hold_rate_tolerance_dps * units.DEG
    rate_tol = s.g.rate_tolerance_dps * units.DEG
    t_cmd = s.now()
    if isinstance(step, PositionStep) or (isinstance(step, CentrifugeStep)
                                          and step.arm_position_deg is not None):
        angles = (list(step.angles_deg) if isinstance(step, PositionStep)
                  else [step.arm_position_deg or 0.0])
        targets = [a * units.DEG for a in angles]
        if fuge:
            dev.set_rate(0, 0.0)
            s.settle(t_cmd, 0.0, lambda: check_rate_hold(
                s.motion_rows(True)[2], 0.0, 0, names[0], hold_tol))
        for i, target in enumerate(targets):
            dev.move_to(i, target)
        if not fuge:
            s.held_targets = targets

        def hold() -> str | None:
            _, angle, rate = s.motion_rows(fuge)
            return (check_position_hold(angle, targets, names, pos_tol)
                    or next((r for i in range(len(targets))
                             if (r := check_rate_hold(rate, 0.0, i, names[i], hold_tol))),
                            None))

        def correct(reason: str) -> bool:
            """Re-command the axes when, at rest over the last tick, one is off target."""
            angle, rate = s.latest_motion(fuge)
            if rate.size == 0 or np.abs(rate).max() > hold_tol:
                return False  # still moving: the move is not over yet
            if check_position_hold(angle, targets, names, pos_tol) is None:
                return False  # arrived; the settling span has yet to pass
            for i, target in enumerate(targets):
                dev.move_to(i, target)
            return True

        s.settle(t_cmd, step.settle_s, lambda: hold() or s.accel_settled(), correct)

        def guard() -> None:
            angle, _ = s.latest_motion(fuge)
            reason = check_position_hold(angle, targets, names, pos_tol)
            if reason:
                raise StepTrip(reason)

        assert step.record_s is not None  # an arm position records for a duration
        return s.record_for(step.record_s, guard)
    axis = 0 if fuge else step.axis  # type: ignore[union-attr]
    rate = step.rate_dps * units.DEG
    dev.set_rate(axis, rate)
    s.settle(t_cmd, step.settle_s, lambda: check_rate_hold(
        s.motion_rows(fuge)[2], rate, axis, names[axis], rate_tol))

    def rate_guard() -> None:
        reason = check_rate_hold(s.latest_motion(fuge)[1], rate, axis, names[axis], rate_tol)
        if reason:
            raise StepTrip(reason)

    if step.revolutions is not None:
        return s.record_revolutions(fuge, axis, step.revolutions, rate_guard)
    assert step.record_s is not None
    return s.record_for(step.record_s, rate_guard)
