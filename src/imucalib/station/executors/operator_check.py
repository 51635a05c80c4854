"""The executor of the operator check: the operator's confirmation, and what it puts in place.

The operator (:class:`~imucalib.station.operator.Operator` of the run's options) confirms or
declines the check's item; who answered, when and any note are logged and become the step's
note. A declined check ends the step ``aborted`` and stops the run
(:class:`~imucalib.station.signals.StepStop`). A confirmed check that remounts the fixture,
swaps two units or sets the centrifuge's test load has it done on a twin (a station with the
``remount``, ``swap_units`` or ``set_centrifuge_load`` method,
:class:`~imucalib.station.sim.SimStation`) and logs it in any case (the operator did it on a
real station) as a typed station event (:meth:`RunSession.log_station_event
<imucalib.station.session.RunSession.log_station_event>`, :mod:`imucalib.io.events`), which
``Recording.events`` and ``imucalib inspect`` find by its kind (``docs/recording-format.md``,
"Station events").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from imucalib.io.events import EventKind
from imucalib.plan.schema import OperatorCheckStep
from imucalib.station.executors.base import StepOutcome
from imucalib.station.signals import StepStop

if TYPE_CHECKING:
    from imucalib.station.session import RunSession

__all__ = ["remount", "run_operator_check", "set_centrifuge_load", "swap_units"]


def run_operator_check(session: RunSession, step: OperatorCheckStep, attempt: int = 0,
                       row: int = -1) -> StepOutcome:
    """Ask the operator; on a confirmation apply the remount, swap or load; return the note."""
    s = session
    answer = s.opt.operator.confirm(step.item)
    note = (f"{'confirmed' if answer.confirmed else 'declined'} by {answer.who} at "
            f"{answer.when_utc}" + (f": {answer.note}" if answer.note else ""))
    s.writer.log_event(s.now(), "info" if answer.confirmed else "warning",
                       f"operator:{answer.who}", f"{step.item} — {note}")
    if not answer.confirmed:
        s.writer.update_step(row, t_end_s=s.now(), status="aborted", note=note)
        raise StepStop(f"operator {answer.who} did not confirm: {step.item}")
    if step.remount is not None:
        remount(s, step.remount, step.remount_yaw_deg)
    if step.swap_units is not None:
        swap_units(s, *step.swap_units)
    if step.centrifuge_load_kg is not None:
        set_centrifuge_load(s, step.centrifuge_load_kg)
    return StepOutcome(note=note)


def remount(session: RunSession, up: str, yaw_deg: float, why: str = "") -> None:
    """Put the fixture in pose (`up`, `yaw_deg`) on a twin; log the remount in any case.

    A station with a ``remount`` method (the twin, :class:`~imucalib.station.sim.SimStation`)
    moves its fixture; on a real station the operator has done it.
    """
    do = getattr(session.station, "remount", None)
    if callable(do):
        do(up, yaw_deg)
    session.log_station_event(EventKind.REMOUNT, f"{up} up, yaw {yaw_deg:g}°{why}")


def swap_units(session: RunSession, first: str, second: str, why: str = "") -> None:
    """Exchange units `first` and `second` on a twin's fixture; log the swap in any case.

    A station with a ``swap_units`` method (the twin) moves its units; on a real station the
    operator has done it.
    """
    do = getattr(session.station, "swap_units", None)
    if callable(do):
        do(first, second)
    session.log_station_event(EventKind.SWAP, f"{first} ↔ {second}{why}")


def set_centrifuge_load(session: RunSession, load_kg: float, why: str = "") -> None:
    """Set the test load on a twin's centrifuge arm; log the load in any case. [kg]

    A station with a ``set_centrifuge_load`` method (the twin) changes its unbalance; on a real
    station the operator has loaded the arm.
    """
    do = getattr(session.station, "set_centrifuge_load", None)
    if callable(do):
        do(load_kg)
    session.log_station_event(EventKind.LOAD, f"{load_kg:g} kg{why}")
