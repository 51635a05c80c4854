"""A look at what the runner reads from a station, for the live view; it changes nothing.

:func:`tap_station` wraps a :class:`~imucalib.station.devices.Station` so that every block the
runner polls or reads passes through :class:`SignalTap` on its way back to the runner: the tap
keeps the latest table and centrifuge feedback, chamber readings, device faults and each IMU's
block means (the decimation of the live view: one value per block, the runner's tick), and
notes when the runner stops a device safely (``safe_stop``, ``standby``). For the window means
of the live view it also bins each IMU's samples by receive time
(:class:`~imucalib.web.window_stats.BinnedMoments`) and follows since when each motion axis
holds its commanded rate (:class:`~imucalib.web.rate_hold.RateHold`, from the runner's
``set_rate`` and the feedback), both in bounded memory; a failure of either is dropped, never
passed to the runner. Every other attribute is the station's own (the twin's ``remount``,
``swap_units``, ``truth`` …), so the runner runs exactly as on the bare station
(docs/web-runs.md, "Live signals").
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import Any, cast

import numpy as np

from imucalib import units
from imucalib.station.devices import (
    ChamberDevice,
    ChamberReadings,
    ChamberStatus,
    Clock,
    ImuBlock,
    ImuSource,
    MotionDevice,
    MotionFeedback,
    MotionStatus,
    Station,
)
from imucalib.web.rate_hold import RateHold
from imucalib.web.window_stats import BinnedMoments

__all__ = ["SignalTap", "TappedStation", "tap_station"]


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _vector(values: Any) -> list[float | None]:
    return [_finite(float(v)) for v in np.asarray(values, dtype=float).ravel()]


class SignalTap:
    """The latest values a run's station delivered, and the safe stops it was given.

    Parameters
    ----------
    on_safe_stop : callable, optional
        Called with the device (``"table"``, ``"centrifuge"``, ``"chamber"``) and the wall time
        (:func:`time.time`) when the runner stops it safely.
    """

    def __init__(self, on_safe_stop: Callable[[str, float], None] | None = None) -> None:
        self.table: dict[str, Any] = {}
        self.centrifuge: dict[str, Any] = {}
        self.chamber: dict[str, Any] = {}
        self.imus: dict[str, dict[str, Any]] = {}
        self.faults: dict[str, str | None] = {}
        self.moments: dict[str, BinnedMoments] = {}
        self.rate_holds: dict[str, RateHold] = {}
        self.rate_tolerance_rps = math.inf
        self.on_safe_stop = on_safe_stop
        #: The devices a safe stop stops (set by :class:`TappedStation`).
        self.stoppable: frozenset[str] = frozenset()

    def set_rate_tolerance(self, tolerance_rps: float) -> None:
        """Set how far a motion axis's rate may be off its command and still hold it. [rad/s]"""
        self.rate_tolerance_rps = tolerance_rps
        for hold in self.rate_holds.values():
            hold.tolerance_rps = tolerance_rps

    def rate_hold(self, role: str) -> RateHold:
        """Return the :class:`~imucalib.web.rate_hold.RateHold` of a motion device."""
        hold = self.rate_holds.get(role)
        if hold is None:
            hold = self.rate_holds[role] = RateHold(self.rate_tolerance_rps)
        return hold

    def command_rate(self, role: str, axis: int, rate_rps: float) -> None:
        """Note that the runner commanded a rate of a motion device's axis. [rad/s]"""
        self.rate_hold(role).command(axis, rate_rps)

    def motion(self, role: str, fb: MotionFeedback) -> None:
        """Keep the last row of a motion device's feedback (its time too, station clock)."""
        if len(fb):
            target = self.table if role == "table" else self.centrifuge
            target["angle_deg"] = _vector(np.degrees(fb.angle_rad[-1]))
            target["rate_dps"] = _vector(np.degrees(fb.rate_rps[-1]))
            target["time_s"] = _finite(float(fb.time_s[-1]))
            try:  # the live view's bookkeeping must never stop the runner's poll
                self.rate_hold(role).feedback(fb.time_s, fb.rate_rps)
            except Exception:
                self.rate_holds.pop(role, None)

    def chamber_rows(self, rows: ChamberReadings) -> None:
        """Keep the last chamber reading and set point."""
        if len(rows):
            self.chamber["air_degc"] = _finite(float(rows.temperature_degc[-1]))
            self.chamber["setpoint_degc"] = _finite(float(rows.setpoint_degc[-1]))

    def imu(self, name: str, block: ImuBlock) -> None:
        """Keep the means of an IMU block: rate [°/s], specific force [g], temperature [°C]."""
        if len(block):
            self.imus[name] = {
                "gyro_dps": _vector(np.degrees(block.gyro_rps.mean(axis=0))),
                "accel_g": _vector(block.accel_mps2.mean(axis=0) / units.G0_MPS2),
                "temperature_degc": _finite(float(block.temperature_degc.mean())),
                "samples": len(block)}
            try:  # the live view's statistics must never stop the runner's read
                self.moments.setdefault(name, BinnedMoments()).add(
                    block.time_s, block.gyro_rps, block.accel_mps2)
            except Exception:
                self.moments.pop(name, None)

    def forget_before(self, time_s: float) -> None:
        """Drop the binned samples received before `time_s` (a step's data once used). [s]"""
        for moments in self.moments.values():
            moments.drop_before(time_s)

    def fault(self, device: str, fault: str | None) -> None:
        """Keep a device's latest fault or alarm (None: none)."""
        self.faults[device] = fault

    def stopped(self, device: str) -> None:
        """Note that the runner stopped `device` safely."""
        if self.on_safe_stop is not None:
            self.on_safe_stop(device, time.time())


class _Proxy:
    """Every attribute is the wrapped device's, save those the subclass defines."""

    def __init__(self, inner: Any, tap: SignalTap, role: str) -> None:
        self._inner, self._tap, self._role = inner, tap, role

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)


class _Motion(_Proxy):
    def set_rate(self, axis: int, rate_rps: float) -> None:
        self._inner.set_rate(axis, rate_rps)
        try:
            self._tap.command_rate(self._role, axis, rate_rps)
        except Exception:
            self._tap.rate_holds.pop(self._role, None)

    def poll(self) -> MotionFeedback:
        fb = cast(MotionFeedback, self._inner.poll())
        self._tap.motion(self._role, fb)
        return fb

    def status(self) -> MotionStatus:
        st = cast(MotionStatus, self._inner.status())
        self._tap.fault(self._role, st.fault)
        return st

    def safe_stop(self) -> None:
        try:
            self._inner.safe_stop()
        finally:
            self._tap.stopped(self._role)


class _Chamber(_Proxy):
    def poll(self) -> ChamberReadings:
        rows = cast(ChamberReadings, self._inner.poll())
        self._tap.chamber_rows(rows)
        return rows

    def status(self) -> ChamberStatus:
        st = cast(ChamberStatus, self._inner.status())
        self._tap.fault("chamber", st.alarm)
        return st

    def standby(self) -> None:
        try:
            self._inner.standby()
        finally:
            self._tap.stopped("chamber")


class _Imu(_Proxy):
    def read(self) -> ImuBlock:
        block = cast(ImuBlock, self._inner.read())
        self._tap.imu(self._role, block)
        return block


class TappedStation:
    """A station whose devices report to a :class:`SignalTap` (see :func:`tap_station`)."""

    def __init__(self, station: Station, tap: SignalTap) -> None:
        self._station = station
        self.tap = tap
        self._table = (cast(MotionDevice, _Motion(station.table, tap, "table"))
                       if station.table is not None else None)
        self._centrifuge = (cast(MotionDevice, _Motion(station.centrifuge, tap, "centrifuge"))
                            if station.centrifuge is not None else None)
        self._chamber = (cast(ChamberDevice, _Chamber(station.chamber, tap, "chamber"))
                         if station.chamber is not None else None)
        self._imus = [cast(ImuSource, _Imu(src, tap, src.name)) for src in station.imus]
        tap.stoppable = frozenset(role for role, dev in (("table", self._table),
                                                         ("centrifuge", self._centrifuge),
                                                         ("chamber", self._chamber))
                                  if dev is not None)

    @property
    def clock(self) -> Clock:
        """The station's clock."""
        return self._station.clock

    @property
    def table(self) -> MotionDevice | None:
        """The table, tapped."""
        return self._table

    @property
    def centrifuge(self) -> MotionDevice | None:
        """The centrifuge, tapped."""
        return self._centrifuge

    @property
    def chamber(self) -> ChamberDevice | None:
        """The chamber, tapped."""
        return self._chamber

    @property
    def imus(self) -> Sequence[ImuSource]:
        """The IMU sources, tapped."""
        return self._imus

    @property
    def latitude_deg(self) -> float:
        """The station's latitude. [°]"""
        return self._station.latitude_deg

    @property
    def heading_deg(self) -> float:
        """The station's heading. [°]"""
        return self._station.heading_deg

    def describe(self) -> dict[str, Any]:
        """Return the station's own description."""
        return self._station.describe()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._station, name)


def tap_station(station: Station, tap: SignalTap) -> Station:
    """Return `station` with its devices reporting to `tap` (module docstring)."""
    return cast(Station, TappedStation(station, tap))
