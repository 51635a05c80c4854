"""The executors of the plan's step kinds: one module per kind, run by the session.

:meth:`RunSession.execute <imucalib.station.session.RunSession.execute>` opens a step's row in
the Recording, runs the executor :data:`EXECUTORS` names for the step's ``kind`` (the step
vocabulary of :mod:`imucalib.plan.schema`), waits for the IMU samples of the valid window the
executor returns, and closes the row. Executors command the equipment and decide when a step
is over; acquisition, guards, settling and recording are the session's
(:class:`~imucalib.station.session.RunSession`: ``tick``, ``settle``, ``record_for``,
``record_revolutions``). Each takes (session, step, attempt, row) and returns a
:class:`~imucalib.station.executors.base.StepOutcome` (:data:`~.base.Executor`).

Contents
--------
:mod:`~imucalib.station.executors.motion`
    :func:`~.motion.run_motion`: ``position``, ``rate``, ``centrifuge``.
:mod:`~imucalib.station.executors.static`
    :func:`~.static.run_static`: ``static``.
:mod:`~imucalib.station.executors.soak`
    :func:`~.soak.run_soak`: ``soak``.
:mod:`~imucalib.station.executors.warm_up`
    :func:`~.warm_up.run_warm_up`: ``warm-up``.
:mod:`~imucalib.station.executors.operator_check`
    :func:`~.operator_check.run_operator_check`: ``operator-check`` (with a remount, a unit
    swap or a centrifuge load on a twin).
:mod:`~imucalib.station.executors.base`
    :class:`~.base.StepOutcome`, :data:`~.base.Executor`.

A new step kind adds its module here and its line in :data:`EXECUTORS`
(docs/architecture.md, "Where a new thing goes").
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from imucalib.station.executors.base import Executor, StepOutcome
from imucalib.station.executors.motion import run_motion
from imucalib.station.executors.operator_check import run_operator_check
from imucalib.station.executors.soak import run_soak
from imucalib.station.executors.static import run_static
from imucalib.station.executors.warm_up import run_warm_up

__all__ = ["EXECUTORS", "Executor", "StepOutcome"]

#: The executor of each step kind (a plan step's ``kind``).
EXECUTORS: Mapping[str, Executor] = MappingProxyType({
    "operator-check": run_operator_check,
    "position": run_motion,
    "rate": run_motion,
    "centrifuge": run_motion,
    "static": run_static,
    "soak": run_soak,
    "warm-up": run_warm_up,
})
