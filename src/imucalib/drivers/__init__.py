"""Real equipment: transports, device dialects, device classes, the station file.

Layers (docs/drivers.md, "Layers"): transports move bytes; pure codecs turn commands
into bytes and replies into values; device classes implement the station protocols of
:mod:`imucalib.station.devices` with the two; simulator servers
(:mod:`imucalib.drivers.simulators`) speak each dialect on 127.0.0.1 with the twin behind them.

Contents
--------
Clock: :class:`MonotonicClock`.
Transports: :class:`Transport`, :class:`TcpTransport`, :class:`SerialTransport`,
:class:`VisaTransport`, :class:`FakeTransport`, :class:`TransportSpec`,
:func:`parse_transport_url`, :func:`open_transport`; Modbus: :class:`RegisterLink`,
:class:`ModbusTcpLink`, :class:`FakeRegisterLink`.
Codecs (modules): :mod:`~imucalib.drivers.acl`, :mod:`~imucalib.drivers.aerosmith`,
:mod:`~imucalib.drivers.watlow_f4t`, :mod:`~imucalib.drivers.espec_p300`,
:mod:`~imucalib.drivers.imu_packet`, :mod:`~imucalib.drivers.imu_csv`.
Devices: :class:`AcutrolTable`, :class:`AerosmithTable`, :class:`AxisLimits` (motion);
:class:`WatlowF4TChamber`, :class:`EspecP300Chamber`; :class:`PacketImu`, :class:`CsvLineImu`;
:class:`DeviceCheck`.
Station: :class:`StationConfig`, :func:`load_station_config`, :func:`parse_station_config`,
:class:`DriverStation`, :func:`load_driver_station`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from imucalib._lazy import lazy_getattr

if TYPE_CHECKING:
    from imucalib.drivers.base import DeviceCheck
    from imucalib.drivers.chambers import EspecP300Chamber, WatlowF4TChamber
    from imucalib.drivers.clock import MonotonicClock
    from imucalib.drivers.fake import FakeRegisterLink, FakeTransport
    from imucalib.drivers.imus import CsvLineImu, PacketImu
    from imucalib.drivers.modbus import ModbusTcpLink, RegisterLink
    from imucalib.drivers.motion import AcutrolTable, AerosmithTable, AxisLimits
    from imucalib.drivers.station import DriverStation, load_driver_station
    from imucalib.drivers.station_config import (
        StationConfig,
        load_station_config,
        parse_station_config,
    )
    from imucalib.drivers.transport import (
        SerialTransport,
        TcpTransport,
        Transport,
        TransportSpec,
        VisaTransport,
        open_transport,
        parse_transport_url,
    )

__all__ = [
    "AcutrolTable",
    "AerosmithTable",
    "AxisLimits",
    "CsvLineImu",
    "DeviceCheck",
    "DriverStation",
    "EspecP300Chamber",
    "FakeRegisterLink",
    "FakeTransport",
    "ModbusTcpLink",
    "MonotonicClock",
    "PacketImu",
    "RegisterLink",
    "SerialTransport",
    "StationConfig",
    "TcpTransport",
    "Transport",
    "TransportSpec",
    "VisaTransport",
    "WatlowF4TChamber",
    "load_driver_station",
    "load_station_config",
    "open_transport",
    "parse_station_config",
    "parse_transport_url",
]

#: Module of each public name, imported on first access (PEP 562): importing one module of this
#: package does not import the others (docs/architecture.md, "Layers").
_LAZY = {
    "AcutrolTable": "imucalib.drivers.motion",
    "AerosmithTable": "imucalib.drivers.motion",
    "AxisLimits": "imucalib.drivers.motion",
    "CsvLineImu": "imucalib.drivers.imus",
    "DeviceCheck": "imucalib.drivers.base",
    "DriverStation": "imucalib.drivers.station",
    "EspecP300Chamber": "imucalib.drivers.chambers",
    "FakeRegisterLink": "imucalib.drivers.fake",
    "FakeTransport": "imucalib.drivers.fake",
    "ModbusTcpLink": "imucalib.drivers.modbus",
    "MonotonicClock": "imucalib.drivers.clock",
    "PacketImu": "imucalib.drivers.imus",
    "RegisterLink": "imucalib.drivers.modbus",
    "SerialTransport": "imucalib.drivers.transport",
    "StationConfig": "imucalib.drivers.station_config",
    "TcpTransport": "imucalib.drivers.transport",
    "Transport": "imucalib.drivers.transport",
    "TransportSpec": "imucalib.drivers.transport",
    "VisaTransport": "imucalib.drivers.transport",
    "WatlowF4TChamber": "imucalib.drivers.chambers",
    "load_driver_station": "imucalib.drivers.station",
    "load_station_config": "imucalib.drivers.station_config",
    "open_transport": "imucalib.drivers.transport",
    "parse_station_config": "imucalib.drivers.station_config",
    "parse_transport_url": "imucalib.drivers.transport",
}

__getattr__ = lazy_getattr(__name__, _LAZY)
