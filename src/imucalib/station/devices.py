"""What the station runner needs from each device: protocols and the data they return.

A station is a clock, at most one rate table, at most one centrifuge, at most one thermal chamber
and one or more IMU sources. The runner (:mod:`imucalib.station.runner`) drives them only through
these protocols, so the digital twin (:mod:`imucalib.station.sim`) and real equipment
(:mod:`imucalib.drivers`) are interchangeable. Devices never do calibration maths.

Contents
--------
Protocols: :class:`Clock`, :class:`MotionDevice` (rate table or centrifuge), :class:`ChamberDevice`,
:class:`ImuSource`, :class:`Station`.
Data: :class:`MotionFeedback`, :class:`MotionStatus`, :class:`ChamberReadings`,
:class:`ChamberStatus`, :class:`ImuBlock`, :class:`ImuHealth`, :class:`ImuIdentity`.

Time base
---------
Every ``time_s`` a device returns is on the station clock (:meth:`Clock.now_s`): seconds since the
run started, virtual on the twin, ``time.monotonic()`` minus the start on real equipment. Drivers
stamp what they receive with the clock they are given; an IMU source also reports its own
``device_time_s`` and sample counter so the analysis can rebuild the device time base.

Units
-----
SI inside: angles in rad (unwrapped, multi-turn), rates in rad/s, temperatures in °C. Drivers
convert at the wire (ACL speaks degrees, for example).

Safety contract
---------------
``safe_stop`` / ``standby`` bring a device to a safe state (rate to zero then mode off; chamber
to standby) and must be callable at any time, also after a fault or a lost connection (then they
do what they still can and never raise). ``status`` reports latched faults as text rather than
raising, so the runner's guards decide what to do. Commands on a faulted or disconnected device
raise :class:`~imucalib.errors.DeviceError` (or :class:`~imucalib.errors.DeviceTimeoutError`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "AxisMode",
    "ChamberDevice",
    "ChamberReadings",
    "ChamberStatus",
    "Clock",
    "ImuBlock",
    "ImuHealth",
    "ImuIdentity",
    "ImuSource",
    "MotionDevice",
    "MotionFeedback",
    "MotionStatus",
    "Station",
    "empty_imu_block",
    "empty_motion_feedback",
]

_F64 = NDArray[np.float64]
AxisMode = Literal["off", "position", "rate", "stop"]


# --- data ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class MotionFeedback:
    """Feedback rows of a table or centrifuge since the previous poll.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Station-clock time of each row. [s]
    angle_rad : ndarray, shape (n, k)
        Measured axis angles, outer axis first, unwrapped. [rad]
    rate_rps : ndarray, shape (n, k)
        Measured axis rates. [rad/s]
    """

    time_s: _F64
    angle_rad: _F64
    rate_rps: _F64

    def __len__(self) -> int:
        return int(self.time_s.shape[0])


def empty_motion_feedback(n_axes: int) -> MotionFeedback:
    """Return a feedback block without rows for `n_axes` axes."""
    return MotionFeedback(np.zeros(0), np.zeros((0, n_axes)), np.zeros((0, n_axes)))


@dataclass(frozen=True)
class MotionStatus:
    """State of a table or centrifuge controller.

    Attributes
    ----------
    modes : tuple of AxisMode
        Mode of each axis.
    interlock_closed : bool
        True when the interlock string is closed (servos may run).
    fault : str or None
        A latched fault (interlock open by a fault, over-speed trip, amplifier fault …) as the
        controller reports it; None when healthy.
    """

    modes: tuple[AxisMode, ...]
    interlock_closed: bool
    fault: str | None = None


@dataclass(frozen=True, eq=False)
class ChamberReadings:
    """Chamber rows since the previous poll: time [s], air temperature [°C], setpoint [°C]."""

    time_s: _F64
    temperature_degc: _F64
    setpoint_degc: _F64

    def __len__(self) -> int:
        return int(self.time_s.shape[0])


@dataclass(frozen=True)
class ChamberStatus:
    """State of a chamber controller: running (vs standby) and any alarm text."""

    running: bool
    alarm: str | None = None


@dataclass(frozen=True, eq=False)
class ImuBlock:
    """IMU samples received since the previous read.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Station-clock receive time. [s]
    device_time_s : ndarray, shape (n,)
        The IMU's own timestamp (NaN where the device has none). [s]
    counter : ndarray of int64, shape (n,)
        Sample counter as sent (it may wrap; gaps are lost samples).
    gyro_rps : ndarray, shape (n, 3)
        Gyro output, sensor frame. [rad/s]
    accel_mps2 : ndarray, shape (n, 3)
        Accelerometer output, sensor frame. [m/s²]
    temperature_degc : ndarray, shape (n,)
        Internal temperature (NaN where the device has none). [°C]
    saturated : ndarray of bool, shape (n,)
        Device-reported over-range flag (False where the device reports none).
    """

    time_s: _F64
    device_time_s: _F64
    counter: NDArray[np.int64]
    gyro_rps: _F64
    accel_mps2: _F64
    temperature_degc: _F64
    saturated: NDArray[np.bool_]

    def __len__(self) -> int:
        return int(self.time_s.shape[0])


def empty_imu_block() -> ImuBlock:
    """Return an IMU block without samples."""
    z = np.zeros(0)
    return ImuBlock(z, z.copy(), np.zeros(0, dtype=np.int64), np.zeros((0, 3)),
                    np.zeros((0, 3)), z.copy(), np.zeros(0, dtype=bool))


@dataclass(frozen=True)
class ImuHealth:
    """Cumulative transport counters of an IMU source since it connected.

    Attributes
    ----------
    frames_ok : int
        Frames decoded and delivered.
    crc_errors : int
        Frames dropped for a bad checksum.
    resyncs : int
        Times the decoder lost and regained frame synchronisation (bytes skipped).
    counter_gaps : int
        Jumps of the sample counter other than +1 (modulo its wrap).
    missing_samples : int
        Samples implied missing by those jumps.
    """

    frames_ok: int = 0
    crc_errors: int = 0
    resyncs: int = 0
    counter_gaps: int = 0
    missing_samples: int = 0


@dataclass(frozen=True)
class ImuIdentity:
    """Who an IMU is and what it can measure.

    Attributes
    ----------
    name : str
        Unit name (serial number); the Recording's stream unit.
    model, maker : str
        Product and manufacturer.
    sample_rate_hz : float
        Nominal output data rate. [Hz]
    gyro_range_rps, accel_range_mps2 : float or None
        Full-scale ranges (for the saturation guard), when known. [rad/s], [m/s²]
    extra : mapping
        Anything else the device reports (firmware, calibration ID …).
    gyro_lsb_rps, accel_lsb_mps2, temperature_lsb_degc : float or None
        The value of one output count, when every sample the source delivers is an exact integer
        multiple of it (a converter's codes times its LSB); the Recording then stores the counts
        as int32 (:func:`imucalib.io.streams.imu_stream_spec`). None: stored as float64.
        [rad/s], [m/s²], [°C]
    """

    name: str
    model: str = ""
    maker: str = ""
    sample_rate_hz: float = float("nan")
    gyro_range_rps: float | None = None
    accel_range_mps2: float | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)
    gyro_lsb_rps: float | None = None
    accel_lsb_mps2: float | None = None
    temperature_lsb_degc: float | None = None


# --- protocols ----------------------------------------------------------------------------------
@runtime_checkable
class Clock(Protocol):
    """The station's time base: virtual on the twin, monotonic on real equipment."""

    def now_s(self) -> float:
        """Return the time since the run started. [s]"""
        ...

    def sleep(self, duration_s: float) -> None:
        """Let `duration_s` pass (the twin advances its virtual time). [s]"""
        ...


@runtime_checkable
class MotionDevice(Protocol):
    """A rate table (one or two axes) or a centrifuge (one axis, ``"spin"``)."""

    name: str
    axis_names: tuple[str, ...]

    def connect(self) -> None:
        """Open the link, take remote control, reset and close the interlocks (servo on)."""
        ...

    def disconnect(self) -> None:
        """Release remote control and close the link (after :meth:`safe_stop`)."""
        ...

    def identify(self) -> str:
        """Return the controller's identification string."""
        ...

    def set_limits(self, axis: int, *, rate_rps: float, accel_rps2: float) -> None:
        """Set the software rate and acceleration limits of an axis. [rad/s], [rad/s²]"""
        ...

    def move_to(self, axis: int, angle_rad: float) -> None:
        """Position mode: move an axis to an angle and hold it. [rad]"""
        ...

    def set_rate(self, axis: int, rate_rps: float) -> None:
        """Rate mode: spin an axis at a constant rate. [rad/s]"""
        ...

    def safe_stop(self) -> None:
        """Bring every axis to rest (rate zero, then mode off); never raises."""
        ...

    def poll(self) -> MotionFeedback:
        """Return the feedback rows since the previous poll (at least the current state)."""
        ...

    def status(self) -> MotionStatus:
        """Return the modes, the interlock state and any latched fault."""
        ...


@runtime_checkable
class ChamberDevice(Protocol):
    """A thermal chamber."""

    name: str

    def connect(self) -> None:
        """Open the link."""
        ...

    def disconnect(self) -> None:
        """Close the link."""
        ...

    def identify(self) -> str:
        """Return the controller's identification string."""
        ...

    def set_temperature(self, temperature_degc: float, *,
                        ramp_degc_ps: float | None = None) -> None:
        """Run at a setpoint, ramping at `ramp_degc_ps` (None: as fast as allowed). [°C], [°C/s]"""
        ...

    def standby(self) -> None:
        """Stop conditioning (safe state); never raises."""
        ...

    def poll(self) -> ChamberReadings:
        """Return the rows since the previous poll (at least the current reading)."""
        ...

    def status(self) -> ChamberStatus:
        """Return running/standby and any alarm."""
        ...


@runtime_checkable
class ImuSource(Protocol):
    """A stream of IMU samples (a packet port, a CSV line stream, the twin)."""

    name: str

    def connect(self) -> None:
        """Open the link and start streaming."""
        ...

    def disconnect(self) -> None:
        """Stop streaming and close the link."""
        ...

    def identify(self) -> ImuIdentity:
        """Return the unit's identity and ranges."""
        ...

    def read(self) -> ImuBlock:
        """Return every sample received since the previous read (possibly none)."""
        ...

    def health(self) -> ImuHealth:
        """Return the cumulative transport counters."""
        ...


@runtime_checkable
class Station(Protocol):
    """Everything a run drives: a clock and the devices, with a description for the records."""

    @property
    def clock(self) -> Clock:
        """The station's time base."""
        ...

    @property
    def table(self) -> MotionDevice | None:
        """The rate table, if any."""
        ...

    @property
    def centrifuge(self) -> MotionDevice | None:
        """The centrifuge, if any."""
        ...

    @property
    def chamber(self) -> ChamberDevice | None:
        """The thermal chamber, if any."""
        ...

    @property
    def imus(self) -> Sequence[ImuSource]:
        """The IMU sources (at least one)."""
        ...

    @property
    def latitude_deg(self) -> float:
        """Latitude of the station. [°]"""
        ...

    @property
    def heading_deg(self) -> float:
        """Azimuth of the table's x axis from North. [°]"""
        ...

    def describe(self) -> dict[str, Any]:
        """Return a JSON-able description (devices, addresses, models) for the Recording."""
        ...
