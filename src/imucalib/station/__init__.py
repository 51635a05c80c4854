"""The station runtime: device protocols, the simulated station, the plan runner.

Contents
--------
:mod:`imucalib.station.devices`
    Protocols the runner drives (:class:`~imucalib.station.devices.MotionDevice`,
    :class:`~imucalib.station.devices.ChamberDevice`, :class:`~imucalib.station.devices.ImuSource`,
    :class:`~imucalib.station.devices.Clock`, :class:`~imucalib.station.devices.Station`) and the
    data blocks they return.
"""

from __future__ import annotations

__all__: list[str] = []
