"""The Ideal Aerosmith ASCII dialect: pure formatting and parsing.

No public programming manual of the AERO 4000 / 1280-series controllers was found; this dialect
follows open code for single-axis Ideal Aerosmith tables (docs/drivers.md, "Sources") and is
**[unverified]** on real hardware, including everything marked so below.

Contents
--------
:func:`format_command`, :func:`expects_reply`, :func:`parse_response`, :func:`parse_number`,
:class:`AerosmithStatus`, :func:`parse_status`, :func:`encode_status` (simulator),
:func:`parse_command_line` (simulator), :data:`COMMANDS`, :data:`PROMPT`.

Wire format
-----------
- RS-232 at 9600 baud 8N1; a command is three letters, an optional number glued to it, then
  CR LF: ``MOV90.000000``, ``JOG-50.000000``, ``STO``, ``PPO``.
- Every command except ``JOG`` and ``SGO`` is answered by a response line and then a prompt line
  (**[unverified]**: we use ``>``); ``JOG``/``SGO`` are not answered.
- **[unverified]** On a controller with several axes, a command is prefixed with the axis number
  (``2MOV45.000000``); a single-axis controller takes it without a prefix.
- Responses (**[unverified]** conventions of our simulator): ``OK`` for a command, the number for
  ``PPO`` [°] and ``PVE`` [°/s], the identification for ``VER``, and
  ``<MODE>,<SERVO>,<FAULT>`` for ``STA`` with MODE in OFF/POS/JOG/STOP, SERVO 0/1 and FAULT
  ``NONE`` or the fault text; a refused command answers ``ERROR <text>``.
- ``SRV1`` switches the servo on (and clears a latched fault whose cause is gone), ``SRV0`` off;
  ``VEL``/``ACL`` set the move velocity [°/s] and acceleration [°/s²] limits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from imucalib.errors import DeviceError, InvalidInputError

__all__ = [
    "COMMANDS",
    "PROMPT",
    "TERMINATOR",
    "AerosmithStatus",
    "encode_status",
    "expects_reply",
    "format_command",
    "parse_command_line",
    "parse_number",
    "parse_response",
    "parse_status",
]

TERMINATOR = b"\r\n"
#: The prompt line that follows every response (**[unverified]**).
PROMPT = ">"
#: Commands the driver and the simulator know (the open-code dialect of docs/drivers.md,
#: "Sources", plus ``VER``, [unverified]).
COMMANDS = ("VER", "SRV", "VEL", "ACL", "MOV", "RMO", "JOG", "STO", "HOM", "PPO", "PVE", "STA",
            "SGO", "ZER")
_NO_REPLY = frozenset({"JOG", "SGO"})

AxisModeText = Literal["OFF", "POS", "JOG", "STOP"]


def expects_reply(command: str) -> bool:
    """Whether `command` (three letters) is answered by a response and a prompt."""
    return command.upper() not in _NO_REPLY


def format_command(command: str, value: float | int | None = None, *,
                   axis: int | None = None) -> bytes:
    """Return the bytes of one command.

    Parameters
    ----------
    command : str
        Three-letter mnemonic (:data:`COMMANDS`).
    value : float or int, optional
        Argument glued to the mnemonic (integers as such, floats with 6 decimals).
    axis : int, optional
        Axis number prefix for multi-axis controllers (None: no prefix).

    Raises
    ------
    InvalidInputError
        For an unknown mnemonic, a non-finite value or an axis outside 1–9.
    """
    cmd = command.upper()
    if cmd not in COMMANDS:
        raise InvalidInputError(f"unknown Aerosmith command {command!r}; expected one of "
                                f"{', '.join(COMMANDS)}")
    text = cmd
    if value is not None:
        if isinstance(value, int) and not isinstance(value, bool):
            text += str(value)
        else:
            v = float(value)
            if not math.isfinite(v):
                raise InvalidInputError(f"{cmd}: value must be finite; got {value!r}")
            text += f"{v:.6f}"
    if axis is not None:
        if not 1 <= int(axis) <= 9:
            raise InvalidInputError(f"Aerosmith axis numbers are 1–9; got {axis!r}")
        text = f"{int(axis)}{text}"
    return text.encode("ascii") + TERMINATOR


def parse_response(line: bytes, command: str) -> str:
    """Return the text of a response line, raising on ``ERROR``.

    Raises
    ------
    DeviceError
        If the controller answered ``ERROR …`` or the line is not ASCII.
    """
    try:
        text = line.decode("ascii").strip()
    except UnicodeDecodeError as exc:
        raise DeviceError(f"Aerosmith {command}: reply {line!r} is not ASCII") from exc
    if text.upper().startswith("ERROR"):
        raise DeviceError(f"Aerosmith {command}: the controller refused it: {text[5:].strip()}")
    return text


def parse_number(text: str, command: str) -> float:
    """Return the number a query answered.

    Raises
    ------
    DeviceError
        If `text` is not a finite number.
    """
    try:
        value = float(text)
    except ValueError:
        raise DeviceError(f"Aerosmith {command}: expected a number; got {text!r}") from None
    if not math.isfinite(value):
        raise DeviceError(f"Aerosmith {command}: expected a finite number; got {text!r}")
    return value


@dataclass(frozen=True)
class AerosmithStatus:
    """An axis' ``STA`` answer: mode, servo state and latched fault (None when healthy)."""

    mode: AxisModeText
    servo_on: bool
    fault: str | None


def parse_status(text: str) -> AerosmithStatus:
    """Parse a ``STA`` answer ``<MODE>,<SERVO>,<FAULT>``.

    Raises
    ------
    DeviceError
        If the answer does not have that form.
    """
    parts = [p.strip() for p in text.split(",", 2)]
    if len(parts) != 3 or parts[0] not in ("OFF", "POS", "JOG", "STOP") \
            or parts[1] not in ("0", "1"):
        raise DeviceError(f"Aerosmith STA: expected <OFF|POS|JOG|STOP>,<0|1>,<fault>; "
                          f"got {text!r}")
    fault = None if parts[2].upper() in ("", "NONE") else parts[2]
    mode: AxisModeText = parts[0]  # type: ignore[assignment]
    return AerosmithStatus(mode, parts[1] == "1", fault)


def encode_status(status: AerosmithStatus) -> str:
    """Return the ``STA`` answer of `status` (simulator side)."""
    fault = status.fault.replace(",", ";") if status.fault else "NONE"
    return f"{status.mode},{int(status.servo_on)},{fault}"


def parse_command_line(line: str) -> tuple[int | None, str, str]:
    """Split a received command line into (axis prefix or None, mnemonic, argument text).

    Raises
    ------
    InvalidInputError
        If the line does not start with an optional digit and a known mnemonic.
    """
    text = line.strip()
    axis: int | None = None
    if text[:1].isdigit():
        axis, text = int(text[0]), text[1:]
    cmd, arg = text[:3].upper(), text[3:].strip()
    if cmd not in COMMANDS:
        raise InvalidInputError(f"unknown command {line.strip()!r}")
    return axis, cmd, arg
