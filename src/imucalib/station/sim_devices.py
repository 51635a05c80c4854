"""The twin's devices: a motion controller (table or centrifuge), a chamber, IMU sources, a clock.

Each implements one device protocol of :mod:`imucalib.station.devices` over the twin's rig, in
virtual time; :class:`~imucalib.station.sim.SimStation` builds them and advances the rig they
read. Each can be made to fail on purpose (the fault hooks below), so that the runner's guards are
tested on the same code path as with real equipment.

Contents
--------
:class:`SimClock`, :class:`SimMotionDevice`, :class:`SimChamberDevice`, :class:`SimImuSource`.

Centrifuge controller
---------------------
The centrifuge's :class:`SimMotionDevice` latches an imbalance alarm (a device fault; the spin
stops) when the rotor's excursion |c|·ω² exceeds ``CentrifugeConfig.imbalance_alarm_um``.

Fault hooks
-----------
``SimMotionDevice``: :meth:`~SimMotionDevice.drop_connection` (every call raises DeviceError until
the runner reconnects; ``permanent=True`` refuses reconnection),
:meth:`~SimMotionDevice.latch_fault`
(interlock opens, status reports the fault, demands are refused until a reconnect resets it),
:meth:`~SimMotionDevice.add_position_drift` and :meth:`~SimMotionDevice.add_rate_error` (the
reported axis drifts / shows a rate error for a while), :meth:`~SimMotionDevice.disturb` (the axis
is physically pushed off its position). ``SimChamberDevice``:
:meth:`~SimChamberDevice.raise_alarm`. ``SimImuSource``: :meth:`~SimImuSource.corrupt_frames`
(frames fail their CRC and are lost), :meth:`~SimImuSource.drop_samples`,
:meth:`~SimImuSource.saturate`. :meth:`SimStation.at` schedules any of them at a station time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from imucalib.errors import DeviceError, InvalidInputError, LimitExceededError
from imucalib.models.sensor import SensorSpec
from imucalib.sim.centrifuge import SimCentrifuge
from imucalib.sim.synth import ImuSamples
from imucalib.sim.table import SimRateTable, TableFeedback
from imucalib.station.devices import (
    AxisMode,
    ChamberReadings,
    ChamberStatus,
    ImuBlock,
    ImuHealth,
    ImuIdentity,
    MotionFeedback,
    MotionStatus,
)

if TYPE_CHECKING:
    from imucalib.station.sim import SimStation

__all__ = ["SimChamberDevice", "SimClock", "SimImuSource", "SimMotionDevice"]

_F64 = NDArray[np.float64]


@dataclass
class _Window:
    """A fault active on [start, end) of station time."""

    start_s: float
    end_s: float
    value: float = 0.0
    axis: int = 0

    def active(self, t: _F64) -> NDArray[np.bool_]:
        return (t >= self.start_s) & (t < self.end_s)


class SimClock:
    """Virtual time: :meth:`sleep` advances the twin and fills the devices' buffers."""

    def __init__(self, station: SimStation) -> None:
        self._station = station

    def now_s(self) -> float:
        """Return the station time. [s]"""
        return self._station.start_time_s + self._station.rig.now_s

    def sleep(self, duration_s: float) -> None:
        """Let `duration_s` of virtual time pass. [s]"""
        if not duration_s >= 0.0:
            raise InvalidInputError(f"`duration_s` must be ≥ 0; got {duration_s!r}")
        self._station.advance(duration_s)


class SimMotionDevice:
    """A rate table or centrifuge of the twin behind the :class:`MotionDevice` protocol.

    For a centrifuge (`centrifuge` given) the controller watches the rotor's excursion
    |c|·ω² (c with the current load, ω the true spin rate) in every feedback block: above
    `imbalance_alarm_m` it latches the fault "imbalance alarm: …" and stops the spin (a real
    centrifuge controller's own alarm).
    """

    def __init__(self, station: SimStation, table: SimRateTable, name: str, *,
                 centrifuge: SimCentrifuge | None = None,
                 imbalance_alarm_m: float | None = None) -> None:
        self._station = station
        self._table = table
        self._centrifuge = centrifuge
        self._imbalance_alarm_m = imbalance_alarm_m
        self.name = name
        self.axis_names = table.spec.names
        self._buffer: list[TableFeedback] = []
        self._connected = False
        self._interlock_closed = False
        self._fault: str | None = None
        self._fault_persistent = False
        self._link_down = False
        self._link_permanent = False
        self._limits = [(ax.max_rate_rps, ax.max_accel_rps2) for ax in table.spec.axes]
        self._drifts: list[_Window] = []
        self._rate_errors: list[_Window] = []
        self.commands: list[tuple[float, str]] = []  # (station time, command) for the tests

    # --- protocol ---------------------------------------------------------------------------
    def connect(self) -> None:
        """Open the link, reset the interlocks and close them (a latched fault is cleared)."""
        if self._link_down and self._link_permanent:
            raise DeviceError(f"{self.name}: connection refused (link down)")
        self._link_down = False
        if self._fault is not None and self._fault_persistent:
            raise DeviceError(f"{self.name}: interlock reset failed: {self._fault}")
        self._fault = None
        self._connected = True
        self._interlock_closed = True
        self._log("connect")

    def disconnect(self) -> None:
        """Close the link."""
        self._connected = False

    def identify(self) -> str:
        """Return the controller identification."""
        self._check_link()
        return f"imucalib twin {self.name} ({len(self.axis_names)} axes: {self.axis_names})"

    def set_limits(self, axis: int, *, rate_rps: float, accel_rps2: float) -> None:
        """Set the software limits of an axis (within the table's own)."""
        self._check_ready()
        ax = self._table.spec.axes[self._axis(axis)]
        if rate_rps > ax.max_rate_rps or accel_rps2 > ax.max_accel_rps2:
            raise LimitExceededError(
                f"{self.name} axis {ax.name!r}: limits {rate_rps:g} rad/s, {accel_rps2:g} rad/s² "
                f"exceed the table's {ax.max_rate_rps:g} rad/s, {ax.max_accel_rps2:g} rad/s²")
        self._limits[self._axis(axis)] = (rate_rps, accel_rps2)

    def move_to(self, axis: int, angle_rad: float) -> None:
        """Position mode: move to `angle_rad` (the equivalent angle nearest to where it is)."""
        self._check_ready()
        i = self._axis(axis)
        t = self._station.rig.now_s
        target = angle_rad
        if self._table.spec.axes[i].angle_limits_rad is None:
            current = float(self._table.axis_motion(i, np.array([t]))[0][0])
            target = angle_rad + 2.0 * math.pi * round((current - angle_rad) / (2.0 * math.pi))
        rate, accel = self._limits[i]
        self._table.command_position(i, target, t, rate_rps=rate, accel_rps2=accel)
        self._log(f"move axis {i} to {angle_rad:.9g} rad")

    def set_rate(self, axis: int, rate_rps: float) -> None:
        """Rate mode: spin an axis at `rate_rps`."""
        self._check_ready()
        i = self._axis(axis)
        if abs(rate_rps) > self._limits[i][0]:
            raise LimitExceededError(f"{self.name} axis {i}: rate {rate_rps:g} rad/s exceeds the "
                                     f"software limit {self._limits[i][0]:g} rad/s")
        self._table.command_rate(i, rate_rps, self._station.rig.now_s,
                                 accel_rps2=self._limits[i][1])
        self._log(f"rate axis {i} {rate_rps:.9g} rad/s")

    def safe_stop(self) -> None:
        """Brake every axis to rest, switch it off, and open the interlock.

        It works with the link down too: the twin's controller stops on its own watchdog.
        """
        t = self._station.rig.now_s
        for i in range(len(self.axis_names)):
            if self._table.mode(i, t) != "off":
                self._table.command_off(i, t)
        self._interlock_closed = False
        self._log("safe stop")

    def poll(self) -> MotionFeedback:
        """Return the feedback rows since the previous poll."""
        self._check_link()
        blocks, self._buffer = self._buffer, []
        k = len(self.axis_names)
        if not blocks:
            t = np.array([self._station.rig.now_s])
            blocks = [self._table.feedback(t)]
        time_s = np.concatenate([b.time_s for b in blocks])
        angle = np.concatenate([b.angle_rad for b in blocks]).reshape(-1, k)
        rate = np.concatenate([b.rate_rps for b in blocks]).reshape(-1, k)
        for w in self._drifts:
            on = w.active(time_s)
            angle[on, w.axis] += w.value * (time_s[on] - w.start_s)
        for w in self._rate_errors:
            rate[w.active(time_s), w.axis] += w.value
        return MotionFeedback(time_s + self._station.start_time_s, angle, rate)

    def status(self) -> MotionStatus:
        """Return the axis modes, the interlock state and any latched fault."""
        self._check_link()
        t = self._station.rig.now_s
        modes: tuple[AxisMode, ...] = tuple(self._table.mode(i, t)
                                            for i in range(len(self.axis_names)))
        return MotionStatus(modes=modes, interlock_closed=self._interlock_closed,
                            fault=self._fault)

    # --- fault hooks -------------------------------------------------------------------------
    def drop_connection(self, *, permanent: bool = False) -> None:
        """Lose the link: every call raises DeviceError until :meth:`connect` (unless permanent)."""
        self._link_down = True
        self._link_permanent = permanent
        self._connected = False

    def latch_fault(self, text: str, *, persistent: bool = False) -> None:
        """Open the interlock with a latched fault; the axes brake to rest on their own."""
        self._fault = text
        self._fault_persistent = persistent
        self._interlock_closed = False
        t = self._station.rig.now_s
        for i in range(len(self.axis_names)):
            self._table.command_stop(i, t)

    def add_position_drift(self, axis: int, rate_rps: float, duration_s: float) -> None:
        """Make the reported angle of `axis` drift at `rate_rps` for `duration_s` from now."""
        t = self._station.rig.now_s
        self._drifts.append(_Window(t, t + duration_s, rate_rps, self._axis(axis)))

    def disturb(self, axis: int, offset_rad: float) -> None:
        """Push an axis physically away from where it holds by `offset_rad` (a bump, a slip)."""
        i = self._axis(axis)
        t = self._station.rig.now_s
        current = float(self._table.axis_motion(i, np.array([t]))[0][0])
        self._table.command_position(i, current + offset_rad, t)

    def add_rate_error(self, axis: int, error_rps: float, duration_s: float) -> None:
        """Add `error_rps` to the reported rate of `axis` for `duration_s` from now."""
        t = self._station.rig.now_s
        self._rate_errors.append(_Window(t, t + duration_s, error_rps, self._axis(axis)))

    # --- internals ---------------------------------------------------------------------------
    def _push(self, fb: TableFeedback | None) -> None:
        if fb is not None and fb.time_s.size:
            self._buffer.append(fb)
            self._watch_imbalance(fb.time_s)

    def _watch_imbalance(self, time_s: _F64) -> None:
        """Latch the imbalance alarm when the rotor's excursion |c|·ω² passes its threshold."""
        fuge, alarm = self._centrifuge, self._imbalance_alarm_m
        if fuge is None or alarm is None or self._fault is not None:
            return
        rate = self._table.axis_motion(0, time_s)[1]
        excursion_m = abs(fuge.unbalance_m_per_rps_sq) * rate * rate
        over = np.flatnonzero(excursion_m > alarm)
        if over.size:  # the excursion where it first passed the threshold
            self.latch_fault(f"imbalance alarm: the rotor is {excursion_m[over[0]] / 1e-6:.4g} "
                             f"µm off centre (alarm at {alarm / 1e-6:.4g} µm)")

    def _axis(self, axis: int) -> int:
        if not 0 <= int(axis) < len(self.axis_names):
            raise InvalidInputError(f"{self.name}: axis {axis} does not exist; axes "
                                    f"0..{len(self.axis_names) - 1} {self.axis_names}")
        return int(axis)

    def _check_link(self) -> None:
        if self._link_down:
            raise DeviceError(f"{self.name}: connection lost")

    def _check_ready(self) -> None:
        self._check_link()
        if not self._connected:
            raise DeviceError(f"{self.name}: not connected")
        if self._fault is not None or not self._interlock_closed:
            reason = self._fault or "interlock open"
            raise DeviceError(f"{self.name}: demand refused ({reason})")

    def _log(self, text: str) -> None:
        self.commands.append((self._station.clock.now_s(), text))


class SimChamberDevice:
    """The twin's chamber behind the :class:`ChamberDevice` protocol."""

    def __init__(self, station: SimStation, name: str) -> None:
        self._station = station
        self.name = name
        self._buffer: list[Any] = []
        self._running = False
        self._alarms: list[tuple[_Window, str]] = []

    def connect(self) -> None:
        """Open the link (nothing to do on the twin)."""

    def disconnect(self) -> None:
        """Close the link."""

    def identify(self) -> str:
        """Return the controller identification."""
        return f"imucalib twin chamber {self.name}"

    def set_temperature(self, temperature_degc: float, *,
                        ramp_degc_ps: float | None = None) -> None:
        """Run at a setpoint."""
        chamber = self._station.rig.chamber
        assert chamber is not None
        chamber.command_setpoint(temperature_degc, self._station.rig.now_s, ramp_degc_ps)
        self._running = True

    def standby(self) -> None:
        """Stop conditioning (the twin holds its current setpoint)."""
        self._running = False

    def poll(self) -> ChamberReadings:
        """Return the rows since the previous poll."""
        blocks, self._buffer = self._buffer, []
        rig = self._station.rig
        if not blocks:
            blocks = [rig.chamber_readings(np.array([rig.now_s]))]
        t0 = self._station.start_time_s
        return ChamberReadings(np.concatenate([b.time_s for b in blocks]) + t0,
                               np.concatenate([b.temperature_degc for b in blocks]),
                               np.concatenate([b.setpoint_degc for b in blocks]))

    def status(self) -> ChamberStatus:
        """Return running/standby and any active alarm."""
        t = self._station.rig.now_s
        for window, text in self._alarms:
            if window.start_s <= t < window.end_s:
                return ChamberStatus(self._running, text)
        return ChamberStatus(self._running, None)

    def raise_alarm(self, text: str, duration_s: float) -> None:
        """Report an alarm for `duration_s` from now."""
        t = self._station.rig.now_s
        self._alarms.append((_Window(t, t + duration_s), text))


class SimImuSource:
    """One twin IMU behind the :class:`ImuSource` protocol (as a packet stream would deliver)."""

    def __init__(self, station: SimStation, name: str) -> None:
        self._station = station
        self.name = name
        self._buffer: list[ImuSamples] = []
        self._health = ImuHealth()
        self._last_counter: int | None = None
        self._corrupt: list[_Window] = []
        self._drops: list[_Window] = []
        self._saturate: list[_Window] = []

    def connect(self) -> None:
        """Start streaming."""

    def disconnect(self) -> None:
        """Stop streaming."""

    def identify(self) -> ImuIdentity:
        """Return the unit's identity and ranges."""
        imu = self._station.rig.imus[self.name]
        grade = self._station.grades.get(self.name, "")
        temp_lsb = imu.temperature_resolution_degc
        return ImuIdentity(name=self.name, model=f"twin-{grade}", maker="imucalib digital twin",
                           sample_rate_hz=imu.model.sample_rate_hz,
                           gyro_range_rps=imu.model.gyro_output.range,
                           accel_range_mps2=imu.model.accel_output.range,
                           extra={"bandwidth_hz": imu.model.gyro_output.bandwidth_hz},
                           gyro_lsb_rps=_count_lsb(imu.model.gyro_output),
                           accel_lsb_mps2=_count_lsb(imu.model.accel_output),
                           temperature_lsb_degc=temp_lsb if temp_lsb > 0 else None)

    def read(self) -> ImuBlock:
        """Return the samples delivered since the previous read."""
        blocks, self._buffer = self._buffer, []
        imu = self._station.rig.imus[self.name].model
        t0 = self._station.start_time_s
        if not blocks:
            z = np.zeros(0)
            return ImuBlock(z, z.copy(), np.zeros(0, dtype=np.int64), np.zeros((0, 3)),
                            np.zeros((0, 3)), z.copy(), np.zeros(0, dtype=bool))
        rig_t = np.concatenate([b.time_s for b in blocks])
        block = ImuBlock(
            time_s=rig_t + t0,
            device_time_s=np.concatenate([b.device_time_s for b in blocks]),
            counter=np.concatenate([b.counter for b in blocks]).astype(np.int64),
            gyro_rps=np.concatenate([b.gyro_rps for b in blocks]),
            accel_mps2=np.concatenate([b.accel_mps2 for b in blocks]),
            temperature_degc=np.concatenate([b.temperature_degc for b in blocks]),
            saturated=np.concatenate([b.saturated for b in blocks]))
        keep = np.ones(len(block), dtype=bool)
        n_crc = 0
        for w in self._corrupt:
            hit = w.active(rig_t)
            n_crc += int(np.count_nonzero(hit & keep))
            keep &= ~hit
        for w in self._drops:
            keep &= ~(w.active(rig_t) & (self._station.fault_rng.random(rig_t.size) < w.value))
        sat = np.zeros(len(block), dtype=bool)
        for w in self._saturate:
            sat |= w.active(rig_t)
        gyro, accel, flags = block.gyro_rps, block.accel_mps2, block.saturated
        if sat.any():
            gyro, accel, flags = gyro.copy(), accel.copy(), flags | sat
            gyro[sat] = _full_scale(imu.gyro_output)
            accel[sat] = _full_scale(imu.accel_output)
        out = ImuBlock(block.time_s[keep], block.device_time_s[keep], block.counter[keep],
                       gyro[keep], accel[keep], block.temperature_degc[keep], flags[keep])
        self._count(out.counter, n_crc)
        return out

    def health(self) -> ImuHealth:
        """Return the cumulative transport counters."""
        return self._health

    # --- fault hooks -------------------------------------------------------------------------
    def corrupt_frames(self, duration_s: float) -> None:
        """Every frame of the next `duration_s` fails its CRC (and is lost)."""
        t = self._station.rig.now_s
        self._corrupt.append(_Window(t, t + duration_s))

    def drop_samples(self, probability: float, duration_s: float) -> None:
        """Lose samples with `probability` for `duration_s` from now."""
        t = self._station.rig.now_s
        self._drops.append(_Window(t, t + duration_s, probability))

    def saturate(self, duration_s: float) -> None:
        """Drive every channel to its range for `duration_s` from now."""
        t = self._station.rig.now_s
        self._saturate.append(_Window(t, t + duration_s))

    def _count(self, counter: NDArray[np.int64], n_crc: int) -> None:
        h = self._health
        gaps = missing = 0
        if counter.size:
            c = counter if self._last_counter is None else np.concatenate(
                ([self._last_counter], counter))
            dc = np.diff(c)
            jumps = dc != 1
            gaps, missing = int(np.count_nonzero(jumps)), int(np.sum(np.clip(dc[jumps] - 1, 0,
                                                                              None)))
            self._last_counter = int(counter[-1])
        self._health = ImuHealth(frames_ok=h.frames_ok + int(counter.size),
                                 crc_errors=h.crc_errors + n_crc, resyncs=h.resyncs,
                                 counter_gaps=h.counter_gaps + gaps,
                                 missing_samples=h.missing_samples + missing)


def _count_lsb(spec: SensorSpec) -> float | None:
    """Return the LSB of an output whose every value is an int32 count of it, else None.

    The output stage (:mod:`imucalib.models.sensor`) delivers ``k·LSB`` with ``k`` between its
    code limits; without limits (no range), or with codes beyond int32, the counts are not
    bounded by int32 and the output is stored as float64.
    """
    lsb = spec.effective_lsb
    limits = spec.code_limits()
    if lsb is None or limits is None:
        return None
    lo, hi = limits
    info = np.iinfo(np.int32)
    top = max(hi, _full_scale(spec) / lsb)  # an injected saturation's code included
    return lsb if info.min <= lo and top <= info.max else None


def _full_scale(spec: SensorSpec) -> float:
    """Return the value an injected saturation drives a channel to: the range, on the grid.

    With a word length the range is a code (``2^(b−1)·LSB``) itself; with a LSB alone the
    nearest multiple of it, so that the value stays one the output stage can deliver.
    """
    top = spec.range or 0.0
    lsb = spec.effective_lsb
    return float(np.rint(top / lsb) * lsb) if lsb is not None else top
