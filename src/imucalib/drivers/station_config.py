"""The station file: which devices a real station has, where they are, and their limits (TOML).

Everything is validated before anything connects or moves: unknown sections and keys, unknown
device kinds, malformed transports and ports, limits above the controller's absolute limits,
and chamber ranges outside the chamber's rating are rejected with
:class:`~imucalib.errors.ConfigurationError`, one line per problem naming the field
(``table.axes[0].max_rate_dps: …``).

Example
-------
.. code-block:: toml

    name = "Lab A, station 1"

    [site]
    latitude_deg = 52.38
    heading_deg = 0.0

    [table]
    kind = "acutrol"                       # or "aerosmith"
    transport = "tcp://192.168.53.1:9878"  # visa://TCPIP::…::SOCKET, serial://…?baud=9600
    [[table.axes]]
    name = "pitch"
    max_rate_dps = 500.0
    max_accel_dps2 = 300.0
    controller_max_rate_dps = 1000.0       # the controller's absolute limit (optional)
    controller_max_accel_dps2 = 500.0
    [[table.axes]]
    name = "roll"
    max_rate_dps = 500.0
    max_accel_dps2 = 300.0

    [chamber]
    kind = "watlow-f4t"                    # or "espec-p300"
    transport = "tcp://192.168.1.20:502"
    min_temp_degc = -40.0
    max_temp_degc = 85.0
    rated_min_temp_degc = -70.0            # the chamber's rating (optional)
    rated_max_temp_degc = 180.0

    [[imu]]
    name = "IMU-0001"
    kind = "packet"                        # or "csv"
    transport = "serial:///dev/ttyACM0?baud=921600"
    sample_rate_hz = 1000.0
    gyro_range_dps = 450.0
    accel_range_g = 8.0

Contents
--------
:class:`StationConfig` and its sections (:class:`SiteSection`, :class:`AxisSection`,
:class:`MotionSection`, :class:`CentrifugeSection`, :class:`ChamberSection`,
:class:`ImuSection`); :func:`load_station_config`, :func:`parse_station_config`,
:func:`format_config_errors`.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from imucalib.drivers.transport import TransportSpec, parse_transport_url
from imucalib.errors import ConfigurationError

__all__ = [
    "AxisSection",
    "CentrifugeSection",
    "ChamberSection",
    "ImuSection",
    "MotionSection",
    "SiteSection",
    "StationConfig",
    "format_config_errors",
    "load_station_config",
    "parse_station_config",
]

_SECTIONS = ("name", "site", "table", "centrifuge", "chamber", "imu")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


def _check_transport(value: str) -> str:
    try:
        parse_transport_url(value)
    except ConfigurationError as exc:
        raise ValueError(str(exc)) from None
    return value


class SiteSection(_Model):
    """Where the station stands: latitude and the table's heading (x_t from north)."""

    latitude_deg: float = Field(ge=-90.0, le=90.0)
    heading_deg: float = Field(0.0, ge=-360.0, le=360.0)
    height_m: float = Field(0.0, ge=-500.0, le=9000.0)


class AxisSection(_Model):
    """One axis: name, software limits, the controller's absolute limits, travel."""

    name: str = Field(min_length=1, max_length=32)
    max_rate_dps: float = Field(gt=0.0)
    max_accel_dps2: float = Field(gt=0.0)
    controller_max_rate_dps: float | None = Field(None, gt=0.0)
    controller_max_accel_dps2: float | None = Field(None, gt=0.0)
    travel_deg: tuple[float, float] | None = None
    axis_number: int | None = Field(None, ge=1, le=9)

    @model_validator(mode="after")
    def _within_controller(self) -> AxisSection:
        if self.controller_max_rate_dps is not None and \
                self.max_rate_dps > self.controller_max_rate_dps:
            raise ValueError(f"max_rate_dps {self.max_rate_dps:g} °/s exceeds the controller's "
                             f"absolute limit controller_max_rate_dps "
                             f"{self.controller_max_rate_dps:g} °/s")
        if self.controller_max_accel_dps2 is not None and \
                self.max_accel_dps2 > self.controller_max_accel_dps2:
            raise ValueError(f"max_accel_dps2 {self.max_accel_dps2:g} °/s² exceeds the "
                             f"controller's absolute limit controller_max_accel_dps2 "
                             f"{self.controller_max_accel_dps2:g} °/s²")
        if self.travel_deg is not None and not self.travel_deg[0] < self.travel_deg[1]:
            raise ValueError(f"travel_deg must be [min, max] with min < max; got "
                             f"{list(self.travel_deg)}")
        return self


class MotionSection(_Model):
    """A rate table: controller dialect, transport, axes (outer first)."""

    kind: Literal["acutrol", "aerosmith"]
    transport: str
    name: str = Field("main", min_length=1)
    axes: tuple[AxisSection, ...] = Field(min_length=1, max_length=3)
    model: str = ""
    timeout_s: float = Field(2.0, gt=0.0, le=60.0)
    stop_timeout_s: float = Field(60.0, gt=0.0, le=3600.0)
    axis_prefix: bool | None = None

    _check_transport = field_validator("transport")(_check_transport)

    @model_validator(mode="after")
    def _consistent(self) -> MotionSection:
        names = [a.name for a in self.axes]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"axis names must be unique; repeated: {dup}")
        scheme = parse_transport_url(self.transport).scheme
        allowed = {"acutrol": ("tcp", "visa", "serial"), "aerosmith": ("serial", "tcp")}[self.kind]
        if scheme not in allowed:
            raise ValueError(f"transport {self.transport!r}: {self.kind} controllers are reached "
                             f"over {' or '.join(allowed)}, not {scheme}")
        return self


class CentrifugeSection(MotionSection):
    """A centrifuge: a motion controller with one axis named ``spin``."""

    name: str = Field("main", min_length=1)
    radius_m: float | None = Field(None, gt=0.0, le=20.0)

    @model_validator(mode="after")
    def _one_spin_axis(self) -> CentrifugeSection:
        if [a.name for a in self.axes] != ["spin"]:
            raise ValueError(f"a centrifuge has one axis named 'spin'; got "
                             f"{[a.name for a in self.axes]}")
        return self


class ChamberSection(_Model):
    """A thermal chamber: controller dialect, transport, setpoint range."""

    kind: Literal["watlow-f4t", "espec-p300"]
    transport: str
    name: str = Field("main", min_length=1)
    min_temp_degc: float = Field(ge=-100.0, le=300.0)
    max_temp_degc: float = Field(ge=-100.0, le=300.0)
    rated_min_temp_degc: float | None = Field(None, ge=-200.0, le=500.0)
    rated_max_temp_degc: float | None = Field(None, ge=-200.0, le=500.0)
    device_id: int = Field(1, ge=0, le=247)
    rs485_address: int | None = Field(None, ge=0, le=99)
    n_alarms: int = Field(6, ge=0, le=14)
    timeout_s: float = Field(2.0, gt=0.0, le=60.0)
    model: str = ""

    _check_transport = field_validator("transport")(_check_transport)

    @model_validator(mode="after")
    def _consistent(self) -> ChamberSection:
        if not self.min_temp_degc < self.max_temp_degc:
            raise ValueError(f"min_temp_degc {self.min_temp_degc:g} °C must be below "
                             f"max_temp_degc {self.max_temp_degc:g} °C")
        if self.rated_min_temp_degc is not None and \
                self.min_temp_degc < self.rated_min_temp_degc:
            raise ValueError(f"min_temp_degc {self.min_temp_degc:g} °C is below the chamber's "
                             f"rating rated_min_temp_degc {self.rated_min_temp_degc:g} °C")
        if self.rated_max_temp_degc is not None and \
                self.max_temp_degc > self.rated_max_temp_degc:
            raise ValueError(f"max_temp_degc {self.max_temp_degc:g} °C is above the chamber's "
                             f"rating rated_max_temp_degc {self.rated_max_temp_degc:g} °C")
        scheme = parse_transport_url(self.transport).scheme
        allowed = {"watlow-f4t": ("tcp",), "espec-p300": ("serial", "tcp")}[self.kind]
        if scheme not in allowed:
            raise ValueError(f"transport {self.transport!r}: {self.kind} controllers are reached "
                             f"over {' or '.join(allowed)}, not {scheme}")
        return self


class ImuSection(_Model):
    """One IMU stream: name (the Recording's unit), format, transport, rate, ranges."""

    name: str = Field(min_length=1, max_length=64)
    kind: Literal["packet", "csv"]
    transport: str
    sample_rate_hz: float = Field(gt=0.0, le=100000.0)
    model: str = ""
    maker: str = ""
    gyro_range_dps: float | None = Field(None, gt=0.0)
    accel_range_g: float | None = Field(None, gt=0.0)
    gyro_lsb_dps: float | None = Field(None, gt=0.0)
    accel_lsb_g: float | None = Field(None, gt=0.0)

    _check_transport = field_validator("transport")(_check_transport)

    @model_validator(mode="after")
    def _consistent(self) -> ImuSection:
        if parse_transport_url(self.transport).scheme == "visa":
            raise ValueError(f"transport {self.transport!r}: an IMU stream is read over tcp or "
                             "serial, not visa")
        if (self.gyro_lsb_dps is None) != (self.accel_lsb_g is None):
            raise ValueError("give both gyro_lsb_dps and accel_lsb_g (int32-count frames) or "
                             "neither")
        if self.kind == "csv" and self.gyro_lsb_dps is not None:
            raise ValueError("gyro_lsb_dps/accel_lsb_g apply to kind 'packet' only (CSV headers "
                             "name their units)")
        return self


class StationConfig(_Model):
    """A whole station: site, at most one table, centrifuge and chamber, and the IMUs."""

    name: str = "station"
    site: SiteSection
    table: MotionSection | None = None
    centrifuge: CentrifugeSection | None = None
    chamber: ChamberSection | None = None
    imu: tuple[ImuSection, ...] = Field(min_length=1)

    @model_validator(mode="after")
    def _consistent(self) -> StationConfig:
        names = [i.name for i in self.imu]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"IMU names must be unique; repeated: {dup}")
        return self

    def transports(self) -> dict[str, TransportSpec]:
        """Return the parsed transport of every device, by ``role`` or ``imu[NAME]``."""
        out: dict[str, TransportSpec] = {}
        for role in ("table", "centrifuge", "chamber"):
            section = getattr(self, role)
            if section is not None:
                out[role] = parse_transport_url(section.transport)
        for imu in self.imu:
            out[f"imu[{imu.name}]"] = parse_transport_url(imu.transport)
        return out


def _loc(loc: tuple[int | str, ...]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + part
    return out or "(top level)"


def format_config_errors(exc: ValidationError, source: str) -> str:
    """Render a pydantic error as one line per problem, each naming its field."""
    lines = [f"invalid station file {source}:"]
    for err in exc.errors():
        loc = tuple(p for p in err["loc"] if not (isinstance(p, str) and "[" in p))
        where = _loc(loc)
        got = err.get("input")
        msg = str(err["msg"]).removeprefix("Value error, ")
        kind = err["type"]
        if kind == "extra_forbidden":
            if len(loc) == 1:
                msg = (f"unknown device or section {loc[0]!r}; expected one of "
                       f"{', '.join(_SECTIONS)}")
            else:
                msg = f"unknown key {loc[-1]!r}"
        elif kind == "literal_error" and loc and loc[-1] == "kind":
            expected = str(err.get("ctx", {}).get("expected", ""))
            section = loc[0] if len(loc) > 1 else "device"
            msg = f"unknown {section} kind {got!r}; expected {expected}"
        elif kind == "missing":
            msg = "required but missing"
        elif not isinstance(got, dict | list | tuple) and kind not in ("value_error",):
            msg = f"{msg} (got {got!r})"
        lines.append(f"  {where}: {msg}")
    return "\n".join(lines)


def parse_station_config(text: str, source: str = "<string>") -> StationConfig:
    """Validate station TOML text.

    Raises
    ------
    ConfigurationError
        If the text is not TOML or does not match the schema (one line per problem).
    """
    try:
        data: dict[str, Any] = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigurationError(f"station file {source} is not valid TOML: {exc}") from exc
    try:
        return StationConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigurationError(format_config_errors(exc, source)) from exc


def load_station_config(path: str | Path) -> StationConfig:
    """Load and validate a station file.

    Raises
    ------
    ConfigurationError
        If the file is missing, not UTF-8 TOML, or does not match the schema; the message names
        each offending field, what was expected and what was found.
    """
    p = Path(path)
    if not p.is_file():
        raise ConfigurationError(f"station file {p} does not exist")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigurationError(f"station file {p} is not UTF-8 text: {exc}") from exc
    return parse_station_config(text, str(p))
