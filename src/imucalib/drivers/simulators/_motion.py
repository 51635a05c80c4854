"""What the two motion simulators share: the twin table behind them, axis state, fault hooks.

Contents
--------
:class:`MotionSimServer`
    Base of :class:`~imucalib.drivers.simulators.AclSimServer` and
    :class:`~imucalib.drivers.simulators.AerosmithSimServer`: translates demands into commands
    of the rig's :class:`~imucalib.sim.table.SimRateTable` (or its centrifuge) at the current
    simulated time, answers readbacks from the rig's feedback, and offers the fault hooks.
:class:`InjectedMotionFaults`
    The record of what was injected, for tests to compare with what the driver saw.

Fault hooks
-----------
:meth:`~MotionSimServer.inject_interlock_fault` (interlock opens with a latched fault: axes brake
and switch off, status reports it, demands are refused), :meth:`~MotionSimServer.clear_fault_cause`
(the cause is gone; the driver's reset may then clear the latch),
:meth:`~MotionSimServer.inject_drift` (the held axis creeps away from its demand: true motion, seen
by the IMUs and the encoder alike), :meth:`~MotionSimServer.inject_rate_error` (the axis turns at
demand + error from now on), :meth:`~MotionSimServer.offset_feedback` (an encoder fault: only the
reported angle/rate are offset), :meth:`~MotionSimServer.clear_faults`, and the inherited
:meth:`~imucalib.drivers.simulators.SimServer.drop_connections`.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from imucalib.drivers.simulators._base import LineSimServer, SimTimeBase
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.sim.rig import TwinRig
from imucalib.sim.table import SimRateTable

__all__ = ["InjectedMotionFaults", "MotionSimServer"]

_LOG = logging.getLogger(__name__)

Interlock = Literal["closed", "open", "fault"]


@dataclass
class InjectedMotionFaults:
    """What the fault hooks injected (tests compare it with what the driver reports)."""

    interlock_faults: list[tuple[int, str]] = field(default_factory=list)
    drifts: list[tuple[int, float, float]] = field(default_factory=list)
    rate_errors: list[tuple[int, float]] = field(default_factory=list)
    feedback_offsets: list[tuple[int, float, float]] = field(default_factory=list)


class MotionSimServer(LineSimServer):
    """A motion controller simulator with a twin table (or centrifuge) behind it.

    Parameters
    ----------
    name : str
        Server name.
    rig : TwinRig
        The twin; its ``table`` (or ``centrifuge`` with `device` = "centrifuge") moves.
    time_base : SimTimeBase
        Shared simulated time.
    device : {"table", "centrifuge"}
        Which of the rig's motion devices this controller drives.
    port : int
        0: the OS picks.
    """

    def __init__(self, name: str, rig: TwinRig, time_base: SimTimeBase, *,
                 device: Literal["table", "centrifuge"] = "table", port: int = 0) -> None:
        super().__init__(name, rig, time_base, port=port)
        self.device = device
        if device == "centrifuge":
            if rig.centrifuge is None:
                raise ConfigurationError(f"{name}: the rig has no centrifuge")
            self.sim: SimRateTable = rig.centrifuge.table
        else:
            if rig.table is None:
                raise ConfigurationError(f"{name}: the rig has no rate table")
            self.sim = rig.table
        k = self.sim.n_axes
        self.axis_names = tuple(ax.name for ax in self.sim.spec.axes)
        self.abs_rate_rps = [float(ax.max_rate_rps) for ax in self.sim.spec.axes]
        self.abs_accel_rps2 = [float(ax.max_accel_rps2) for ax in self.sim.spec.axes]
        self.rate_limit_rps = list(self.abs_rate_rps)
        self.accel_limit_rps2 = list(self.abs_accel_rps2)
        self.interlock: list[Interlock] = ["open"] * k
        self.fault: tuple[int, str] | None = None
        self.fault_cause_active = False
        self.rate_demand_rps = [0.0] * k
        self.rate_error_rps = [0.0] * k
        self.angle_offset_rad = [0.0] * k
        self.rate_offset_rps = [0.0] * k
        self.injected = InjectedMotionFaults()

    @property
    def n_axes(self) -> int:
        """Number of axes."""
        return self.sim.n_axes

    def now_s(self) -> float:
        """Return the simulated time (call with ``rig.lock`` held when commands follow). [s]"""
        return self.time_base.now_s()

    # --- physics ------------------------------------------------------------------------------
    def true_angle_rad(self, i: int, t: float) -> float:
        """Return the true angle of axis `i` at time `t`. [rad]"""
        return float(self.sim.axis_motion(i, np.array([t]))[0][0])

    def feedback(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Return the reported angles [rad] and rates [rad/s] at `t` (with injected offsets)."""
        table, fuge = self.rig.motion_feedback(np.array([t]))
        fb = fuge if self.device == "centrifuge" else table
        assert fb is not None  # checked in __init__
        return (fb.angle_rad[0] + np.array(self.angle_offset_rad),
                fb.rate_rps[0] + np.array(self.rate_offset_rps))

    def command_position(self, i: int, angle_rad: float, t: float) -> None:
        """Move axis `i` at the profiler limits (a centrifuge arm only at rest)."""
        if self.device == "centrifuge" and self.sim.mode(i, t) == "rate":
            raise InvalidInputError("the centrifuge arm can only be positioned at rest")
        rate = min(self.rate_limit_rps[i], self.abs_rate_rps[i])
        self.sim.command_position(i, angle_rad, t, rate_rps=rate,
                                  accel_rps2=min(self.accel_limit_rps2[i], self.abs_accel_rps2[i]))

    def command_rate(self, i: int, rate_rps: float, t: float) -> None:
        """Spin axis `i` at `rate_rps` plus any injected rate error."""
        self.rate_demand_rps[i] = rate_rps
        self.sim.command_rate(i, rate_rps + self.rate_error_rps[i], t,
                              accel_rps2=min(self.accel_limit_rps2[i], self.abs_accel_rps2[i]))

    def command_stop(self, i: int, t: float) -> None:
        """Brake axis `i` to rest and hold."""
        self.rate_demand_rps[i] = 0.0
        self.sim.command_stop(i, t)

    def command_off(self, i: int, t: float) -> None:
        """Brake axis `i` to rest, mode off."""
        self.rate_demand_rps[i] = 0.0
        self.sim.command_off(i, t)

    def _axis_index(self, axis: int) -> int:
        if not 0 <= int(axis) < self.n_axes:
            raise InvalidInputError(f"axis index must be 0–{self.n_axes - 1}; got {axis}")
        return int(axis)

    # --- fault hooks --------------------------------------------------------------------------
    def inject_interlock_fault(self, text: str = "emergency stop pressed", code: int = 301
                               ) -> None:
        """Open the interlock with a latched fault: every axis brakes and switches off.

        Status then reports the fault and demands are refused until the cause is cleared
        (:meth:`clear_fault_cause`) and the driver resets the interlock.
        """
        with self.rig.lock:
            t = self.now_s()
            for i in range(self.n_axes):
                self.command_off(i, t)
                self.interlock[i] = "fault"
            self.fault = (int(code), str(text))
            self.fault_cause_active = True
            self.on_fault()
        self.injected.interlock_faults.append((int(code), str(text)))
        _LOG.info("%s: injected interlock fault %d: %s", self.name, code, text)

    def on_fault(self) -> None:
        """Dialect hook: what else an interlock fault changes (modes …)."""

    def clear_fault_cause(self) -> None:
        """Remove the fault's cause; the latch stays until the driver resets it."""
        self.fault_cause_active = False

    def inject_drift(self, axis: int, offset_rad: float, duration_s: float) -> None:
        """Let a held axis creep by `offset_rad` over `duration_s` simulated seconds.

        The true axis moves (IMUs and encoder see it); a new demand corrects it.
        """
        i = self._axis_index(axis)
        if not (math.isfinite(offset_rad) and offset_rad != 0.0 and duration_s > 0.0):
            raise InvalidInputError("drift needs a non-zero `offset_rad` and `duration_s` > 0")
        with self.rig.lock:
            t = self.now_s()
            start = self.true_angle_rad(i, t)
            self.sim.command_position(i, start + offset_rad, t,
                                      rate_rps=abs(offset_rad) / duration_s)
        self.injected.drifts.append((i, float(offset_rad), float(duration_s)))
        _LOG.info("%s: axis %d drifts by %g rad over %g s", self.name, i, offset_rad, duration_s)

    def inject_rate_error(self, axis: int, error_rps: float) -> None:
        """From now on axis `axis` turns at its rate demand plus `error_rps` (in rate mode)."""
        i = self._axis_index(axis)
        with self.rig.lock:
            self.rate_error_rps[i] = float(error_rps)
            t = self.now_s()
            if self.sim.mode(i, t) in ("rate", "stop") and self.interlock[i] == "closed" and \
                    self.rate_demand_rps[i] != 0.0:
                self.command_rate(i, self.rate_demand_rps[i], t)
        self.injected.rate_errors.append((i, float(error_rps)))

    def offset_feedback(self, axis: int, *, angle_rad: float = 0.0, rate_rps: float = 0.0
                        ) -> None:
        """Add offsets to the reported angle and rate only (an encoder fault; not the motion)."""
        i = self._axis_index(axis)
        self.angle_offset_rad[i] = float(angle_rad)
        self.rate_offset_rps[i] = float(rate_rps)
        self.injected.feedback_offsets.append((i, float(angle_rad), float(rate_rps)))

    def clear_faults(self) -> None:
        """Remove rate errors and feedback offsets and the fault cause (latches stay)."""
        with self.rig.lock:
            self.angle_offset_rad = [0.0] * self.n_axes
            self.rate_offset_rps = [0.0] * self.n_axes
            t = self.now_s()
            for i in range(self.n_axes):
                if self.rate_error_rps[i] != 0.0:
                    self.rate_error_rps[i] = 0.0
                    if self.sim.mode(i, t) == "rate" and self.interlock[i] == "closed":
                        self.command_rate(i, self.rate_demand_rps[i], t)
            self.fault_cause_active = False
