"""A real station assembled from its station file: device objects behind the ``Station`` protocol.

Contents
--------
:class:`DriverStation`
    Implements :class:`~imucalib.station.devices.Station`: a clock, the table, centrifuge and
    chamber drivers, the IMU sources, the site. Built by :meth:`DriverStation.from_config`
    without connecting anything; :meth:`DriverStation.check` is what
    ``imucalib station check`` runs.
:func:`load_driver_station`
    Station file → :class:`DriverStation` (what ``imucalib run --station FILE`` uses).
:func:`make_motion_driver`, :func:`make_chamber_driver`, :func:`make_imu_source`
    One device from its section.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Protocol

from imucalib import units
from imucalib.drivers.base import DeviceCheck, TransportOpener
from imucalib.drivers.chambers import EspecP300Chamber, WatlowF4TChamber
from imucalib.drivers.clock import MonotonicClock
from imucalib.drivers.imus import CsvLineImu, PacketImu
from imucalib.drivers.modbus import ModbusTcpLink, RegisterLink
from imucalib.drivers.motion import AcutrolTable, AerosmithTable, AxisLimits
from imucalib.drivers.station_config import (
    ChamberSection,
    ImuSection,
    MotionSection,
    StationConfig,
    load_station_config,
)
from imucalib.drivers.transport import Transport, TransportSpec, open_transport, parse_transport_url
from imucalib.errors import CalibrationError
from imucalib.station.devices import (
    ChamberDevice,
    Clock,
    ImuIdentity,
    ImuSource,
    MotionDevice,
)

__all__ = ["DriverDevice", "DriverStation", "load_driver_station", "make_chamber_driver",
           "make_imu_source", "make_motion_driver"]

_LOG = logging.getLogger(__name__)


class DriverDevice(Protocol):
    """What every driver device offers besides its station protocol."""

    name: str

    def check(self) -> DeviceCheck:
        """Connect, identify, read status and one reading, disconnect; moves nothing."""
        ...

    def describe(self) -> dict[str, Any]:
        """Return a JSON-able description."""
        ...


def _opener(spec: TransportSpec, timeout_s: float) -> TransportOpener:
    def open_() -> Transport:
        return open_transport(spec, connect_timeout_s=timeout_s)
    return open_


def make_motion_driver(section: MotionSection, clock: Clock, *, role: str = "table"
                       ) -> AcutrolTable | AerosmithTable:
    """Return the (unconnected) motion driver a table or centrifuge section describes."""
    limits = [AxisLimits(
        max_rate_rps=ax.max_rate_dps * units.DEG, max_accel_rps2=ax.max_accel_dps2 * units.DEG,
        controller_max_rate_rps=(None if ax.controller_max_rate_dps is None
                                 else ax.controller_max_rate_dps * units.DEG),
        controller_max_accel_rps2=(None if ax.controller_max_accel_dps2 is None
                                   else ax.controller_max_accel_dps2 * units.DEG),
        travel_rad=(None if ax.travel_deg is None
                    else (ax.travel_deg[0] * units.DEG, ax.travel_deg[1] * units.DEG)),
    ) for ax in section.axes]
    names = [ax.name for ax in section.axes]
    opener = _opener(parse_transport_url(section.transport), section.timeout_s)
    if section.kind == "acutrol":
        numbers = [ax.axis_number if ax.axis_number is not None else k + 1
                   for k, ax in enumerate(section.axes)]
        return AcutrolTable(section.name, names, opener, clock=clock, limits=limits,
                            axis_numbers=numbers, timeout_s=section.timeout_s,
                            address=section.transport, stop_timeout_s=section.stop_timeout_s,
                            role=role)
    return AerosmithTable(section.name, names, opener, clock=clock, limits=limits,
                          axis_prefix=section.axis_prefix, timeout_s=section.timeout_s,
                          address=section.transport, stop_timeout_s=section.stop_timeout_s,
                          role=role)


def make_chamber_driver(section: ChamberSection, clock: Clock
                        ) -> WatlowF4TChamber | EspecP300Chamber:
    """Return the (unconnected) chamber driver a chamber section describes."""
    spec = parse_transport_url(section.transport)
    if section.kind == "watlow-f4t":
        def open_link() -> RegisterLink:
            return ModbusTcpLink(spec.host, spec.port, device_id=section.device_id,
                                 timeout_s=section.timeout_s)
        return WatlowF4TChamber(section.name, open_link, clock=clock,
                                min_temp_degc=section.min_temp_degc,
                                max_temp_degc=section.max_temp_degc, n_alarms=section.n_alarms,
                                address=section.transport)
    return EspecP300Chamber(section.name, _opener(spec, section.timeout_s), clock=clock,
                            min_temp_degc=section.min_temp_degc,
                            max_temp_degc=section.max_temp_degc,
                            rs485_address=section.rs485_address, timeout_s=section.timeout_s,
                            address=section.transport)


def make_imu_source(section: ImuSection, clock: Clock) -> PacketImu | CsvLineImu:
    """Return the (unconnected) IMU source an ``[[imu]]`` section describes."""
    gyro_lsb_rps = None if section.gyro_lsb_dps is None else section.gyro_lsb_dps * units.DEG
    accel_lsb_mps2 = None if section.accel_lsb_g is None else section.accel_lsb_g * units.G0_MPS2
    # int32-count frames decode to counts × LSB exactly: the Recording stores the counts
    identity = ImuIdentity(
        name=section.name, model=section.model, maker=section.maker,
        sample_rate_hz=section.sample_rate_hz,
        gyro_range_rps=None if section.gyro_range_dps is None
        else section.gyro_range_dps * units.DEG,
        accel_range_mps2=None if section.accel_range_g is None
        else section.accel_range_g * units.G0_MPS2,
        gyro_lsb_rps=gyro_lsb_rps, accel_lsb_mps2=accel_lsb_mps2)
    opener = _opener(parse_transport_url(section.transport), 3.0)
    if section.kind == "packet":
        return PacketImu(identity, opener, clock=clock, gyro_scale_rps=gyro_lsb_rps,
                         accel_scale_mps2=accel_lsb_mps2, address=section.transport)
    return CsvLineImu(identity, opener, clock=clock, address=section.transport)


class DriverStation:
    """A real station: implements :class:`~imucalib.station.devices.Station`.

    Parameters
    ----------
    config : StationConfig
        The validated station file.
    clock : Clock
        The station clock (devices stamp with it).
    table, centrifuge : MotionDevice or None
    chamber : ChamberDevice or None
    imus : list of ImuSource
    drivers : list of DriverDevice
        The same device objects, for checks and descriptions.
    """

    def __init__(self, config: StationConfig, *, clock: Clock, table: MotionDevice | None,
                 centrifuge: MotionDevice | None, chamber: ChamberDevice | None,
                 imus: list[ImuSource], drivers: list[DriverDevice]) -> None:
        self.config = config
        self.name = config.name
        self.clock = clock
        self.table = table
        self.centrifuge = centrifuge
        self.chamber = chamber
        self.imus = imus
        self.drivers = drivers
        self.latitude_deg = config.site.latitude_deg
        self.heading_deg = config.site.heading_deg

    @classmethod
    def from_config(cls, config: StationConfig, clock: Clock | None = None) -> DriverStation:
        """Assemble the device objects of `config` (nothing connects yet).

        Parameters
        ----------
        config : StationConfig
            From :func:`~imucalib.drivers.station_config.load_station_config`.
        clock : Clock, optional
            The station clock; a new :class:`~imucalib.drivers.clock.MonotonicClock` if None.
        """
        clk: Clock = clock if clock is not None else MonotonicClock()
        drivers: list[DriverDevice] = []
        table = centrifuge = None
        if config.table is not None:
            table = make_motion_driver(config.table, clk, role="table")
            drivers.append(table)
        if config.centrifuge is not None:
            centrifuge = make_motion_driver(config.centrifuge, clk, role="centrifuge")
            drivers.append(centrifuge)
        chamber = None
        if config.chamber is not None:
            chamber = make_chamber_driver(config.chamber, clk)
            drivers.append(chamber)
        imus: list[ImuSource] = []
        for section in config.imu:
            imu = make_imu_source(section, clk)
            imus.append(imu)
            drivers.append(imu)
        return cls(config, clock=clk, table=table, centrifuge=centrifuge, chamber=chamber,
                   imus=imus, drivers=drivers)

    def describe(self) -> dict[str, Any]:
        """Return a JSON-able description: name, site, devices, and the station file."""
        return {"kind": "equipment", "name": self.name,
                "site": self.config.site.model_dump(),
                "devices": [d.describe() for d in self.drivers],
                "station_config": self.config.model_dump(mode="json")}

    def connect(self) -> None:
        """Connect every device (IMUs first, motion last); on a failure, stop and disconnect all.

        Raises
        ------
        CalibrationError
            The first failure (after everything was brought to a safe state).
        """
        order: list[Any] = [*self.imus, self.chamber, self.centrifuge, self.table]
        try:
            for dev in order:
                if dev is not None:
                    dev.connect()
        except CalibrationError:
            self.safe_stop()
            self.disconnect()
            raise

    def safe_stop(self) -> None:
        """Stop and switch off the motion devices, chamber to standby; never raises."""
        for dev in (self.table, self.centrifuge):
            if dev is not None:
                dev.safe_stop()
        if self.chamber is not None:
            self.chamber.standby()

    def disconnect(self) -> None:
        """Disconnect every device, logging (not raising) failures."""
        for dev in [self.table, self.centrifuge, self.chamber, *self.imus]:
            if dev is None:
                continue
            try:
                dev.disconnect()
            except Exception as exc:  # disconnecting must go on
                _LOG.warning("%s: disconnect failed: %s", dev.name, exc)

    def check(self) -> list[DeviceCheck | tuple[str, CalibrationError]]:
        """Check every device in turn; a device that fails gives (name, error) instead."""
        results: list[DeviceCheck | tuple[str, CalibrationError]] = []
        for dev in self.drivers:
            try:
                results.append(dev.check())
            except CalibrationError as exc:
                results.append((dev.name, exc))
        return results


def load_driver_station(path: str | Path, *, start_time_s: float = 0.0,
                        clock: Clock | None = None) -> DriverStation:
    """Load a station file and assemble its (unconnected) devices.

    Parameters
    ----------
    path : str or Path
        The station TOML file.
    start_time_s : float
        Station time now, on a new :class:`~imucalib.drivers.clock.MonotonicClock` (a resumed
        run continues after its recording's last sample). Ignored when `clock` is given. [s]
    clock : Clock, optional
        Use this clock instead (tests: a :class:`~imucalib.drivers.simulators.SimTimeBase`).

    Raises
    ------
    ConfigurationError
        If the file is missing or invalid (nothing is connected or moved).
    """
    config = load_station_config(path)
    return DriverStation.from_config(
        config, clock if clock is not None else MonotonicClock(start_s=start_time_s))
