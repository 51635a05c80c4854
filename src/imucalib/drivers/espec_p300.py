"""The Espec P300 (and SCP-220-compatible) ASCII dialect: pure formatting and parsing.

Sources: ChamberConnectLibrary ``p300.py`` / ``especinteract.py`` **[code]**
(docs/drivers.md, "Sources"). Over RS-232/485, optionally prefixed by an address ``n,``; over
TCP through a serial server (port 10001 in that code). Commands and replies end in CR LF.

Commands used
-------------
========================================  =====================================================
``ROM?``                                  controller ROM version (identification)
``TYPE?``                                 sensor, controller, maximum temperature
``TEMP?``                                 ``PV,SP,HIGH,LOW`` [°C]
``TEMP, S<sp>``                           constant setpoint (0.1 °C resolution)
``MODE?``                                 ``OFF``, ``STANDBY``, ``CONSTANT`` or ``RUN…``
``MODE, CONSTANT`` / ``MODE, STANDBY``    run at the constant setpoint / stop conditioning
``ALARM?``                                ``<n>[,<code>…]``: number of active alarms and codes
``RUN PRGM, TEMP<a> TIME<h>:<m> GOTEMP<b>``  remote one-step program: ramp a → b in h:m
========================================  =====================================================

A refused command answers ``NA:<reason>``; other commands answer ``OK: <command>``
**[code]**. What the chamber does when a remote program ends (our simulator holds the goal
temperature in ``CONSTANT``) and the meaning of alarm codes are **[unverified]**.

Contents
--------
:func:`format_command`, :func:`set_temperature`, :func:`run_ramp_program`, :func:`parse_reply`,
:class:`TempReading`, :func:`parse_temp`, :func:`parse_mode`, :func:`parse_alarm`,
:func:`parse_setpoint_args` (simulator), :func:`parse_ramp_program` (simulator),
:data:`ERROR_DESCRIPTIONS`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from imucalib.errors import DeviceError, InvalidInputError

__all__ = [
    "ERROR_DESCRIPTIONS",
    "TERMINATOR",
    "TempReading",
    "format_command",
    "parse_alarm",
    "parse_mode",
    "parse_ramp_program",
    "parse_reply",
    "parse_setpoint_args",
    "parse_temp",
    "run_ramp_program",
    "set_temperature",
]

TERMINATOR = b"\r\n"

#: Reasons a P300 gives after ``NA:`` [code].
ERROR_DESCRIPTIONS = {
    "CMD ERR": "unrecognised command",
    "ADDR ERR": "bad address",
    "PARA ERR": "parameter missing or unrecognisable",
    "DATA OUT OF RANGE": "value outside the valid range",
    "PROTECT ON": "data protection is on at the controller",
    "CHB NOT READY": "the chamber could not act on the command",
    "INVALID REQ": "unsupported function",
}


def _check(value: float, name: str) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise InvalidInputError(f"`{name}` must be finite; got {value!r}")
    return v


def format_command(command: str, *, address: int | None = None) -> bytes:
    """Return the bytes of `command`, with an RS-485 address prefix ``n,`` when given."""
    prefix = "" if address is None else f"{int(address)},"
    return (prefix + command).encode("ascii") + TERMINATOR


def set_temperature(setpoint_degc: float) -> str:
    """``TEMP, S<sp>``: the constant temperature setpoint (0.1 °C). [°C]"""
    return f"TEMP, S{_check(setpoint_degc, 'setpoint_degc'):.1f}"


def run_ramp_program(start_degc: float, goal_degc: float, duration_s: float) -> str:
    """``RUN PRGM, TEMP<a> TIME<h>:<m> GOTEMP<b>``: ramp from `start` to `goal`.

    The duration is rounded up to whole minutes (at least one), so the ramp is never faster than
    asked. [°C], [s]
    """
    minutes = max(1, math.ceil(_check(duration_s, "duration_s") / 60.0 - 1e-9))
    return (f"RUN PRGM, TEMP{_check(start_degc, 'start_degc'):.1f} "
            f"TIME{minutes // 60}:{minutes % 60} GOTEMP{_check(goal_degc, 'goal_degc'):.1f}")


def parse_reply(line: bytes, command: str) -> str:
    """Return a reply's text, raising on ``NA:``.

    Raises
    ------
    DeviceError
        If the chamber answered ``NA:<reason>`` (the message names the command and the reason)
        or the reply is not ASCII.
    """
    try:
        text = line.decode("ascii").strip()
    except UnicodeDecodeError as exc:
        raise DeviceError(f"Espec {command!r}: reply {line!r} is not ASCII") from exc
    if text.startswith("NA:"):
        reason = text[3:].strip()
        detail = ERROR_DESCRIPTIONS.get(reason.split("-")[0].strip(), "no description")
        raise DeviceError(f"Espec {command!r}: the chamber refused it: {reason} ({detail})")
    return text


@dataclass(frozen=True)
class TempReading:
    """A ``TEMP?`` answer: process value, setpoint, high and low limits. [°C]"""

    process_degc: float
    setpoint_degc: float
    high_degc: float
    low_degc: float


def parse_temp(text: str) -> TempReading:
    """Parse ``PV,SP,HIGH,LOW``.

    Raises
    ------
    DeviceError
        If the answer does not hold four numbers.
    """
    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise DeviceError(f"Espec TEMP?: expected PV,SP,HIGH,LOW numbers; got {text!r}") from None
    if len(values) != 4:
        raise DeviceError(f"Espec TEMP?: expected 4 values PV,SP,HIGH,LOW; got {text!r}")
    return TempReading(*values)


def parse_mode(text: str) -> str:
    """Return the operating mode (``OFF``, ``STANDBY``, ``CONSTANT``, ``RUN …``).

    Raises
    ------
    DeviceError
        For an unknown mode word.
    """
    mode = text.strip().upper()
    if mode.split(" ")[0] not in ("OFF", "STANDBY", "CONSTANT", "RUN", "RMT"):
        raise DeviceError(f"Espec MODE?: unknown mode {text!r}")
    return mode


def parse_alarm(text: str) -> list[int]:
    """Return the active alarm codes of an ``ALARM?`` answer (empty when none).

    Raises
    ------
    DeviceError
        If the answer is not ``<n>[,<code>…]`` with n codes.
    """
    try:
        parts = [int(p) for p in text.split(",")]
    except ValueError:
        raise DeviceError(f"Espec ALARM?: expected integers; got {text!r}") from None
    if not parts or parts[0] != len(parts) - 1:
        raise DeviceError(f"Espec ALARM?: expected a count then that many codes; got {text!r}")
    return parts[1:]


_SETPOINT_ARG = re.compile(r"^\s*([SHL])\s*(-?\d+(?:\.\d*)?)\s*$", re.IGNORECASE)
_PROGRAM = re.compile(
    r"^TEMP\s*(-?\d+(?:\.\d*)?)\s+TIME\s*(\d+):(\d+)\s+GOTEMP\s*(-?\d+(?:\.\d*)?)\s*$",
    re.IGNORECASE)


def parse_setpoint_args(args: str) -> dict[str, float]:
    """Parse the arguments of ``TEMP, S23.0 H80.0 L-40.0`` into {"S": 23.0, …} (simulator).

    Raises
    ------
    InvalidInputError
        For an argument that is not S, H or L followed by a number.
    """
    out: dict[str, float] = {}
    for token in args.replace(",", " ").split():
        m = _SETPOINT_ARG.match(token)
        if m is None:
            raise InvalidInputError(f"bad TEMP argument {token!r}")
        out[m.group(1).upper()] = float(m.group(2))
    if not out:
        raise InvalidInputError("TEMP needs S, H or L values")
    return out


def parse_ramp_program(args: str) -> tuple[float, float, float]:
    """Parse ``TEMP<a> TIME<h>:<m> GOTEMP<b>`` into (a [°C], b [°C], duration [s]) (simulator).

    Raises
    ------
    InvalidInputError
        If the arguments do not have that form.
    """
    m = _PROGRAM.match(args.strip())
    if m is None:
        raise InvalidInputError(f"bad RUN PRGM arguments {args!r}")
    return float(m.group(1)), float(m.group(4)), 3600.0 * int(m.group(2)) + 60.0 * int(m.group(3))
