"""The Acutronic ACL dialect (ACUTROL3000/3000e, ACT2000 superset): pure formatting and parsing.

No I/O here: functions build command strings in the controller's units (degrees, °/s, °/s²) and
parse reply bytes; :class:`~imucalib.drivers.motion.AcutrolTable` sends them over a transport,
and :class:`~imucalib.drivers.simulators.AclSimServer` parses commands with :func:`parse_message`.

Contents
--------
Commands: :func:`identify`, :func:`lockout`, :func:`interlock_open`, :func:`interlock_reset`,
:func:`interlock_close`, :func:`interlock_query`, :func:`mode`, :func:`mode_query`,
:func:`demand_position`, :func:`demand_rate`, :func:`limit_rate`, :func:`limit_accel`,
:func:`limit_absolute_query`, :func:`read_feedback`, :func:`status_csr`, :func:`error_text`,
:func:`join_commands`.
Replies: :class:`AclReply`, :func:`parse_reply`, :func:`parse_floats`, :func:`encode_reply`.
Simulator side: :class:`AclCommand`, :class:`AclCommandError`, :func:`parse_message`,
:data:`ERROR_TEXTS`, :data:`MODE_LETTERS`.

Wire format
-----------
- Commands (TM-8004-C): a colon-separated, case-insensitive tree with short forms; the axis
  number (1-based) is the first argument; ``;`` chains commands, and a chained command without a
  leading colon is relative to the previous command's branch (``:R:P? 1;P? 2``). A message ends in
  LF. ``ALL`` is allowed for commands, not for queries.
- Replies: every message gets one reply line. Its first 8 characters are a header, then the
  payload, then LF. **[unverified]** The manual says that over non-GPIB interfaces each reply
  carries an error code and a message length ahead of the data, and an open driver drops the
  first 8 characters; the exact layout needs vendor confirmation. Our convention (the simulator
  speaks it, the driver checks it): ``EEEELLLL`` = the error code as 4 decimal digits (0000: no
  error) and the payload length in bytes as 4 decimal digits. The payload is the answers of the
  message's queries joined by ``;`` when the code is 0, else the error text.

Error codes of our simulator (**[unverified]**: real controllers have their own table, readable
with ``:Query:Error? <code>``): see :data:`ERROR_TEXTS`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from imucalib.errors import DeviceError, InvalidInputError

__all__ = [
    "ERROR_TEXTS",
    "HEADER_LENGTH",
    "MODE_LETTERS",
    "TERMINATOR",
    "AclCommand",
    "AclCommandError",
    "AclReply",
    "demand_position",
    "demand_rate",
    "encode_reply",
    "error_text",
    "identify",
    "interlock_close",
    "interlock_open",
    "interlock_query",
    "interlock_reset",
    "join_commands",
    "limit_absolute_query",
    "limit_accel",
    "limit_rate",
    "lockout",
    "mode",
    "mode_query",
    "parse_floats",
    "parse_message",
    "parse_reply",
    "read_feedback",
    "status_csr",
]

TERMINATOR = b"\n"
HEADER_LENGTH = 8

#: Error codes of our ACL simulator (the driver shows the text the controller sends).
ERROR_TEXTS: dict[int, str] = {
    0: "no error",
    100: "command error: unknown or ambiguous header",
    101: "parameter error: missing or invalid argument",
    102: "parameter error: no such axis",
    200: "execution error: remote lockout not taken (send :U:L ON)",
    201: "execution error: interlock open; demand refused",
    202: "execution error: axis not in the mode this demand needs",
    203: "execution error: limit exceeded",
    204: "execution error: interlock fault latched; reset it with :I:R after removing the cause",
    300: "hardware fault",
}

#: ``:Mode? <ax>`` answers and the modes they stand for.
MODE_LETTERS: dict[str, str] = {"P": "position", "R": "rate", "O": "off", "S": "synthesis",
                                "T": "track", "A": "arate", "H": "home"}

Axis = int | Literal["ALL"]
Profile = Literal["P", "R"]


def _axis(axis: Axis, *, allow_all: bool = True) -> str:
    if axis == "ALL":
        if not allow_all:
            raise InvalidInputError("ACL queries take one axis, not ALL")
        return "ALL"
    if isinstance(axis, bool) or not isinstance(axis, int) or axis < 1:
        raise InvalidInputError(f"ACL axis numbers are integers ≥ 1 (or 'ALL'); got {axis!r}")
    return str(axis)


def _num(value: float, name: str) -> str:
    v = float(value)
    if not math.isfinite(v):
        raise InvalidInputError(f"`{name}` must be finite; got {value!r}")
    return f"{v:.6f}"


# --- commands -----------------------------------------------------------------------------------
def identify() -> str:
    """``*IDN?``: the IEEE-488.2 identification query."""
    return "*IDN?"


def lockout(on: bool) -> str:
    """``:U:L ON|OFF``: take (or release) remote control, locking out the GUI."""
    return f":U:L {'ON' if on else 'OFF'}"


def interlock_open(axis: Axis) -> str:
    """``:I:O <ax>``: open the interlock of an axis (servo off)."""
    return f":I:O {_axis(axis)}"


def interlock_reset() -> str:
    """``:I:R``: unfreeze latched fault status on all axes."""
    return ":I:R"


def interlock_close(axis: Axis) -> str:
    """``:I:C <ax>``: close the interlock string and servo the axis."""
    return f":I:C {_axis(axis)}"


def interlock_query(axis: int) -> str:
    """``:I? <ax>``: interlock state, ``Closed``, ``Open`` or ``Fault``."""
    return f":I? {_axis(axis, allow_all=False)}"


def mode(axis: Axis, new_mode: Literal["position", "rate", "off"]) -> str:
    """``:M:P|R|O <ax>``: position, rate, or off (controlled stop, then servo hold)."""
    letter = {"position": "P", "rate": "R", "off": "O"}.get(new_mode)
    if letter is None:
        raise InvalidInputError(f"mode must be 'position', 'rate' or 'off'; got {new_mode!r}")
    return f":M:{letter} {_axis(axis)}"


def mode_query(axis: int) -> str:
    """``:M? <ax>``: the axis mode as one letter (:data:`MODE_LETTERS`)."""
    return f":M? {_axis(axis, allow_all=False)}"


def demand_position(axis: int, angle_deg: float) -> str:
    """``:D:P <ax>,<deg>``: position demand. [°]"""
    return f":D:P {_axis(axis, allow_all=False)},{_num(angle_deg, 'angle_deg')}"


def demand_rate(axis: int, rate_dps: float) -> str:
    """``:D:R <ax>,<deg/s>``: rate demand. [°/s]"""
    return f":D:R {_axis(axis, allow_all=False)},{_num(rate_dps, 'rate_dps')}"


def limit_rate(profile: Profile, axis: int, rate_dps: float) -> str:
    """``:LIM:RATE <P|R>,<ax>,<deg/s>``: rate limit of the position or rate profiler. [°/s]"""
    return f":LIM:RATE {profile},{_axis(axis, allow_all=False)},{_num(rate_dps, 'rate_dps')}"


def limit_accel(profile: Profile, axis: int, accel_dps2: float) -> str:
    """``:LIM:ACC <P|R>,<ax>,<deg/s²>``: acceleration limit of a profiler. [°/s²]"""
    return f":LIM:ACC {profile},{_axis(axis, allow_all=False)},{_num(accel_dps2, 'accel_dps2')}"


def limit_absolute_query(axis: int) -> str:
    """``:LIM:ABS? <ax>``: the factory "limits on limits", answered ``<deg/s>,<deg/s²>``."""
    return f":LIM:ABS? {_axis(axis, allow_all=False)}"


def read_feedback(axes: Sequence[int]) -> str:
    """``:R:P? 1;P? 2;R? 1;R? 2``: positions then rates of `axes`, in one message.

    The answer holds 2·len(`axes`) values: the angles [°] of the axes in order, then their
    rates [°/s], sampled together.
    """
    if not axes:
        raise InvalidInputError("read_feedback needs at least one axis")
    parts = [f":R:P? {_axis(axes[0], allow_all=False)}"]
    parts += [f"P? {_axis(a, allow_all=False)}" for a in axes[1:]]
    parts += [f"R? {_axis(a, allow_all=False)}" for a in axes]
    return ";".join(parts)


def status_csr(register: str = "SI") -> str:
    """``:S:CSR? <reg>``: a condition register (SI, ACP, SUP, RI, ESR, EQ) as an integer."""
    return f":S:CSR? {register}"


def error_text(code: int) -> str:
    """``:Q:E? <code>``: the text of an error or fault code."""
    return f":Q:E? {int(code)}"


def join_commands(commands: Sequence[str]) -> bytes:
    """Join commands into one message: ``;``-chained, LF-terminated, ASCII."""
    if not commands:
        raise InvalidInputError("a message needs at least one command")
    return (";".join(commands)).encode("ascii") + TERMINATOR


# --- replies ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AclReply:
    """One reply: error code (0: none) and payload (answers, or the error text)."""

    code: int
    payload: str

    @property
    def ok(self) -> bool:
        """Whether the controller reported no error."""
        return self.code == 0

    def values(self) -> list[str]:
        """Return the answers of the message's queries, in order (empty without a payload)."""
        return [v.strip() for v in self.payload.split(";")] if self.payload else []


def encode_reply(code: int, payload: str = "") -> bytes:
    """Return the reply line for `code` and `payload` (module docstring: header convention)."""
    data = payload.encode("ascii")
    if not 0 <= code <= 9999 or len(data) > 9999:
        raise InvalidInputError(f"code must be 0–9999 and the payload ≤ 9999 bytes; got {code}, "
                         f"{len(data)} bytes")
    return f"{code:04d}{len(data):04d}".encode("ascii") + data + TERMINATOR


def parse_reply(line: bytes) -> AclReply:
    """Parse one reply line (with or without its LF).

    Raises
    ------
    DeviceError
        If the header is not 8 decimal digits or its length disagrees with the payload.
    """
    text = line.rstrip(b"\r\n")
    header = text[:HEADER_LENGTH]
    if len(header) < HEADER_LENGTH or not header.isdigit():
        raise DeviceError(f"ACL reply {bytes(line)!r}: expected an 8-digit header "
                          "(error code, payload length)")
    code, length = int(header[:4]), int(header[4:])
    payload = text[HEADER_LENGTH:]
    if len(payload) != length:
        raise DeviceError(f"ACL reply {bytes(line)!r}: header announces {length} payload "
                          f"byte(s); got {len(payload)}")
    try:
        return AclReply(code, payload.decode("ascii"))
    except UnicodeDecodeError as exc:
        raise DeviceError(f"ACL reply {bytes(line)!r} is not ASCII") from exc


def parse_floats(reply: AclReply, count: int, what: str) -> list[float]:
    """Return the `count` numeric answers of a reply (``;``- or ``,``-separated).

    Raises
    ------
    DeviceError
        If the reply has another number of answers or one is not a number.
    """
    vals = [v.strip() for answer in reply.values() for v in answer.split(",")]
    if len(vals) != count:
        raise DeviceError(f"ACL {what}: expected {count} value(s); got {len(vals)} "
                          f"({reply.payload!r})")
    try:
        return [float(v) for v in vals]
    except ValueError as exc:
        raise DeviceError(f"ACL {what}: non-numeric answer in {reply.payload!r}") from exc


# --- simulator side: parsing commands -----------------------------------------------------------
_TREE: dict[str, tuple[str, ...]] = {
    "": ("UTILITY", "INTERLOCK", "MODE", "DEMAND", "LIMIT", "READ", "STATUS", "QUERY"),
    "UTILITY": ("LOCKOUT", "REMOTELOCKOUT", "FORMAT"),
    "INTERLOCK": ("RESET", "CLOSE", "OPEN"),
    "MODE": ("POSITION", "RATE", "OFF", "HOME", "SYNTHESIS", "ARATE", "TRACK"),
    "DEMAND": ("POSITION", "RATE", "ACCELERATION", "DELTAPOSITION", "SHORTVECTOR", "OSCILLATOR"),
    "LIMIT": ("RATE", "ACCELERATION", "JERK", "HIGHPOSITION", "LOWPOSITION", "VELOCITYTRIP",
              "ABSOLUTE"),
    "READ": ("POSITION", "RATE", "ACCELERATION", "TIMECLOCK", "FDELAY", "VECTOR"),
    "STATUS": ("CSR", "ESE"),
    "QUERY": ("ERROR", "SYSTEM"),
}


class AclCommandError(Exception):
    """A command the simulator refuses; carries the ACL error code and its text."""

    def __init__(self, code: int, detail: str = "") -> None:
        self.code = code
        base = ERROR_TEXTS.get(code, "error")
        self.text = f"{base}: {detail}" if detail else base
        super().__init__(self.text)


@dataclass(frozen=True)
class AclCommand:
    """One parsed command: canonical path (long names), query flag and arguments."""

    path: tuple[str, ...]
    query: bool
    args: tuple[str, ...]

    @property
    def header(self) -> str:
        """The long-form header, e.g. ``:DEMAND:POSITION`` or ``*IDN``."""
        if self.path and self.path[0].startswith("*"):
            return self.path[0]
        return ":" + ":".join(self.path)


def _resolve(parent: str, token: str) -> str:
    children = _TREE.get(parent, ())
    key = token.upper()
    if key in children:
        return key
    hits = [c for c in children if c.startswith(key)] if key else []
    if len(hits) != 1:
        where = f":{parent}" if parent else "the root"
        kind = "ambiguous" if hits else "unknown"
        raise AclCommandError(100, f"{kind} header {token!r} under {where}")
    return hits[0]


def parse_message(text: str) -> list[AclCommand]:
    """Parse one message (without its LF) into commands, resolving short forms and chaining.

    Raises
    ------
    AclCommandError
        With code 100 for an unknown or ambiguous header.
    """
    commands: list[AclCommand] = []
    branch: tuple[str, ...] = ()
    for raw in text.split(";"):
        part = raw.strip()
        if not part:
            continue
        header, _, rest = part.partition(" ")
        args = tuple(a.strip() for a in rest.split(",")) if rest.strip() else ()
        query = header.endswith("?")
        header = header.rstrip("?")
        if header.startswith("*"):
            commands.append(AclCommand((header.upper(),), query, args))
            continue
        absolute = header.startswith(":")
        tokens = [t for t in header.lstrip(":").split(":")]
        if not tokens or any(not t for t in tokens):
            raise AclCommandError(100, f"malformed header {header!r}")
        path = list(() if absolute else branch)
        for tok in tokens:
            path.append(_resolve(path[-1] if path else "", tok))
        commands.append(AclCommand(tuple(path), query, args))
        branch = tuple(path[:-1])
    return commands
