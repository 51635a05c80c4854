"""An ACUTROL controller simulator speaking ACL over TCP, with a twin table behind it.

:class:`AclSimServer` parses each message with :func:`imucalib.drivers.acl.parse_message`
(short forms, ``;`` chaining), executes the commands in order at the current simulated time and
answers one reply line in our header convention (:mod:`imucalib.drivers.acl`). Readbacks in one
message come from one feedback sample. Fault hooks: :class:`~._motion.MotionSimServer`.

Commands served
---------------
``*IDN?``, ``*RST``, ``*CLS``; ``:U:L ON|OFF``; ``:I:O|C <ax|ALL>``, ``:I:R``, ``:I? <ax>``;
``:M:P|R|O <ax|ALL>`` (and ``:M <ax>,<P|R|O>``), ``:M? <ax>``; ``:D:P <ax>,<deg>``,
``:D:R <ax>,<deg/s>``; ``:LIM:RATE|ACC <P|R>,<ax>,<v>``, ``:LIM:ABS? <ax>``;
``:R:P? <ax>``, ``:R:R? <ax>``, ``:R:TIME?``; ``:S:CSR? SI``; ``:Q:E? <code>``, ``:Q:S?``.

Rules (our simulator's, **[unverified]** against a real ACUTROL)
-----------------------------------------------------------------
- Demands, modes other than off and closing an interlock need the remote lockout (error 200).
- ``:M:P``/``:M:R`` and demands need a closed interlock (201); a demand needs its mode (202);
  rates above the profiler limit, limits above the absolute limits, and moves beyond the travel
  answer 203; a latched interlock fault refuses ``:I:C`` (204) until its cause is gone and
  ``:I:R`` cleared it.
- ``:M:O`` and ``:I:O`` are always accepted (a stop must always work).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from imucalib import units
from imucalib.drivers import acl
from imucalib.drivers.acl import AclCommand, AclCommandError
from imucalib.drivers.simulators._base import SimTimeBase
from imucalib.drivers.simulators._motion import MotionSimServer
from imucalib.errors import InvalidInputError, LimitExceededError
from imucalib.sim.rig import TwinRig

__all__ = ["AclSimServer"]


class AclSimServer(MotionSimServer):
    """ACL over TCP on 127.0.0.1 with the rig's table (or centrifuge) behind it.

    Parameters
    ----------
    rig : TwinRig
        The twin.
    time_base : SimTimeBase
        Shared simulated time.
    device : {"table", "centrifuge"}
        Which motion device of the rig this controller drives.
    idn : str
        Answer to ``*IDN?``.
    port : int
        0: the OS picks (see :attr:`port`).

    Attributes
    ----------
    remote : bool
        Whether the remote lockout is taken.
    modes : list of str
        Mode letter of each axis (``P``, ``R``, ``O``).
    """

    terminator = acl.TERMINATOR

    def __init__(self, rig: TwinRig, time_base: SimTimeBase, *,
                 device: Literal["table", "centrifuge"] = "table",
                 idn: str = "ACUTRONIC,ACUTROL3000-SIM,0001,imucalib-twin", port: int = 0) -> None:
        super().__init__("acl-sim", rig, time_base, device=device, port=port)
        self.idn = idn
        self.remote = False
        self.modes = ["O"] * self.n_axes

    def on_fault(self) -> None:
        """Switch every axis off (an interlock fault)."""
        self.modes = ["O"] * self.n_axes

    # --- parsing helpers ----------------------------------------------------------------------
    def _axes(self, cmd: AclCommand, *, allow_all: bool = True) -> list[int]:
        if not cmd.args:
            raise AclCommandError(101, f"{cmd.header} needs an axis")
        arg = cmd.args[0].upper()
        if arg == "ALL" and allow_all and not cmd.query:
            return list(range(self.n_axes))
        try:
            n = int(arg)
        except ValueError:
            raise AclCommandError(101, f"{cmd.header}: bad axis {cmd.args[0]!r}") from None
        if not 1 <= n <= self.n_axes:
            raise AclCommandError(102, f"{cmd.header}: axis {n} (the controller has "
                                       f"{self.n_axes})")
        return [n - 1]

    @staticmethod
    def _value(cmd: AclCommand, index: int) -> float:
        try:
            v = float(cmd.args[index])
        except (IndexError, ValueError):
            raise AclCommandError(101, f"{cmd.header}: argument {index + 1} must be a "
                                       "number") from None
        if not math.isfinite(v):
            raise AclCommandError(101, f"{cmd.header}: argument {index + 1} must be finite")
        return v

    def _need_remote(self, cmd: AclCommand) -> None:
        if not self.remote:
            raise AclCommandError(200, cmd.header)

    def _need_closed(self, cmd: AclCommand, i: int) -> None:
        if self.interlock[i] != "closed":
            raise AclCommandError(201, f"{cmd.header}: axis {i + 1} interlock "
                                       f"{self.interlock[i]}")

    # --- execution ----------------------------------------------------------------------------
    def on_line(self, line: str) -> bytes:
        """Execute one message and return its reply line."""
        with self.rig.lock:
            t = self.now_s()
            answers: list[str] = []
            fb = None
            try:
                for cmd in acl.parse_message(line):
                    if cmd.path[:1] == ("READ",) and cmd.path[-1] in ("POSITION", "RATE"):
                        fb = fb if fb is not None else self.feedback(t)
                    out = self._execute(cmd, t, fb)
                    if out is not None:
                        answers.append(out)
            except AclCommandError as exc:
                return acl.encode_reply(exc.code, exc.text)
        return acl.encode_reply(0, ";".join(answers))

    def _execute(self, cmd: AclCommand, t: float,
                 fb: tuple[NDArray[np.float64], NDArray[np.float64]] | None) -> str | None:
        path = cmd.path
        head = path[0]
        if head.startswith("*"):
            return self._common(cmd)
        if head == "UTILITY" and path[-1] == "LOCKOUT" and not cmd.query:
            state = cmd.args[0].upper() if cmd.args else ""
            if state not in ("ON", "OFF", "1", "0"):
                raise AclCommandError(101, ":U:L needs ON or OFF")
            self.remote = state in ("ON", "1")
            return None
        if head == "INTERLOCK":
            return self._interlock(cmd, t)
        if head == "MODE":
            return self._mode(cmd, t)
        if head == "DEMAND" and len(path) == 2 and not cmd.query:
            self._demand(cmd, t)
            return None
        if head == "LIMIT" and len(path) == 2:
            return self._limit(cmd)
        if head == "READ" and len(path) == 2 and cmd.query:
            if path[1] == "TIMECLOCK":
                return f"{t * 1000.0:.3f}"
            if path[1] in ("POSITION", "RATE") and fb is not None:
                i = self._axes(cmd, allow_all=False)[0]
                angles, rates = fb
                value = angles[i] if path[1] == "POSITION" else rates[i]
                return f"{value / units.DEG:.7f}"
        if head == "STATUS" and path[-1] == "CSR" and cmd.query:
            return str(self.fault[0] if self.fault else 0)
        if head == "QUERY" and cmd.query:
            if path[-1] == "SYSTEM":
                return str(self.n_axes)
            if path[-1] == "ERROR":
                code = int(self._value(cmd, 0))
                if self.fault and code == self.fault[0]:
                    return self.fault[1]
                return acl.ERROR_TEXTS.get(code, "unknown code")
        raise AclCommandError(100, f"{cmd.header}{'?' if cmd.query else ''} is not supported "
                                   "by the simulator")

    def _common(self, cmd: AclCommand) -> str | None:
        if cmd.path[0] == "*IDN" and cmd.query:
            return self.idn
        if cmd.path[0] in ("*RST", "*CLS", "*WAI") and not cmd.query:
            return None
        if cmd.path[0] == "*OPC" and cmd.query:
            return "1"
        raise AclCommandError(100, f"{cmd.path[0]} is not supported by the simulator")

    def _interlock(self, cmd: AclCommand, t: float) -> str | None:
        if len(cmd.path) == 1:
            if not cmd.query:
                raise AclCommandError(100, ":I needs a subcommand or ?")
            i = self._axes(cmd, allow_all=False)[0]
            return {"closed": "Closed", "open": "Open", "fault": "Fault"}[self.interlock[i]]
        action = cmd.path[1]
        if action == "RESET":
            if self.fault is not None and not self.fault_cause_active:
                self.fault = None
                self.interlock = ["open" if s == "fault" else s for s in self.interlock]
            return None
        axes = self._axes(cmd)
        if action == "OPEN":
            for i in axes:
                self.command_off(i, t)
                self.modes[i] = "O"
                if self.interlock[i] != "fault":
                    self.interlock[i] = "open"
            return None
        if action == "CLOSE":
            self._need_remote(cmd)
            if self.fault is not None:
                raise AclCommandError(204, f"fault {self.fault[0]}: {self.fault[1]}")
            for i in axes:
                self.interlock[i] = "closed"
            return None
        raise AclCommandError(100, f"{cmd.header} is not supported by the simulator")

    def _mode(self, cmd: AclCommand, t: float) -> str | None:
        if cmd.query:
            return self.modes[self._axes(cmd, allow_all=False)[0]]
        if len(cmd.path) == 2:
            letter = {"POSITION": "P", "RATE": "R", "OFF": "O"}.get(cmd.path[1])
            axes = self._axes(cmd)
        else:  # :M <ax>,<letter>
            axes = self._axes(cmd)
            letter = cmd.args[1].upper()[:1] if len(cmd.args) > 1 else None
        if letter not in ("P", "R", "O"):
            raise AclCommandError(100, f"{cmd.header}: only modes P, R and O are simulated")
        for i in axes:
            if letter == "O":
                self.command_off(i, t)
            else:
                self._need_remote(cmd)
                self._need_closed(cmd, i)
                if letter == "P" and self.modes[i] != "P":
                    self._hold_position(i, t)
                elif letter == "R" and self.modes[i] != "R":
                    self._guard(functools.partial(self.command_rate, i, 0.0, t))
            self.modes[i] = letter
        return None

    def _hold_position(self, i: int, t: float) -> None:
        self._guard(functools.partial(self.command_position, i, self.true_angle_rad(i, t), t))

    def _demand(self, cmd: AclCommand, t: float) -> None:
        self._need_remote(cmd)
        i = self._axes(cmd, allow_all=False)[0]
        value = self._value(cmd, 1)
        self._need_closed(cmd, i)
        kind = cmd.path[1]
        if kind == "POSITION":
            if self.modes[i] != "P":
                raise AclCommandError(202, f"axis {i + 1} is in mode {self.modes[i]}, not P")
            self._guard(lambda: self.command_position(i, value * units.DEG, t))
            return
        if kind == "RATE":
            if self.modes[i] != "R":
                raise AclCommandError(202, f"axis {i + 1} is in mode {self.modes[i]}, not R")
            if abs(value) * units.DEG > self.rate_limit_rps[i] * (1 + 1e-9):
                raise AclCommandError(203, f"rate {value:g} °/s on axis {i + 1} exceeds the "
                                           f"limit {self.rate_limit_rps[i] / units.DEG:g} °/s")
            self._guard(lambda: self.command_rate(i, value * units.DEG, t))
            return
        raise AclCommandError(100, f"{cmd.header} is not supported by the simulator")

    @staticmethod
    def _guard(action: Callable[[], object]) -> None:
        try:
            action()
        except LimitExceededError as exc:
            raise AclCommandError(203, str(exc)) from exc
        except InvalidInputError as exc:
            raise AclCommandError(101, str(exc)) from exc

    def _limit(self, cmd: AclCommand) -> str | None:
        kind = cmd.path[1]
        if kind == "ABSOLUTE" and cmd.query:
            i = self._axes(cmd, allow_all=False)[0]
            return (f"{self.abs_rate_rps[i] / units.DEG:.6f},"
                    f"{self.abs_accel_rps2[i] / units.DEG:.6f}")
        if kind not in ("RATE", "ACCELERATION") or cmd.query or len(cmd.args) != 3:
            raise AclCommandError(100, f"{cmd.header}: only :LIM:RATE and :LIM:ACC "
                                       "<P|R>,<ax>,<v> and :LIM:ABS? are simulated")
        if cmd.args[0].upper() not in ("P", "R", "S", "T", "O", "A"):
            raise AclCommandError(101, f"{cmd.header}: bad profiler {cmd.args[0]!r}")
        i = self._axes(AclCommand(cmd.path, False, cmd.args[1:]), allow_all=False)[0]
        value = self._value(cmd, 2) * units.DEG
        top = self.abs_rate_rps[i] if kind == "RATE" else self.abs_accel_rps2[i]
        if value <= 0.0 or value > top * (1 + 1e-9):
            raise AclCommandError(203, f"{cmd.header}: {value / units.DEG:g} on axis {i + 1} "
                                       f"is outside (0, {top / units.DEG:g}]")
        if cmd.args[0].upper() in ("P", "R"):
            # the twin has one limit per axis: the last one set wins
            if kind == "RATE":
                self.rate_limit_rps[i] = value
            else:
                self.accel_limit_rps2[i] = value
        return None
