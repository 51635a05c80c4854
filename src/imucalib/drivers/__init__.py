"""Real equipment: transports, device dialects, device classes, the station file.

Layers (``reference/devices.md``; STYLE.md §8): transports move bytes; pure codecs turn commands
into bytes and replies into values; device classes implement the station protocols of
:mod:`imucalib.station.devices` with the two.

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
"""

from __future__ import annotations

from imucalib.drivers.clock import MonotonicClock
from imucalib.drivers.fake import FakeRegisterLink, FakeTransport
from imucalib.drivers.modbus import ModbusTcpLink, RegisterLink
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
    "FakeRegisterLink",
    "FakeTransport",
    "ModbusTcpLink",
    "MonotonicClock",
    "RegisterLink",
    "SerialTransport",
    "TcpTransport",
    "Transport",
    "TransportSpec",
    "VisaTransport",
    "open_transport",
    "parse_transport_url",
]
