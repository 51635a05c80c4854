"""The Watlow F4T register map (Modbus, Data Map 1) and pure helpers around it.

Values are IEEE-754 float32 across two registers, low word first (the F4T default), or 16-bit
enumerations (Watlow's numeric value codes). Addresses are the 0-based protocol addresses that go
into the Modbus PDU, as ChamberConnectLibrary uses them.

Sources (docs/drivers.md, "Sources"): the setpoint (2782) and the actual chamber temperature
(27586) are from the F4T manuals **[manual]**; the working setpoint (2810), control mode (2730),
setpoint range (2774/2776), alarm states (1356 + 100·i), part number (16) and display units
(6730) are from ChamberConnectLibrary's ``watlowf4t.py`` **[code]**. The ramp registers
2794/2796/2798 are named in the F4T manuals; their meaning here (ramp action, ramp scale, ramp rate
per scale unit) and the alarm-state codes that mean "active" are **[unverified]**.

Contents
--------
Register constants (``SETPOINT`` …), enumeration codes (``MODE_AUTO`` …),
:func:`alarm_register`, :func:`alarm_text`, :func:`setpoint_writes`, :func:`to_celsius`,
:func:`from_celsius`, :func:`encode_string` (simulator).
"""

from __future__ import annotations

import math

from imucalib.drivers.modbus import floats_to_registers
from imucalib.errors import DeviceError, InvalidInputError

__all__ = [
    "ALARM_ACTIVE_TEXTS",
    "ALARM_INACTIVE",
    "ALARM_STATE_BASE",
    "ALARM_STRIDE",
    "CONTROL_MODE",
    "DISPLAY_UNITS",
    "MODE_AUTO",
    "MODE_MANUAL",
    "MODE_OFF",
    "PART_NUMBER",
    "PART_NUMBER_LENGTH",
    "PROCESS_VALUE",
    "RAMP_ACTION",
    "RAMP_OFF",
    "RAMP_RATE",
    "RAMP_SCALE",
    "RAMP_SETPOINT",
    "RANGE_HIGH",
    "RANGE_LOW",
    "SCALE_HOURS",
    "SCALE_MINUTES",
    "SETPOINT",
    "UNITS_C",
    "UNITS_F",
    "WORKING_SETPOINT",
    "alarm_register",
    "alarm_text",
    "encode_string",
    "from_celsius",
    "setpoint_writes",
    "to_celsius",
]

# --- registers (float32 = 2 registers) ----------------------------------------------------------
SETPOINT = 2782            #: loop 1 closed-loop setpoint, float [manual]
WORKING_SETPOINT = 2810    #: loop 1 current (ramping) setpoint, float [code]
PROCESS_VALUE = 27586      #: actual chamber temperature, float [manual]
CONTROL_MODE = 2730        #: loop 1 control mode, enum MODE_* [code]
RANGE_LOW = 2774           #: loop 1 setpoint low limit, float [code]
RANGE_HIGH = 2776          #: loop 1 setpoint high limit, float [code]
RAMP_ACTION = 2794         #: enum RAMP_* [unverified]
RAMP_SCALE = 2796          #: enum SCALE_* [unverified]
RAMP_RATE = 2798           #: ramp rate per scale unit, float [unverified]
ALARM_STATE_BASE = 1356    #: alarm i (0-based) state at 1356 + 100·i, enum [code]
ALARM_STRIDE = 100
PART_NUMBER = 16           #: 15 registers, one ASCII character each [code]
PART_NUMBER_LENGTH = 15
DISPLAY_UNITS = 6730       #: enum UNITS_* [code]

# --- enumeration codes (Watlow value codes) -----------------------------------------------------
MODE_AUTO, MODE_MANUAL, MODE_OFF = 10, 54, 62
RAMP_OFF, RAMP_SETPOINT = 62, 85
SCALE_HOURS, SCALE_MINUTES = 39, 57
UNITS_C, UNITS_F = 15, 30
#: Alarm states that mean "no alarm": startup (88), none (61), 12 [code].
ALARM_INACTIVE = frozenset({12, 61, 88})
#: Texts of the active alarm states our simulator raises [unverified].
ALARM_ACTIVE_TEXTS = {37: "high", 53: "low", 28: "error", 24: "deviation"}


def alarm_register(index: int) -> int:
    """Return the state register of alarm `index` (0-based)."""
    if index < 0:
        raise InvalidInputError(f"alarm index must be ≥ 0; got {index}")
    return ALARM_STATE_BASE + ALARM_STRIDE * index


def alarm_text(index: int, state: int) -> str | None:
    """Return the text of alarm `index` (0-based) in `state`, or None when it is inactive."""
    if state in ALARM_INACTIVE:
        return None
    return f"alarm {index + 1}: {ALARM_ACTIVE_TEXTS.get(state, f'state {state}')}"


def to_celsius(value: float, units: int) -> float:
    """Convert a temperature the controller shows in `units` (UNITS_C/UNITS_F) to °C.

    Raises
    ------
    DeviceError
        For an unknown units code.
    """
    if units == UNITS_C:
        return value
    if units == UNITS_F:
        return (value - 32.0) / 1.8
    raise DeviceError(f"Watlow F4T display units code {units}: expected {UNITS_C} (°C) or "
                      f"{UNITS_F} (°F)")


def from_celsius(value_degc: float, units: int) -> float:
    """Convert °C to the controller's `units` (UNITS_C/UNITS_F)."""
    if units == UNITS_C:
        return value_degc
    if units == UNITS_F:
        return value_degc * 1.8 + 32.0
    raise DeviceError(f"Watlow F4T display units code {units}: expected {UNITS_C} (°C) or "
                      f"{UNITS_F} (°F)")


def setpoint_writes(temperature: float, ramp_per_s: float | None) -> list[tuple[int, list[int]]]:
    """Return the register writes that run loop 1 at a setpoint, in order.

    Parameters
    ----------
    temperature : float
        Setpoint in the controller's units.
    ramp_per_s : float or None
        Ramp rate in the controller's units per second (None: no ramp, as fast as it goes).

    Returns
    -------
    list of (address, registers)
        Ramp action (and scale and rate, per minute), the setpoint, then the control mode auto.
    """
    t = float(temperature)
    if not math.isfinite(t):
        raise InvalidInputError(f"`temperature` must be finite; got {temperature!r}")
    writes: list[tuple[int, list[int]]] = []
    if ramp_per_s is None:
        writes.append((RAMP_ACTION, [RAMP_OFF]))
    else:
        r = float(ramp_per_s)
        if not math.isfinite(r) or r <= 0.0:
            raise InvalidInputError(f"`ramp_per_s` must be > 0; got {ramp_per_s!r}")
        writes += [(RAMP_SCALE, [SCALE_MINUTES]), (RAMP_RATE, floats_to_registers([r * 60.0])),
                   (RAMP_ACTION, [RAMP_SETPOINT])]
    writes += [(SETPOINT, floats_to_registers([t])), (CONTROL_MODE, [MODE_AUTO])]
    return writes


def encode_string(text: str, length: int) -> list[int]:
    """Return `text` as `length` registers, one ASCII character each, zero-padded (simulator)."""
    data = text.encode("ascii")[:length]
    return list(data) + [0] * (length - len(data))
