"""The station runtime: device protocols, the simulated station, the plan runner.

Contents
--------
:mod:`imucalib.station.devices`
    Protocols the runner drives (:class:`MotionDevice`, :class:`ChamberDevice`,
    :class:`ImuSource`, :class:`Clock`, :class:`Station`) and the data blocks they return.
:mod:`imucalib.station.sim`
    :class:`SimStation`: the digital twin behind those protocols, with fault hooks.
:mod:`imucalib.station.runner`
    :func:`run_plan`, :func:`resume_run`, :func:`find_resume_point`,
    :func:`check_plan_against_station`, :class:`RunSummary`.
:mod:`imucalib.station.session`
    :class:`RunSession` (acquisition, guards, settling, recording, the step loop),
    :class:`RunOptions`, :class:`RunStatus`.
:mod:`imucalib.station.executors`
    The executor of each step kind, one module per kind (motion, static, soak, warm-up,
    operator check); :data:`~imucalib.station.executors.EXECUTORS`.
:mod:`imucalib.station.signals`
    :class:`~imucalib.station.signals.StepTrip`, :class:`~imucalib.station.signals.StepStop`.
:mod:`imucalib.station.guards`
    Pure guard checks and settling criteria.
:mod:`imucalib.station.operator`
    :class:`Operator`, :class:`AutoOperator`, :class:`ScriptedOperator`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from imucalib._lazy import lazy_getattr

if TYPE_CHECKING:
    from imucalib.station.devices import ChamberDevice, Clock, ImuSource, MotionDevice, Station
    from imucalib.station.operator import AutoOperator, Operator, OperatorAnswer, ScriptedOperator
    from imucalib.station.runner import (
        RunSummary,
        check_plan_against_station,
        find_resume_point,
        resume_run,
        run_plan,
    )
    from imucalib.station.session import RunOptions, RunSession, RunStatus
    from imucalib.station.sim import SimStation

__all__ = [
    "AutoOperator",
    "ChamberDevice",
    "Clock",
    "ImuSource",
    "MotionDevice",
    "Operator",
    "OperatorAnswer",
    "RunOptions",
    "RunSession",
    "RunStatus",
    "RunSummary",
    "ScriptedOperator",
    "SimStation",
    "Station",
    "check_plan_against_station",
    "find_resume_point",
    "resume_run",
    "run_plan",
]

#: Module of each public name, imported on first access (PEP 562): importing one module of this
#: package does not import the others (docs/architecture.md, "Layers").
_LAZY = {
    "AutoOperator": "imucalib.station.operator",
    "ChamberDevice": "imucalib.station.devices",
    "Clock": "imucalib.station.devices",
    "ImuSource": "imucalib.station.devices",
    "MotionDevice": "imucalib.station.devices",
    "Operator": "imucalib.station.operator",
    "OperatorAnswer": "imucalib.station.operator",
    "RunOptions": "imucalib.station.session",
    "RunSession": "imucalib.station.session",
    "RunStatus": "imucalib.station.session",
    "RunSummary": "imucalib.station.runner",
    "ScriptedOperator": "imucalib.station.operator",
    "SimStation": "imucalib.station.sim",
    "Station": "imucalib.station.devices",
    "check_plan_against_station": "imucalib.station.runner",
    "find_resume_point": "imucalib.station.runner",
    "resume_run": "imucalib.station.runner",
    "run_plan": "imucalib.station.runner",
}

__getattr__ = lazy_getattr(__name__, _LAZY)
