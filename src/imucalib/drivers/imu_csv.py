"""IMU samples as CSV lines: a header naming columns and units, then one line per sample.

The generic ASCII output of many IMUs and loggers (docs/drivers.md, "Sources"). Pure: no I/O.

Stream format
-------------
Optional comment lines ``# key=value;key=value`` (identity: model, serial, firmware …), then a
header line naming each column with its unit in brackets, then data lines, all ending in LF
(CR LF accepted)::

    # model=SIM-TACTICAL;serial=IMU-0001
    counter,device_time[s],gyro_x[deg/s],gyro_y[deg/s],gyro_z[deg/s],accel_x[g],accel_y[g],accel_z[g],temperature[degC],status
    0,0.000000,0.0012,-0.0031,0.0040,0.00012,-0.00031,1.00002,25.03,0

Columns (any order; case-insensitive; unknown ones are ignored):
``gyro_x gyro_y gyro_z`` and ``accel_x accel_y accel_z`` (required; any rate and acceleration
unit :func:`imucalib.units.parse_unit` knows), ``counter``, ``device_time`` (a time unit),
``temperature`` (``degC``, ``°C``, ``C``, ``K`` or ``degF``), ``status`` (integer flags, bit 0
saturated) or ``saturated`` (0/1). A line that does not hold one number per column is dropped
and counted (a CSV stream has no checksum; a malformed line is its only integrity check).

Contents
--------
:class:`CsvLayout`, :func:`parse_header`, :func:`format_header`, :func:`parse_lines`,
:func:`format_lines` (simulator), :class:`CsvLineDecoder` (streaming).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from imucalib import units
from imucalib.drivers.imu_packet import FLAG_SATURATED, CounterGaps, DecodedSamples
from imucalib.errors import InvalidInputError, UnitError

__all__ = [
    "CsvLayout",
    "CsvLineDecoder",
    "format_header",
    "format_lines",
    "parse_header",
    "parse_lines",
]

_AXES = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
_ROLES = (*_AXES, "counter", "device_time", "temperature", "status", "saturated")
_COLUMN = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?:\[(.*)\])?\s*$")
#: Temperature units: value_degc = (value + offset) * scale.
_TEMPERATURE_UNITS: dict[str, tuple[float, float]] = {
    "degc": (0.0, 1.0), "°c": (0.0, 1.0), "c": (0.0, 1.0), "celsius": (0.0, 1.0),
    "k": (-273.15, 1.0), "kelvin": (-273.15, 1.0), "degf": (-32.0, 5.0 / 9.0),
    "°f": (-32.0, 5.0 / 9.0), "f": (-32.0, 5.0 / 9.0),
}
_KINDS = {"gyro": "rate", "accel": "acceleration", "device_time": "time"}
_SI_CHECK = {"rate": ("rad/s", "deg/s"), "acceleration": ("m/s^2", "g"), "time": ("s", "ms")}


@dataclass(frozen=True)
class CsvLayout:
    """Where each quantity sits in a line and how it converts to SI.

    Attributes
    ----------
    n_columns : int
        Fields per data line.
    index : dict of str to int
        Column of each known role (``gyro_x`` …, ``counter``, ``device_time``, ``temperature``,
        ``status``, ``saturated``).
    factor : dict of str to float
        SI factor of each dimensional column (temperature uses `temperature_offset_scale`).
    temperature_offset_scale : (float, float)
        °C = (value + offset)·scale.
    columns : tuple of str
        The header's column texts.
    """

    n_columns: int
    index: dict[str, int]
    factor: dict[str, float]
    temperature_offset_scale: tuple[float, float] = (0.0, 1.0)
    columns: tuple[str, ...] = field(default=())


def _unit_factor(role: str, unit: str | None, column: str) -> float:
    kind = next((k for prefix, k in _KINDS.items() if role.startswith(prefix)), None)
    if kind is None:
        return 1.0
    if not unit:
        raise UnitError(f"CSV column {column!r} needs a unit in brackets, e.g. "
                        f"{role}[{_SI_CHECK[kind][1]}]")
    factor = units.parse_unit(unit)
    # a rate unit must not be taken for an acceleration (both parse): check the dimension by
    # comparing with the families' own members
    families = {"rate": {"rad/s", "deg/s", "°/s", "dps", "deg/h", "°/h", "dph", "rpm"},
                "acceleration": {"m/s^2", "m/s²", "mps2", "g", "mg", "ug", "µg"},
                "time": {"s", "ms", "us", "min", "h"}}
    if unit.strip().lower().replace(" ", "") not in families[kind]:
        raise UnitError(f"CSV column {column!r}: unit {unit!r} is not a {kind} unit; expected "
                        f"one of {sorted(families[kind])}")
    return factor


def parse_header(line: str) -> CsvLayout:
    """Parse the header line.

    Raises
    ------
    InvalidInputError
        If a column name is malformed, a role appears twice, or a gyro/accel axis is missing.
    UnitError
        If a unit is unknown or of the wrong kind (a rate unit on an accel column …).
    """
    cols = tuple(c.strip() for c in line.strip().split(","))
    index: dict[str, int] = {}
    factor: dict[str, float] = {}
    temp = (0.0, 1.0)
    for i, col in enumerate(cols):
        m = _COLUMN.match(col)
        if m is None:
            raise InvalidInputError(f"CSV header column {col!r} must be NAME or NAME[unit]")
        role, unit = m.group(1).lower(), m.group(2)
        if role not in _ROLES:
            continue
        if role in index:
            raise InvalidInputError(f"CSV header names {role!r} twice")
        index[role] = i
        if role == "temperature":
            key = (unit or "degC").strip().lower()
            if key not in _TEMPERATURE_UNITS:
                raise UnitError(f"CSV column {col!r}: unknown temperature unit {unit!r}; "
                                f"expected one of {sorted(_TEMPERATURE_UNITS)}")
            temp = _TEMPERATURE_UNITS[key]
        elif role in _AXES or role == "device_time":
            factor[role] = _unit_factor(role, unit, col)
    missing = [r for r in _AXES if r not in index]
    if missing:
        raise InvalidInputError(f"CSV header lacks column(s) {missing}; got {list(cols)}")
    return CsvLayout(len(cols), index, factor, temp, cols)


def format_header(*, gyro_unit: str = "deg/s", accel_unit: str = "g",
                  temperature_unit: str = "degC") -> str:
    """Return the header line our simulator sends (without the line end)."""
    return ",".join(["counter", "device_time[s]", *(f"gyro_{a}[{gyro_unit}]" for a in "xyz"),
                     *(f"accel_{a}[{accel_unit}]" for a in "xyz"),
                     f"temperature[{temperature_unit}]", "status"])


def _to_samples(values: NDArray[np.float64], layout: CsvLayout) -> DecodedSamples:
    n = values.shape[0]
    ix, fac = layout.index, layout.factor
    gyro = np.stack([values[:, ix[f"gyro_{a}"]] * fac[f"gyro_{a}"] for a in "xyz"], axis=1)
    accel = np.stack([values[:, ix[f"accel_{a}"]] * fac[f"accel_{a}"] for a in "xyz"], axis=1)
    counter = (values[:, ix["counter"]].astype(np.int64) if "counter" in ix
               else np.full(n, -1, dtype=np.int64))
    dev_t = (values[:, ix["device_time"]] * fac["device_time"] if "device_time" in ix
             else np.full(n, np.nan))
    off, scale = layout.temperature_offset_scale
    temp = ((values[:, ix["temperature"]] + off) * scale if "temperature" in ix
            else np.full(n, np.nan))
    flags = np.zeros(n, dtype=np.uint16)
    if "status" in ix:
        flags = values[:, ix["status"]].astype(np.int64).astype(np.uint16)
    elif "saturated" in ix:
        flags = np.where(values[:, ix["saturated"]] != 0, FLAG_SATURATED, 0).astype(np.uint16)
    return DecodedSamples(counter, dev_t, gyro, accel, temp, flags)


def parse_lines(lines: list[str], layout: CsvLayout) -> tuple[DecodedSamples, int]:
    """Decode data lines; return the samples and the number of malformed lines dropped."""
    if not lines:
        return DecodedSamples.concatenate([]), 0
    try:
        values = np.array([ln.split(",") for ln in lines], dtype=np.float64)
        if values.ndim != 2 or values.shape[1] != layout.n_columns:
            raise ValueError
        if np.all(np.isfinite(values[:, [layout.index[r] for r in _AXES]])):
            return _to_samples(values, layout), 0
    except ValueError:
        pass
    rows, bad = [], 0
    for ln in lines:  # slow path: find the bad lines
        try:
            row = [float(v) for v in ln.split(",")]
        except ValueError:
            bad += 1
            continue
        if len(row) != layout.n_columns or not all(
                math.isfinite(row[layout.index[r]]) for r in _AXES):
            bad += 1
            continue
        rows.append(row)
    if not rows:
        return DecodedSamples.concatenate([]), bad
    return _to_samples(np.array(rows, dtype=np.float64), layout), bad


def format_lines(samples: DecodedSamples, *, gyro_unit: str = "deg/s", accel_unit: str = "g"
                 ) -> list[str]:
    """Return the data lines of `samples` in the layout of :func:`format_header` (simulator)."""
    g = samples.gyro_rps / units.parse_unit(gyro_unit)
    a = samples.accel_mps2 / units.parse_unit(accel_unit)
    out = []
    for i in range(len(samples)):
        out.append(f"{samples.counter[i]},{samples.device_time_s[i]:.6f},"
                   f"{g[i, 0]:.9g},{g[i, 1]:.9g},{g[i, 2]:.9g},"
                   f"{a[i, 0]:.9g},{a[i, 1]:.9g},{a[i, 2]:.9g},"
                   f"{samples.temperature_degc[i]:.4f},{int(samples.flags[i])}")
    return out


class CsvLineDecoder:
    """Streaming decoder of the CSV stream in the module docstring.

    Attributes
    ----------
    layout : CsvLayout or None
        The header's layout (None until the header arrived).
    info : dict of str to str
        ``key=value`` fields of the comment lines.
    frames_ok, crc_errors, counter_gaps, missing_samples, resyncs : int
        Cumulative counters; ``crc_errors`` counts malformed lines, ``resyncs`` data lines
        dropped before the header arrived.
    """

    def __init__(self, counter_bits: int = 32) -> None:
        self.layout: CsvLayout | None = None
        self.info: dict[str, str] = {}
        self.gaps = CounterGaps(counter_bits)
        self.frames_ok = self.crc_errors = self.resyncs = 0
        self._tail = b""

    @property
    def counter_gaps(self) -> int:
        """Counter jumps other than +1 so far."""
        return self.gaps.counter_gaps

    @property
    def missing_samples(self) -> int:
        """Samples implied missing by those jumps."""
        return self.gaps.missing_samples

    def feed(self, data: bytes) -> DecodedSamples:
        """Decode the complete lines in `data` (an incomplete last line waits for more).

        Raises
        ------
        InvalidInputError, UnitError
            If a header line is malformed (see :func:`parse_header`).
        """
        raw = self._tail + bytes(data)
        *complete, self._tail = raw.split(b"\n")
        parts: list[DecodedSamples] = []
        pending: list[str] = []
        for bline in complete:
            line = bline.decode("utf-8", errors="replace").strip()
            if not line:
                continue
            if line.startswith("#"):
                for item in line[1:].split(";"):
                    key, sep, value = item.partition("=")
                    if sep and key.strip():
                        self.info[key.strip()] = value.strip()
                continue
            first = line.split(",", 1)[0].strip()
            if first and (first[0].isalpha() or first[0] == "_"):
                parts.append(self._flush(pending))
                pending = []
                self.layout = parse_header(line)
                continue
            if self.layout is None:
                self.resyncs += 1
                continue
            pending.append(line)
        parts.append(self._flush(pending))
        return DecodedSamples.concatenate([p for p in parts if len(p)])

    def _flush(self, lines: list[str]) -> DecodedSamples:
        if not lines or self.layout is None:
            return DecodedSamples.concatenate([])
        samples, bad = parse_lines(lines, self.layout)
        self.crc_errors += bad
        self.frames_ok += len(samples)
        if "counter" in self.layout.index:
            self.gaps.update(samples.counter)
        return samples
