"""Bounds of every duration, count, rate and temperature a plan or a twin description may ask for.

Each is a physical or station limit with margin, so that no input can ask for an absurd run: a
file of terabytes, a wait of centuries. Plans (:mod:`imucalib.plan.schema`), the equipment
description (:mod:`imucalib.plan.equipment`) and twin scenarios (:mod:`imucalib.sim.scenario`)
all use these numbers; docs/station.md and docs/twin.md list them.

Contents
--------
The ``MAX_*``/``MIN_*`` constants; :func:`check_record_length`; :func:`format_validation_error`
(a pydantic error rendered one line per offending field).
"""

from __future__ import annotations

from pydantic import ValidationError

__all__ = [
    "MAX_ANGLE_DEG",
    "MAX_CENTRIFUGE_RATE_DPS",
    "MAX_IMUS",
    "MAX_RAMP_DEGC_PER_MIN",
    "MAX_RECORD_S",
    "MAX_REVOLUTIONS",
    "MAX_SAMPLE_RATE_HZ",
    "MAX_SETTLE_S",
    "MAX_STEPS",
    "MAX_TABLE_ACCEL_DPS2",
    "MAX_TABLE_RATE_DPS",
    "MAX_TEMPERATURE_DEGC",
    "MAX_TIME_CONSTANT_S",
    "MAX_TOTAL_S",
    "MAX_WAIT_S",
    "MIN_RAMP_DEGC_PER_MIN",
    "MIN_SAMPLE_RATE_HZ",
    "MIN_TEMPERATURE_DEGC",
    "MIN_TIME_CONSTANT_S",
    "check_record_length",
    "format_validation_error",
]

#: Longest settle (dwell) before a record: an hour; tables settle in seconds. [s]
MAX_SETTLE_S = 3600.0
#: Longest single record or static step: 7 days (an Allan record of a navigation IMU is 1–3). [s]
MAX_RECORD_S = 7 * 86400.0
#: Longest wait or time-out (soak, warm-up, stability): 2 days. [s]
MAX_WAIT_S = 2 * 86400.0
#: Longest plan or scenario, summed least step durations: 14 days. [s]
MAX_TOTAL_S = 14 * 86400.0
#: Longest thermal time constant (chamber air, IMU): a day. [s]
MAX_TIME_CONSTANT_S = 86400.0
#: Shortest thermal time constant: a second (shorter ones overflow the closed-form chamber model
#: and no chamber or IMU housing is that fast). [s]
MIN_TIME_CONSTANT_S = 1.0
#: Most steps in a plan or scenario (the default P1 plan has 110).
MAX_STEPS = 10_000
#: Most IMUs on one fixture.
MAX_IMUS = 64
#: Most whole revolutions one step records.
MAX_REVOLUTIONS = 100_000
#: Fastest rate-table rate (real tables: a few thousand °/s at most). [°/s]
MAX_TABLE_RATE_DPS = 10_000.0
#: Highest rate-table acceleration. [°/s²]
MAX_TABLE_ACCEL_DPS2 = 100_000.0
#: Fastest centrifuge rate (about 1700 rpm). [°/s]
MAX_CENTRIFUGE_RATE_DPS = 10_000.0
#: Largest commanded table or arm angle in magnitude (a turn either way). [°]
MAX_ANGLE_DEG = 360.0
#: Temperature range of thermal chambers (real ones: about −75 … +180 °C). [°C]
MIN_TEMPERATURE_DEGC = -100.0
MAX_TEMPERATURE_DEGC = 200.0
#: Fastest chamber ramp: 10 °C/s (thermal-shock chambers move an item between zones in seconds;
#: the driver tests' fast chamber ramps at 2 °C/s). [°C/min]
MAX_RAMP_DEGC_PER_MIN = 600.0
#: Slowest chamber ramp asked for: 0.01 °C/min (a degree in 100 minutes; real controllers
#: stop at about 0.1). [°C/min]
MIN_RAMP_DEGC_PER_MIN = 0.01
#: IMU output data rates accepted. [Hz]
MIN_SAMPLE_RATE_HZ = 1.0
MAX_SAMPLE_RATE_HZ = 100_000.0


def check_record_length(revolutions: int | None, record_s: float | None, rate_dps: float
                        ) -> None:
    """Refuse a record of whole revolutions longer than :data:`MAX_RECORD_S` (a slow rate).

    Raises
    ------
    ValueError
        Naming the revolutions, the rate and the length (pydantic turns it into a field error).
    """
    if revolutions is not None and rate_dps != 0.0:
        length = revolutions * 360.0 / abs(rate_dps)
        if length > MAX_RECORD_S:
            raise ValueError(f"{revolutions} revolution(s) at {rate_dps:g} °/s take "
                             f"{length:.4g} s; a record may last at most {MAX_RECORD_S:.0f} s "
                             "(7 days)")


def format_validation_error(exc: ValidationError, source: str, what: str = "scenario") -> str:
    """Render a pydantic error naming the field path: one line, or one line per problem."""
    lines = [f"invalid {what} {source}:"]
    errors = exc.errors()
    for err in errors:
        if err["type"] == "too_short" and any(
                len(e["loc"]) > len(err["loc"]) and e["loc"][:len(err["loc"])] == err["loc"]
                for e in errors):
            continue  # pydantic's echo of an invalid item: "at least 1 item … not 0"
        loc = ".".join(str(p) for p in err["loc"])
        got = err.get("input")
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "value_error":  # a model check: its message names the fields
            lines.append(f"  {loc + ': ' if loc else ''}{msg}")
            continue
        got_txt = "" if isinstance(got, dict | list | tuple) else f" (got {got!r})"
        lines.append(f"  {loc or '(top level)'}: {msg}{got_txt}")
    if len(lines) == 2:
        return f"{lines[0]} {lines[1].strip()}"
    return "\n".join(lines)
