"""Protocol-faithful simulator servers on 127.0.0.1, with the digital twin's physics behind them.

Each server speaks one device dialect over a real loopback socket (port 0: the OS picks; the
server's ``port`` tells which), so a driver tested against it runs the code path it runs on real
equipment. Servers sharing one :class:`~imucalib.sim.rig.TwinRig` share one
:class:`SimTimeBase`: simulated time = (monotonic − start) × speed.

Contents
--------
:class:`SimTimeBase`, :class:`SimServer`
    Shared virtual time; the threaded server base (``drop_connections``, ``close``).
:class:`AclSimServer`, :class:`AerosmithSimServer`
    Motion controllers (table or centrifuge) with fault hooks ``inject_interlock_fault``,
    ``clear_fault_cause``, ``inject_drift``, ``inject_rate_error``, ``offset_feedback``,
    ``clear_faults``.
:class:`F4TSimServer`, :class:`P300SimServer`
    Chambers with ``raise_alarm`` / ``clear_alarms``.
:class:`PacketImuServer`, :class:`CsvImuServer`
    IMU streams with ``set_corruption``, ``set_drop_probability``, ``saturate``.
:class:`LoopbackStation`
    Every server of a rig at once, and the station file that reaches them.
"""

from __future__ import annotations

from imucalib.drivers.simulators._base import SimServer, SimTimeBase
from imucalib.drivers.simulators._motion import InjectedMotionFaults, MotionSimServer
from imucalib.drivers.simulators.acl_server import AclSimServer
from imucalib.drivers.simulators.aerosmith_server import AerosmithSimServer
from imucalib.drivers.simulators.f4t_server import F4TSimServer
from imucalib.drivers.simulators.imu_server import CsvImuServer, InjectedImuFaults, PacketImuServer
from imucalib.drivers.simulators.loopback_station import LoopbackStation
from imucalib.drivers.simulators.p300_server import P300SimServer

__all__ = [
    "AclSimServer",
    "AerosmithSimServer",
    "CsvImuServer",
    "F4TSimServer",
    "InjectedImuFaults",
    "InjectedMotionFaults",
    "LoopbackStation",
    "MotionSimServer",
    "P300SimServer",
    "PacketImuServer",
    "SimServer",
    "SimTimeBase",
]
