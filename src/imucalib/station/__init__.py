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
    :class:`RunSession` (acquisition, guards, step execution), :class:`RunOptions`,
    :class:`RunStatus`.
:mod:`imucalib.station.guards`
    Pure guard checks and settling criteria.
:mod:`imucalib.station.operator`
    :class:`Operator`, :class:`AutoOperator`, :class:`ScriptedOperator`.
"""

from __future__ import annotations

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
