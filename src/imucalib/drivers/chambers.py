"""Thermal chambers on real controllers: Watlow F4T (Modbus TCP) and Espec P300 (ASCII).

Both classes implement :class:`~imucalib.station.devices.ChamberDevice`.

Contents
--------
:class:`WatlowF4TChamber`
    Registers of :mod:`~imucalib.drivers.watlow_f4t` through a
    :class:`~imucalib.drivers.modbus.RegisterLink` (Modbus TCP, port 502).
:class:`EspecP300Chamber`
    Commands of :mod:`~imucalib.drivers.espec_p300` over a line transport (serial, or TCP
    through a serial server).

Behaviour
---------
- The setpoint range (``min_temp_degc`` … ``max_temp_degc``) is checked **before** anything is
  sent: :class:`~imucalib.errors.LimitExceededError` names the value and the range.
- ``poll`` returns one row (air temperature, working setpoint) stamped with the station clock
  at the midpoint of the exchange.
- ``status`` reports alarms as text (``alarm 1: high``; Espec: ``alarm codes [12]``) and never
  raises for an alarm; ``standby`` never raises.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from imucalib.drivers import espec_p300, watlow_f4t
from imucalib.drivers.base import DeviceCheck, LineChannel, TransportOpener
from imucalib.drivers.modbus import RegisterLink, read_floats, read_string
from imucalib.errors import ConfigurationError, DeviceError, InvalidInputError, LimitExceededError
from imucalib.station.devices import ChamberReadings, ChamberStatus, Clock

__all__ = ["EspecP300Chamber", "WatlowF4TChamber"]

_LOG = logging.getLogger(__name__)


class _ChamberDriver:
    """Shared: range check, one-row readings, the station check."""

    kind = "chamber"

    def __init__(self, name: str, *, clock: Clock, min_temp_degc: float, max_temp_degc: float,
                 address: str = "") -> None:
        lo, hi = float(min_temp_degc), float(max_temp_degc)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ConfigurationError(f"{name}: range must be finite with min < max; got "
                                     f"[{lo}, {hi}] °C")
        self.name = name
        self.min_temp_degc, self.max_temp_degc = lo, hi
        self.address = address
        self._clock = clock
        self._identity: str | None = None

    def _check_setpoint(self, temperature_degc: float, ramp_degc_ps: float | None
                        ) -> tuple[float, float | None]:
        t = float(temperature_degc)
        if not math.isfinite(t):
            raise InvalidInputError(f"{self.name}: setpoint must be finite; got "
                                    f"{temperature_degc!r}")
        if not self.min_temp_degc <= t <= self.max_temp_degc:
            raise LimitExceededError(
                f"{self.name}: setpoint {t:g} °C is outside the range "
                f"[{self.min_temp_degc:g}, {self.max_temp_degc:g}] °C; nothing was sent"
            )
        if ramp_degc_ps is not None:
            r = float(ramp_degc_ps)
            if not math.isfinite(r) or r <= 0.0:
                raise InvalidInputError(f"{self.name}: ramp must be > 0 °C/s; got "
                                        f"{ramp_degc_ps!r}")
            return t, r
        return t, None

    def _reading(self, read: Callable[[], tuple[float, float]]) -> ChamberReadings:
        t0 = self._clock.now_s()
        air, sp = read()
        t1 = self._clock.now_s()
        return ChamberReadings(np.array([0.5 * (t0 + t1)]), np.array([air]), np.array([sp]))

    def _check_result(self, status: ChamberStatus, reading: ChamberReadings) -> DeviceCheck:
        state = ("running" if status.running else "standby") + (
            f"; ALARM {status.alarm}" if status.alarm else "")
        return DeviceCheck(
            "chamber", self.name, self.kind, self.address, self._identity or "", state,
            f"air {reading.temperature_degc[0]:.2f} °C, setpoint {reading.setpoint_degc[0]:.2f} °C",
            ok=status.alarm is None,
            details={"running": status.running, "alarm": status.alarm,
                     "temperature_degc": float(reading.temperature_degc[0]),
                     "setpoint_degc": float(reading.setpoint_degc[0])})

    def describe(self) -> dict[str, Any]:
        """Return a JSON-able description (kind, address, range, identity)."""
        return {"role": "chamber", "name": self.name, "kind": self.kind, "address": self.address,
                "identity": self._identity, "min_temp_degc": self.min_temp_degc,
                "max_temp_degc": self.max_temp_degc}


class WatlowF4TChamber(_ChamberDriver):
    """A chamber on a Watlow F4T controller (Modbus, Data Map 1, loop 1).

    Parameters
    ----------
    name : str
        Device name.
    opener : callable
        Returns an opened :class:`~imucalib.drivers.modbus.RegisterLink`.
    clock : Clock
        The station clock.
    min_temp_degc, max_temp_degc : float
        Software setpoint range. [°C]
    n_alarms : int
        Number of alarm blocks to scan in :meth:`status`.
    address : str
        Transport URL, for descriptions.
    """

    kind = "watlow-f4t"

    def __init__(self, name: str, opener: Callable[[], RegisterLink], *, clock: Clock,
                 min_temp_degc: float, max_temp_degc: float, n_alarms: int = 6,
                 address: str = "") -> None:
        super().__init__(name, clock=clock, min_temp_degc=min_temp_degc,
                         max_temp_degc=max_temp_degc, address=address)
        self._opener = opener
        self._link: RegisterLink | None = None
        self.n_alarms = int(n_alarms)
        self._units = watlow_f4t.UNITS_C

    def _require(self) -> RegisterLink:
        if self._link is None:
            raise DeviceError(f"{self.name}: not connected; call connect()")
        return self._link

    def _io(self, fn: Callable[[RegisterLink], Any]) -> Any:
        link = self._require()
        try:
            return fn(link)
        except DeviceError:
            self._drop()
            raise

    def _write(self, address: int, values: list[int]) -> None:
        self._io(lambda ln: ln.write_registers(address, values))

    def _read(self, address: int, count: int) -> list[int]:
        regs: list[int] = self._io(lambda ln: ln.read_registers(address, count))
        return regs

    def _drop(self) -> None:
        link, self._link = self._link, None
        if link is not None:
            link.close()

    def connect(self) -> None:
        """Open the link and read the display units (°C or °F)."""
        if self._link is None:
            self._link = self._opener()
        self._units = self._read(watlow_f4t.DISPLAY_UNITS, 1)[0]
        watlow_f4t.to_celsius(0.0, self._units)  # raises for an unknown units code

    def disconnect(self) -> None:
        """Close the link."""
        self._drop()

    def identify(self) -> str:
        """Return the controller's part number (registers 16–30)."""
        self._identity = "Watlow F4T " + self._io(lambda ln: read_string(
            ln, watlow_f4t.PART_NUMBER, watlow_f4t.PART_NUMBER_LENGTH))
        return self._identity

    def set_temperature(self, temperature_degc: float, *,
                        ramp_degc_ps: float | None = None) -> None:
        """Run loop 1 at a setpoint, ramping at `ramp_degc_ps` (None: no ramp). [°C], [°C/s]"""
        t, ramp = self._check_setpoint(temperature_degc, ramp_degc_ps)
        value = watlow_f4t.from_celsius(t, self._units)
        ramp_units = None if ramp is None else (ramp * 1.8 if self._units == watlow_f4t.UNITS_F
                                                else ramp)
        for address, regs in watlow_f4t.setpoint_writes(value, ramp_units):
            self._write(address, regs)

    def standby(self) -> None:
        """Switch loop 1 off (control mode off); never raises."""
        try:
            if self._link is None:
                self._link = self._opener()
            self._write(watlow_f4t.CONTROL_MODE, [watlow_f4t.MODE_OFF])
        except Exception as exc:  # the contract: never raise
            _LOG.error("%s: standby failed: %s", self.name, exc)

    def _read_pv_sp(self) -> tuple[float, float]:
        pv = self._io(lambda ln: read_floats(ln, watlow_f4t.PROCESS_VALUE))[0]
        sp = self._io(lambda ln: read_floats(ln, watlow_f4t.WORKING_SETPOINT))[0]
        return (watlow_f4t.to_celsius(pv, self._units), watlow_f4t.to_celsius(sp, self._units))

    def poll(self) -> ChamberReadings:
        """Return the air temperature and the working setpoint now (one row). [°C]"""
        return self._reading(self._read_pv_sp)

    def status(self) -> ChamberStatus:
        """Return running (control mode auto/manual) and the active alarms' text."""
        mode = self._read(watlow_f4t.CONTROL_MODE, 1)[0]
        alarms = []
        for i in range(self.n_alarms):
            state = self._read(watlow_f4t.alarm_register(i), 1)[0]
            text = watlow_f4t.alarm_text(i, state)
            if text:
                alarms.append(text)
        return ChamberStatus(mode in (watlow_f4t.MODE_AUTO, watlow_f4t.MODE_MANUAL),
                             "; ".join(alarms) or None)

    def check(self) -> DeviceCheck:
        """Connect, identify, read status and one reading, disconnect; changes nothing."""
        try:
            self.connect()
            self.identify()
            result = self._check_result(self.status(), self.poll())
        finally:
            self.disconnect()
        return result


class EspecP300Chamber(_ChamberDriver):
    """A chamber on an Espec P300 controller (ASCII, CR LF).

    Parameters
    ----------
    name, clock, min_temp_degc, max_temp_degc, address
        As for :class:`WatlowF4TChamber`.
    opener : callable
        Returns an opened line transport (serial, or TCP to a serial server).
    rs485_address : int, optional
        Prefix ``n,`` for RS-485 multi-drop lines.
    timeout_s : float
        Reply time-out. [s]
    """

    kind = "espec-p300"

    def __init__(self, name: str, opener: TransportOpener, *, clock: Clock,
                 min_temp_degc: float, max_temp_degc: float, rs485_address: int | None = None,
                 timeout_s: float = 2.0, address: str = "") -> None:
        super().__init__(name, clock=clock, min_temp_degc=min_temp_degc,
                         max_temp_degc=max_temp_degc, address=address)
        self._ch = LineChannel(name, opener, terminator=espec_p300.TERMINATOR,
                               timeout_s=timeout_s, logger=_LOG)
        self.rs485_address = rs485_address

    def _cmd(self, command: str) -> str:
        line = self._ch.exchange(espec_p300.format_command(command, address=self.rs485_address))
        return espec_p300.parse_reply(line[0], command)

    def connect(self) -> None:
        """Open the link."""
        self._ch.open()

    def disconnect(self) -> None:
        """Close the link."""
        self._ch.close()

    def identify(self) -> str:
        """Return ``TYPE?`` and ``ROM?`` (controller type and ROM version)."""
        self._identity = f"Espec {self._cmd('TYPE?')} ROM {self._cmd('ROM?')}"
        return self._identity

    def set_temperature(self, temperature_degc: float, *,
                        ramp_degc_ps: float | None = None) -> None:
        """Run at a setpoint: ``TEMP, S…`` and ``MODE, CONSTANT``; a ramp runs a remote program.

        With a ramp, the chamber runs ``RUN PRGM`` from the current setpoint to the target over
        whole minutes (never faster than `ramp_degc_ps`). [°C], [°C/s]
        """
        t, ramp = self._check_setpoint(temperature_degc, ramp_degc_ps)
        if ramp is None:
            self._cmd(espec_p300.set_temperature(t))
            self._cmd("MODE, CONSTANT")
            return
        start = espec_p300.parse_temp(self._cmd("TEMP?")).setpoint_degc
        self._cmd(espec_p300.set_temperature(t))  # the constant setpoint once the program ends
        self._cmd(espec_p300.run_ramp_program(start, t, abs(t - start) / ramp))

    def standby(self) -> None:
        """Stop conditioning (``MODE, STANDBY``); never raises."""
        try:
            if not self._ch.is_open:
                self._ch.open()
            self._cmd("MODE, STANDBY")
        except Exception as exc:  # the contract: never raise
            _LOG.error("%s: standby failed: %s", self.name, exc)

    def _read_pv_sp(self) -> tuple[float, float]:
        reading = espec_p300.parse_temp(self._cmd("TEMP?"))
        return reading.process_degc, reading.setpoint_degc

    def poll(self) -> ChamberReadings:
        """Return the air temperature and setpoint now (``TEMP?``, one row). [°C]"""
        return self._reading(self._read_pv_sp)

    def status(self) -> ChamberStatus:
        """Return running (``MODE?`` CONSTANT or RUN) and the active alarm codes."""
        mode = espec_p300.parse_mode(self._cmd("MODE?"))
        codes = espec_p300.parse_alarm(self._cmd("ALARM?"))
        running = mode.startswith(("CONSTANT", "RUN", "RMT RUN"))
        return ChamberStatus(running, f"alarm codes {codes}" if codes else None)

    def check(self) -> DeviceCheck:
        """Connect, identify, read status and one reading, disconnect; changes nothing."""
        try:
            self.connect()
            self.identify()
            result = self._check_result(self.status(), self.poll())
        finally:
            self.disconnect()
        return result
