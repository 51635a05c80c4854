"""An Ideal Aerosmith controller simulator speaking its ASCII dialect, with a twin table behind it.

Serves the commands of :mod:`imucalib.drivers.aerosmith` over TCP on 127.0.0.1; a serial client
reaches it through pyserial's ``socket://127.0.0.1:PORT`` URL, so the serial code path is the
one tested. Fault hooks: :class:`~._motion.MotionSimServer`.

Rules (our simulator's, **[unverified]**)
-----------------------------------------
- Every command except ``JOG``/``SGO`` answers a response line and the prompt line ``>``.
- ``SRV1`` switches an axis' servo on, holding its position (refused while a latched fault's
  cause is active; otherwise it clears the latch); ``SRV0`` brakes to rest and switches off.
- ``MOV`` and ``JOG`` need the servo on; ``JOG`` beyond ``VEL`` is ignored (it has no reply to
  carry an error; :attr:`AerosmithSimServer.refused` counts it).
- ``VEL``/``ACL`` above the axis' absolute limits answer ``ERROR``.
"""

from __future__ import annotations

import math
from typing import Literal

from imucalib import units
from imucalib.drivers import aerosmith
from imucalib.drivers.aerosmith import AerosmithStatus
from imucalib.drivers.simulators._base import SimTimeBase
from imucalib.drivers.simulators._motion import MotionSimServer
from imucalib.errors import InvalidInputError, LimitExceededError
from imucalib.sim.rig import TwinRig

__all__ = ["AerosmithSimServer"]

_OK = "OK"


class AerosmithSimServer(MotionSimServer):
    """The Aerosmith ASCII dialect on 127.0.0.1 with the rig's table (or centrifuge) behind it.

    Parameters
    ----------
    rig, time_base, device, port
        As for :class:`~imucalib.drivers.simulators.AclSimServer`.
    version : str
        Answer to ``VER``.

    Attributes
    ----------
    modes : list of str
        ``OFF``, ``POS``, ``JOG`` or ``STOP`` per axis.
    refused : int
        Commands without a reply that were ignored (``JOG`` beyond ``VEL``, servo off …).
    """

    terminator = aerosmith.TERMINATOR

    def __init__(self, rig: TwinRig, time_base: SimTimeBase, *,
                 device: Literal["table", "centrifuge"] = "table",
                 version: str = "AERO4000-SIM 1.0 imucalib-twin", port: int = 0) -> None:
        super().__init__("aerosmith-sim", rig, time_base, device=device, port=port)
        self.version = version
        self.modes: list[Literal["OFF", "POS", "JOG", "STOP"]] = ["OFF"] * self.n_axes
        self.refused = 0

    def on_fault(self) -> None:
        """Switch every axis off (an interlock fault)."""
        self.modes = ["OFF"] * self.n_axes

    def on_line(self, line: str) -> bytes | None:
        """Execute one command; return its response and prompt (nothing for JOG/SGO)."""
        try:
            axis, cmd, arg = aerosmith.parse_command_line(line)
        except InvalidInputError as exc:
            return self._reply(f"ERROR {exc}")
        i = 0 if axis is None else axis - 1
        if not 0 <= i < self.n_axes:
            return None if not aerosmith.expects_reply(cmd) else self._reply(
                f"ERROR no axis {axis}")
        with self.rig.lock:
            t = self.now_s()
            try:
                text = self._execute(cmd, arg, i, t)
            except (InvalidInputError, LimitExceededError) as exc:
                text = f"ERROR {exc}"
        if not aerosmith.expects_reply(cmd):
            return None
        return self._reply(text or _OK)

    @staticmethod
    def _reply(text: str) -> bytes:
        term = aerosmith.TERMINATOR.decode()
        return f"{text}{term}{aerosmith.PROMPT}{term}".encode("ascii", errors="replace")

    @staticmethod
    def _number(arg: str, cmd: str) -> float:
        try:
            v = float(arg)
        except ValueError:
            raise InvalidInputError(f"{cmd} needs a number; got {arg!r}") from None
        if not math.isfinite(v):
            raise InvalidInputError(f"{cmd} needs a finite number")
        return v

    def _servo_ready(self, i: int, cmd: str) -> None:
        if self.interlock[i] != "closed":
            why = f"fault: {self.fault[1]}" if self.fault else "servo off"
            raise InvalidInputError(f"{cmd}: axis {i + 1} {why}")

    def _execute(self, cmd: str, arg: str, i: int, t: float) -> str:
        if cmd == "VER":
            return self.version
        if cmd == "STA":
            fault = self.fault[1] if self.fault and self.interlock[i] == "fault" else None
            return aerosmith.encode_status(AerosmithStatus(self.modes[i],
                                                           self.interlock[i] == "closed", fault))
        if cmd in ("PPO", "PVE"):
            angles, rates = self.feedback(t)
            value = angles[i] if cmd == "PPO" else rates[i]
            return f"{value / units.DEG:.7f}"
        if cmd == "SRV":
            return self._servo(arg, i, t)
        if cmd in ("VEL", "ACL"):
            value = self._number(arg, cmd) * units.DEG
            top = self.abs_rate_rps[i] if cmd == "VEL" else self.abs_accel_rps2[i]
            if not 0.0 < value <= top * (1 + 1e-9):
                raise LimitExceededError(f"{cmd} {value / units.DEG:g} outside "
                                         f"(0, {top / units.DEG:g}]")
            if cmd == "VEL":
                self.rate_limit_rps[i] = value
            else:
                self.accel_limit_rps2[i] = value
            return _OK
        if cmd in ("MOV", "RMO", "HOM"):
            self._servo_ready(i, cmd)
            target = 0.0 if cmd == "HOM" else self._number(arg, cmd) * units.DEG
            if cmd == "RMO":
                target += self.true_angle_rad(i, t)
            self.command_position(i, target, t)
            self.modes[i] = "POS"
            return _OK
        if cmd == "JOG":
            rate = self._number(arg, cmd) * units.DEG
            if self.interlock[i] != "closed" or abs(rate) > self.rate_limit_rps[i] * (1 + 1e-9):
                self.refused += 1
                return ""
            self.command_rate(i, rate, t)
            self.modes[i] = "JOG"
            return ""
        if cmd == "STO":
            self.command_stop(i, t)
            if self.interlock[i] == "closed":
                self.modes[i] = "STOP"
            return _OK
        if cmd == "SGO":
            self.refused += 1
            return ""
        raise InvalidInputError(f"{cmd} is not supported by the simulator")

    def _servo(self, arg: str, i: int, t: float) -> str:
        if arg not in ("0", "1"):
            raise InvalidInputError(f"SRV needs 0 or 1; got {arg!r}")
        if arg == "0":
            self.command_off(i, t)
            self.modes[i] = "OFF"
            if self.interlock[i] != "fault":
                self.interlock[i] = "open"
            return _OK
        if self.fault is not None:
            if self.fault_cause_active:
                raise InvalidInputError(f"fault {self.fault[0]}: {self.fault[1]}")
            self.fault = None
            self.interlock = ["open" if s == "fault" else s for s in self.interlock]
        if self.interlock[i] != "closed":
            self.interlock[i] = "closed"
            self.command_position(i, self.true_angle_rad(i, t), t)
            self.modes[i] = "POS"
        return _OK
