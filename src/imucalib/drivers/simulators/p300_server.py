"""An Espec P300 simulator speaking its ASCII dialect (CR LF), with the twin chamber behind it.

Serves ``ROM?``, ``TYPE?``, ``TEMP?``, ``TEMP, S…``, ``MODE?``, ``MODE, CONSTANT|STANDBY|OFF``,
``ALARM?`` and ``RUN PRGM, TEMP<a> TIME<h>:<m> GOTEMP<b>`` (:mod:`imucalib.drivers.espec_p300`),
answering ``OK: <command>`` or ``NA:<reason>``; an ``n,`` address prefix is accepted. A
serial client reaches it through ``socket://127.0.0.1:PORT``.

Physics: ``CONSTANT`` commands the chamber to the constant setpoint (at its ramp limit); a remote
program ramps linearly to its goal (at most at the chamber's limit; mode ``RUN`` until the ramp
ends, then ``CONSTANT`` at the goal, **[unverified]** end behaviour); ``STANDBY``/``OFF`` let the
setpoint drift towards the rig's ambient temperature at 1 °C/min. ``TEMP?`` answers the air
temperature and the working setpoint.

Fault hooks: :meth:`P300SimServer.raise_alarm`, :meth:`P300SimServer.clear_alarms`, and
:meth:`~imucalib.drivers.simulators.SimServer.drop_connections`.
"""

from __future__ import annotations

import numpy as np

from imucalib.drivers import espec_p300
from imucalib.drivers.simulators._base import LineSimServer, SimTimeBase
from imucalib.errors import ConfigurationError, InvalidInputError
from imucalib.sim.rig import TwinRig

__all__ = ["P300SimServer"]

_STANDBY_RAMP_DEGC_PS = 1.0 / 60.0


class P300SimServer(LineSimServer):
    """The P300 dialect on 127.0.0.1 with the rig's chamber behind it.

    Parameters
    ----------
    rig : TwinRig
        The twin; it must have a chamber.
    time_base : SimTimeBase
        Shared simulated time.
    rom : str
        Answer to ``ROM?``.
    port : int
        0: the OS picks.

    Attributes
    ----------
    mode : str
        ``CONSTANT``, ``STANDBY`` or ``OFF`` (``RUN`` while a program ramps).
    alarms : list of int
        Active alarm codes.
    """

    terminator = espec_p300.TERMINATOR

    def __init__(self, rig: TwinRig, time_base: SimTimeBase, *, rom: str = "P300-SIM 1.00",
                 port: int = 0) -> None:
        super().__init__("p300-sim", rig, time_base, port=port)
        if rig.chamber is None:
            raise ConfigurationError("P300SimServer: the rig has no chamber")
        self.chamber = rig.chamber
        self.rom = rom
        self.mode = "CONSTANT"
        self.constant_setpoint_degc = float(self.chamber.setpoint_degc(np.array([0.0]))[0])
        self.program_end_s: float | None = None
        self.alarms: list[int] = []

    def raise_alarm(self, code: int = 12) -> None:
        """Fault: add an active alarm code (``ALARM?`` lists it)."""
        self.alarms.append(int(code))

    def clear_alarms(self) -> None:
        """Clear every alarm."""
        self.alarms = []

    def _mode_now(self, t: float) -> str:
        if self.program_end_s is not None:
            if t < self.program_end_s:
                return "RUN"
            self.program_end_s = None
            self.mode = "CONSTANT"
        return self.mode

    def on_line(self, line: str) -> bytes:
        """Answer one command line."""
        text = line.strip()
        if text[:1].isdigit() and "," in text and text.split(",", 1)[0].isdigit():
            text = text.split(",", 1)[1].strip()  # RS-485 address prefix
        with self.rig.lock:
            t = self.time_base.now_s()
            try:
                reply = self._execute(text, t)
            except InvalidInputError as exc:
                reply = f"NA:{exc}"
        return reply.encode("ascii", errors="replace") + espec_p300.TERMINATOR

    def _execute(self, text: str, t: float) -> str:
        upper = text.upper()
        spec = self.chamber.spec
        if upper == "ROM?":
            return self.rom
        if upper == "TYPE?":
            return f"T,P300,{spec.max_temp_degc:.1f}"
        if upper == "TEMP?":
            air = float(self.chamber.air_temperature_degc(np.array([t]))[0])
            sp = float(self.chamber.setpoint_degc(np.array([t]))[0])
            return f"{air:.2f},{sp:.2f},{spec.max_temp_degc:.1f},{spec.min_temp_degc:.1f}"
        if upper == "MODE?":
            return self._mode_now(t)
        if upper == "ALARM?":
            return ",".join(str(v) for v in [len(self.alarms), *self.alarms])
        head, _, args = text.partition(",")
        head = head.strip().upper()
        if head == "TEMP":
            try:
                values = espec_p300.parse_setpoint_args(args)
            except InvalidInputError:
                raise InvalidInputError("PARA ERR") from None
            target = values.get("S")
            if target is not None:
                if not spec.min_temp_degc <= target <= spec.max_temp_degc:
                    raise InvalidInputError("DATA OUT OF RANGE")
                self.constant_setpoint_degc = target
                if self._mode_now(t) == "CONSTANT":
                    self.chamber.command_setpoint(target, t)
            return f"OK: {text}"
        if head == "MODE":
            return self._set_mode(args.strip().upper(), text, t)
        if head == "RUN PRGM":
            try:
                start, goal, duration = espec_p300.parse_ramp_program(args)
            except InvalidInputError:
                raise InvalidInputError("PARA ERR") from None
            if not all(spec.min_temp_degc <= v <= spec.max_temp_degc for v in (start, goal)) \
                    or duration <= 0:
                raise InvalidInputError("DATA OUT OF RANGE")
            rate = min(abs(goal - start) / duration, spec.max_ramp_degc_ps)
            end = self.chamber.command_setpoint(goal, t, rate if rate > 0 else None)
            self.program_end_s = max(end, t + duration)
            return f"OK: {text}"
        raise InvalidInputError("CMD ERR")

    def _set_mode(self, mode: str, text: str, t: float) -> str:
        spec = self.chamber.spec
        if mode == "CONSTANT":
            self.program_end_s = None
            self.mode = "CONSTANT"
            self.chamber.command_setpoint(self.constant_setpoint_degc, t)
        elif mode in ("STANDBY", "OFF"):
            self.program_end_s = None
            if self.mode not in ("STANDBY", "OFF"):
                ambient = min(max(self.rig.ambient_temperature_degc, spec.min_temp_degc),
                              spec.max_temp_degc)
                self.chamber.command_setpoint(ambient, t, min(_STANDBY_RAMP_DEGC_PS,
                                                              spec.max_ramp_degc_ps))
            self.mode = mode
        else:
            raise InvalidInputError("PARA ERR")
        return f"OK: {text}"
