"""A Watlow F4T simulator: a Modbus TCP server whose registers are the twin chamber's state.

The server side of Modbus TCP is written here (MBAP header, function codes 3, 4, 6, 16 and
exception replies) rather than taken from pymodbus: the client under test is pymodbus, so an
independent server checks it against the protocol rather than against itself, and the
register values are computed when read (the chamber's temperature at the simulated time).

Registers (:mod:`imucalib.drivers.watlow_f4t`): the actual temperature and the working setpoint
come from the rig's chamber; writing the setpoint (with the control mode auto) commands the
chamber at the ramp the ramp registers give (at most the chamber's limit); control mode off is
standby (the setpoint drifts towards the rig's ambient temperature at 1 °C/min). Unmapped
addresses answer exception 2, values outside the chamber's range exception 3.

Fault hook: :meth:`F4TSimServer.raise_alarm` / :meth:`F4TSimServer.clear_alarms`, and the
inherited :meth:`~imucalib.drivers.simulators.SimServer.drop_connections`.
"""

from __future__ import annotations

import logging
import socket
import struct

import numpy as np

from imucalib.drivers import watlow_f4t as f4t
from imucalib.drivers.modbus import floats_to_registers, registers_to_floats
from imucalib.drivers.simulators._base import SimServer, SimTimeBase
from imucalib.errors import ConfigurationError, LimitExceededError
from imucalib.sim.rig import TwinRig

__all__ = ["F4TSimServer", "ModbusExceptionError"]

_LOG = logging.getLogger(__name__)
_STANDBY_RAMP_DEGC_PS = 1.0 / 60.0


class ModbusExceptionError(Exception):
    """A Modbus exception reply (1 illegal function, 2 illegal address, 3 illegal value)."""

    def __init__(self, code: int, detail: str = "") -> None:
        self.code = code
        super().__init__(f"Modbus exception {code}: {detail}")


class F4TSimServer(SimServer):
    """Watlow F4T registers over Modbus TCP on 127.0.0.1, with the rig's chamber behind them.

    Parameters
    ----------
    rig : TwinRig
        The twin; it must have a chamber.
    time_base : SimTimeBase
        Shared simulated time.
    part_number : str
        Answer in the part-number registers.
    n_alarms : int
        Alarm blocks served.
    port : int
        0: the OS picks (see :attr:`port`).

    Attributes
    ----------
    registers : dict of int to int
        The stored registers (computed ones are not stored).
    requests : int
        Modbus requests served.
    """

    def __init__(self, rig: TwinRig, time_base: SimTimeBase, *,
                 part_number: str = "F4T-SIM-TWIN-01", n_alarms: int = 6, port: int = 0) -> None:
        super().__init__("f4t-sim", port=port)
        if rig.chamber is None:
            raise ConfigurationError("F4TSimServer: the rig has no chamber")
        self.rig, self.time_base = rig, time_base
        self.chamber = rig.chamber
        spec = self.chamber.spec
        start_sp = float(self.chamber.setpoint_degc(np.array([0.0]))[0])
        self.registers: dict[int, int] = {}
        self._store(f4t.SETPOINT, floats_to_registers([start_sp]))
        self._store(f4t.RANGE_LOW, floats_to_registers([spec.min_temp_degc]))
        self._store(f4t.RANGE_HIGH, floats_to_registers([spec.max_temp_degc]))
        self._store(f4t.RAMP_RATE, floats_to_registers([spec.max_ramp_degc_ps * 60.0]))
        self._store(f4t.PART_NUMBER, f4t.encode_string(part_number, f4t.PART_NUMBER_LENGTH))
        self.registers.update({f4t.CONTROL_MODE: f4t.MODE_AUTO, f4t.RAMP_ACTION: f4t.RAMP_OFF,
                               f4t.RAMP_SCALE: f4t.SCALE_MINUTES,
                               f4t.DISPLAY_UNITS: f4t.UNITS_C})
        self.n_alarms = int(n_alarms)
        for k in range(self.n_alarms):
            self.registers[f4t.alarm_register(k)] = 61
        self.requests = 0

    def _store(self, address: int, values: list[int]) -> None:
        for k, v in enumerate(values):
            self.registers[address + k] = int(v) & 0xFFFF

    # --- fault hooks --------------------------------------------------------------------------
    def raise_alarm(self, index: int = 0, state: int = 37) -> None:
        """Fault: put alarm `index` (0-based) in an active `state` (37 high, 53 low, 28 error)."""
        if not 0 <= index < self.n_alarms or state in f4t.ALARM_INACTIVE:
            raise ConfigurationError(f"alarm index must be 0–{self.n_alarms - 1} and the state "
                                     f"active; got {index}, {state}")
        self.registers[f4t.alarm_register(index)] = int(state)
        _LOG.info("%s: alarm %d raised (state %d)", self.name, index + 1, state)

    def clear_alarms(self) -> None:
        """Return every alarm to state none (61)."""
        for k in range(self.n_alarms):
            self.registers[f4t.alarm_register(k)] = 61

    # --- registers ----------------------------------------------------------------------------
    def _computed(self, t: float) -> dict[int, int]:
        air = float(self.chamber.air_temperature_degc(np.array([t]))[0])
        sp = float(self.chamber.setpoint_degc(np.array([t]))[0])
        out = {}
        for address, value in ((f4t.PROCESS_VALUE, air), (f4t.WORKING_SETPOINT, sp)):
            for k, reg in enumerate(floats_to_registers([value])):
                out[address + k] = reg
        return out

    def read(self, address: int, count: int) -> list[int]:
        """Return `count` registers from `address` (exception 2 for an unmapped one)."""
        if not 1 <= count <= 125:
            raise ModbusExceptionError(3, f"count {count}")
        with self.rig.lock:
            computed = self._computed(self.time_base.now_s())
        out = []
        for a in range(address, address + count):
            if a in computed:
                out.append(computed[a])
            elif a in self.registers:
                out.append(self.registers[a])
            else:
                raise ModbusExceptionError(2, f"address {a} is not mapped")
        return out

    def write(self, address: int, values: list[int]) -> None:
        """Store `values` and act on the setpoint and control-mode registers."""
        span = range(address, address + len(values))
        writable = {f4t.SETPOINT, f4t.SETPOINT + 1, f4t.CONTROL_MODE, f4t.RAMP_ACTION,
                    f4t.RAMP_SCALE, f4t.RAMP_RATE, f4t.RAMP_RATE + 1}
        bad = [a for a in span if a not in writable]
        if bad:
            raise ModbusExceptionError(2, f"address {bad[0]} is not writable")
        with self.rig.lock:
            old = dict(self.registers)
            self._store(address, values)
            try:
                if f4t.SETPOINT in span or f4t.SETPOINT + 1 in span:
                    lo, hi = self.chamber.spec.min_temp_degc, self.chamber.spec.max_temp_degc
                    if not lo <= self._float(f4t.SETPOINT) <= hi:
                        raise ModbusExceptionError(3, "setpoint outside the chamber's range")
                if f4t.CONTROL_MODE in span and values[f4t.CONTROL_MODE - address] not in (
                        f4t.MODE_AUTO, f4t.MODE_MANUAL, f4t.MODE_OFF):
                    raise ModbusExceptionError(3, "unknown control mode")
                self._apply(self.time_base.now_s(), setpoint_written=f4t.SETPOINT in span,
                            mode_written=f4t.CONTROL_MODE in span, old_mode=old.get(
                                f4t.CONTROL_MODE, f4t.MODE_AUTO))
            except ModbusExceptionError:
                self.registers = old
                raise

    def _float(self, address: int) -> float:
        return registers_to_floats([self.registers[address], self.registers[address + 1]])[0]

    def _apply(self, t: float, *, setpoint_written: bool, mode_written: bool,
               old_mode: int) -> None:
        mode = self.registers[f4t.CONTROL_MODE]
        running = mode in (f4t.MODE_AUTO, f4t.MODE_MANUAL)
        spec = self.chamber.spec
        if not running:
            if mode_written and old_mode != mode:  # standby: drift towards the room
                ambient = min(max(self.rig.ambient_temperature_degc, spec.min_temp_degc),
                              spec.max_temp_degc)
                self.chamber.command_setpoint(ambient, t, min(_STANDBY_RAMP_DEGC_PS,
                                                              spec.max_ramp_degc_ps))
            return
        if not (setpoint_written or (mode_written and old_mode != mode)):
            return
        ramp = None
        if self.registers[f4t.RAMP_ACTION] == f4t.RAMP_SETPOINT:
            per = 60.0 if self.registers[f4t.RAMP_SCALE] == f4t.SCALE_MINUTES else 3600.0
            ramp = min(self._float(f4t.RAMP_RATE) / per, spec.max_ramp_degc_ps)
            ramp = ramp if ramp > 0 else None
        try:
            self.chamber.command_setpoint(self._float(f4t.SETPOINT), t, ramp)
        except LimitExceededError as exc:
            raise ModbusExceptionError(3, str(exc)) from exc

    # --- Modbus TCP framing -------------------------------------------------------------------
    def handle(self, conn: socket.socket) -> None:
        """Serve Modbus TCP requests until the client disconnects."""
        buf = b""
        while not self._closed.is_set():
            data = conn.recv(4096)
            if not data:
                return
            buf += data
            while len(buf) >= 7:
                tid, pid, length, unit = struct.unpack(">HHHB", buf[:7])
                if len(buf) < 6 + length:
                    break
                pdu, buf = buf[7:6 + length], buf[6 + length:]
                reply = self._pdu(pdu) if pid == 0 else None
                if reply is not None:
                    conn.sendall(struct.pack(">HHHB", tid, 0, len(reply) + 1, unit) + reply)

    def _pdu(self, pdu: bytes) -> bytes:
        self.requests += 1
        fc = pdu[0] if pdu else 0
        try:
            if fc in (3, 4) and len(pdu) == 5:
                address, count = struct.unpack(">HH", pdu[1:5])
                regs = self.read(address, count)
                return bytes([fc, 2 * len(regs)]) + struct.pack(f">{len(regs)}H", *regs)
            if fc == 6 and len(pdu) == 5:
                address, value = struct.unpack(">HH", pdu[1:5])
                self.write(address, [value])
                return pdu[:5]
            if fc == 16 and len(pdu) >= 6:
                address, count, nbytes = struct.unpack(">HHB", pdu[1:6])
                if nbytes != 2 * count or len(pdu) != 6 + nbytes:
                    raise ModbusExceptionError(3, "byte count")
                self.write(address, list(struct.unpack(f">{count}H", pdu[6:6 + nbytes])))
                return pdu[:5]
            raise ModbusExceptionError(1, f"function {fc}")
        except ModbusExceptionError as exc:
            _LOG.debug("%s: %s", self.name, exc)
            return bytes([(fc | 0x80) & 0xFF, exc.code])
