"""IMU sample streams: binary frames (:class:`PacketImu`) and CSV lines (:class:`CsvLineImu`).

Both implement :class:`~imucalib.station.devices.ImuSource`. A background thread reads the
transport in chunks, stamps each chunk with the station clock when it arrives (host receive
time, docs/drivers.md "Time synchronisation practice"), decodes it and buffers the samples;
:meth:`~PacketImu.read` returns everything received since the previous read.

Time stamps. A chunk's last sample arrives with it, so ``receive time − device time`` of that
sample is the clock offset plus a delay that is never negative. Each sample's station time is
its device time plus the *smallest* such difference over the chunks of the last
``sync_window_s`` station seconds (the lower envelope: a delay spike on a loaded host moves no
sample, where stamping each chunk by its own arrival opened gaps of 0.15–0.35 s and bunched the
samples after them; a least-squares fit, as §3.3 suggests, would be pulled by those one-sided
spikes). The window follows a device clock that drifts against the station's. Without device
times, a chunk is back-dated from its arrival by the nominal period. The device counter and time
are kept alongside so that the analysis can rebuild the device time base.

Contents
--------
:class:`PacketImu`
    Frames of :mod:`~imucalib.drivers.imu_packet` (sync, counter, CRC-16).
:class:`CsvLineImu`
    Lines of :mod:`~imucalib.drivers.imu_csv` (header with units).

When the link is lost, :meth:`~PacketImu.read` first returns what was received, then raises
:class:`~imucalib.errors.DeviceError` naming the cause; :meth:`~PacketImu.connect` starts over
(counters reset).
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import asdict, replace
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from imucalib.drivers.base import DeviceCheck, TransportOpener
from imucalib.drivers.imu_csv import CsvLineDecoder
from imucalib.drivers.imu_packet import DecodedSamples, PacketDecoder
from imucalib.drivers.transport import Transport, log_wire
from imucalib.errors import CalibrationError, DeviceError, DeviceTimeoutError
from imucalib.station.devices import Clock, ImuBlock, ImuHealth, ImuIdentity, empty_imu_block

__all__ = ["CsvLineImu", "PacketImu"]

_LOG = logging.getLogger(__name__)


class _Decoder(Protocol):
    frames_ok: int
    crc_errors: int
    resyncs: int
    info: dict[str, str]

    @property
    def counter_gaps(self) -> int: ...

    @property
    def missing_samples(self) -> int: ...

    def feed(self, data: bytes) -> DecodedSamples: ...


class _StreamImu:
    """The reader thread, buffer and counters shared by the stream classes."""

    kind = "stream"

    def __init__(self, identity: ImuIdentity, opener: TransportOpener, *, clock: Clock,
                 decoder_factory: Callable[[], _Decoder], address: str = "",
                 chunk_bytes: int = 65536, read_timeout_s: float = 0.2,
                 sync_window_s: float = 10.0) -> None:
        self.name = identity.name
        self._identity = identity
        self._opener = opener
        self._clock = clock
        self._make_decoder = decoder_factory
        self.address = address
        self.chunk_bytes = int(chunk_bytes)
        self.read_timeout_s = float(read_timeout_s)
        self._lock = threading.Lock()
        self._blocks: list[tuple[float, DecodedSamples]] = []
        self._decoder: _Decoder = decoder_factory()
        self._transport: Transport | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._error: Exception | None = None
        self._first_data = threading.Event()
        self._last_time_s = -np.inf
        self.sync_window_s = float(sync_window_s)
        self._offsets: deque[tuple[float, float]] = deque()  # (receive time, offset) [s]

    @property
    def connected(self) -> bool:
        """Whether the reader thread is running."""
        return self._thread is not None and self._thread.is_alive()

    def connect(self) -> None:
        """Open the link and start the reader thread (counters and buffer start afresh)."""
        if self.connected:
            return
        self.disconnect()
        self._transport = self._opener()
        with self._lock:
            self._decoder = self._make_decoder()
            self._blocks = []
            self._error = None
            # a backlog in the first chunk is not back-dated before the connection
            self._last_time_s = self._clock.now_s()
            self._offsets.clear()  # the device's clock starts afresh with its counters
        self._stop.clear()
        self._first_data.clear()
        self._thread = threading.Thread(target=self._run, name=f"imu-reader-{self.name}",
                                        daemon=True)
        self._thread.start()
        _LOG.info("%s: streaming from %s", self.name, self.address or "transport")

    def _run(self) -> None:
        transport = self._transport
        assert transport is not None  # set by connect before the thread starts
        while not self._stop.is_set():
            try:
                data = transport.read(self.chunk_bytes, timeout_s=self.read_timeout_s)
            except DeviceTimeoutError:
                continue
            except Exception as exc:  # DeviceError, or a transport closed under the reader
                if not self._stop.is_set():
                    _LOG.warning("%s: stream lost: %s", self.name, exc)
                    with self._lock:
                        self._error = exc
                break
            t_host = self._clock.now_s()
            log_wire(_LOG, self.name, "rx", f"{len(data)} bytes")
            try:
                with self._lock:
                    samples = self._decoder.feed(data)
                    if len(samples):
                        self._blocks.append((t_host, samples))
            except CalibrationError as exc:
                _LOG.error("%s: undecodable stream: %s", self.name, exc)
                with self._lock:
                    self._error = exc
                break
            self._first_data.set()

    def disconnect(self) -> None:
        """Stop the reader thread and close the link (idempotent)."""
        self._stop.set()
        transport, self._transport = self._transport, None
        if transport is not None:
            try:
                transport.close()
            except Exception as exc:  # closing must not raise
                _LOG.debug("%s: close failed: %s", self.name, exc)
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None

    def read(self) -> ImuBlock:
        """Return every sample received since the previous read (possibly none).

        Raises
        ------
        DeviceError
            When nothing is left to return and the stream was lost (or never connected).
        """
        with self._lock:
            blocks, self._blocks = self._blocks, []
            error = self._error
        if not blocks:
            if error is not None:
                raise DeviceError(f"{self.name}: stream lost: {error}") from error
            if self._thread is None:
                raise DeviceError(f"{self.name}: not connected; call connect()")
            return empty_imu_block()
        samples = DecodedSamples.concatenate([b for _, b in blocks])
        times = np.concatenate([self._back_dated(t, b) for t, b in blocks])
        times = np.maximum.accumulate(np.maximum(times, self._last_time_s))
        self._last_time_s = float(times[-1])
        return ImuBlock(time_s=times, device_time_s=samples.device_time_s,
                        counter=samples.counter, gyro_rps=samples.gyro_rps,
                        accel_mps2=samples.accel_mps2,
                        temperature_degc=samples.temperature_degc,
                        saturated=samples.saturated)

    def _back_dated(self, t_host: float, block: DecodedSamples) -> NDArray[np.float64]:
        """Station time of each sample of a chunk that arrived at `t_host` (module docstring).

        Device time plus the lower envelope of the receive-time offsets over the sync window;
        without device times, back-dated from the arrival by the nominal period. Chunks must be
        passed in arrival order.
        """
        n = len(block)
        dev = np.asarray(block.device_time_s, dtype=np.float64)
        if n and np.all(np.isfinite(dev)):
            self._offsets.append((t_host, t_host - float(dev[-1])))
            while self._offsets and self._offsets[0][0] < t_host - self.sync_window_s:
                self._offsets.popleft()
            offset = min(v for _, v in self._offsets)
            return np.asarray(dev + offset, dtype=np.float64)
        rate = self._identity.sample_rate_hz
        period = 1.0 / rate if rate > 0 else 0.0
        return np.asarray(t_host - period * np.arange(n - 1, -1, -1), dtype=np.float64)

    def health(self) -> ImuHealth:
        """Return the cumulative transport counters since the last connect."""
        with self._lock:
            d = self._decoder
            return ImuHealth(frames_ok=d.frames_ok, crc_errors=d.crc_errors, resyncs=d.resyncs,
                             counter_gaps=d.counter_gaps, missing_samples=d.missing_samples)

    def identify(self, *, wait_s: float = 1.0) -> ImuIdentity:
        """Return the configured identity, with what the device announced in ``extra``.

        While connected, waits up to `wait_s` wall seconds for the device's info frame (or
        comment lines), or for the first sample when it sends none.
        """
        deadline = time.monotonic() + wait_s
        while self.connected and time.monotonic() < deadline:
            with self._lock:  # the info comes first: wait for it or for the first sample
                if self._decoder.info or self._decoder.frames_ok:
                    break
            self._first_data.wait(0.01)
        with self._lock:
            info = dict(self._decoder.info)
        extra = {**dict(self._identity.extra), **{f"device_{k}": v for k, v in info.items()}}
        return replace(self._identity, extra=extra)

    def check(self, *, listen_s: float = 0.5) -> DeviceCheck:
        """Connect, identify, listen `listen_s` wall seconds, disconnect; report the stream."""
        try:
            self.connect()
            ident = self.identify()
            time.sleep(listen_s)
            block = self.read()
            health = self.health()
        finally:
            self.disconnect()
        serial = ident.extra.get("device_serial")
        identity = f"{ident.maker} {ident.model}".strip() + (f" serial {serial}" if serial
                                                              else "")
        n = len(block)
        span = float(np.ptp(block.device_time_s)) if n > 1 else 0.0
        rate = (n - 1) / span if span > 0 and np.all(np.isfinite(block.device_time_s)) else None
        rate_txt = f" ≈ {rate:.0f} Hz device time" if rate else ""
        state = (f"frames {health.frames_ok}, CRC errors {health.crc_errors}, gaps "
                 f"{health.counter_gaps}, resyncs {health.resyncs}")
        saturated = int(np.count_nonzero(block.saturated))
        ok = n > 0 and health.crc_errors == 0 and health.counter_gaps == 0 and saturated == 0
        reading = f"{n} samples in {listen_s:g} s{rate_txt}" + (
            f"; {saturated} saturated" if saturated else "")
        return DeviceCheck("imu", self.name, self.kind, self.address,
                           identity, state, reading, ok=ok,
                           details={"samples": n, "health": asdict(health),
                                    "saturated": saturated, "identity": dict(ident.extra)})

    def describe(self) -> dict[str, Any]:
        """Return a JSON-able description (kind, address, identity, ranges)."""
        ident = self._identity
        return {"role": "imu", "name": self.name, "kind": self.kind, "address": self.address,
                "model": ident.model, "maker": ident.maker,
                "sample_rate_hz": ident.sample_rate_hz, "gyro_range_rps": ident.gyro_range_rps,
                "accel_range_mps2": ident.accel_range_mps2,
                "device_info": dict(self._decoder.info)}


class PacketImu(_StreamImu):
    """An IMU streaming the binary frame of :mod:`~imucalib.drivers.imu_packet`.

    Parameters
    ----------
    identity : ImuIdentity
        Name (the Recording's unit), model, maker, nominal rate and ranges.
    opener : callable
        Returns an opened transport (serial or TCP).
    clock : Clock
        The station clock (receive time stamps).
    gyro_scale_rps, accel_scale_mps2 : float, optional
        SI value of one count, for int32-count frames. [rad/s], [m/s²]
    address : str
        Transport URL, for descriptions.
    chunk_bytes : int
        Largest read per chunk.
    """

    kind = "packet"

    def __init__(self, identity: ImuIdentity, opener: TransportOpener, *, clock: Clock,
                 gyro_scale_rps: float | None = None, accel_scale_mps2: float | None = None,
                 address: str = "", chunk_bytes: int = 65536) -> None:
        super().__init__(identity, opener, clock=clock, address=address, chunk_bytes=chunk_bytes,
                         decoder_factory=lambda: PacketDecoder(gyro_scale_rps=gyro_scale_rps,
                                                               accel_scale_mps2=accel_scale_mps2))


class CsvLineImu(_StreamImu):
    """An IMU streaming CSV lines with a header naming columns and units.

    Parameters
    ----------
    identity, opener, clock, address, chunk_bytes
        As for :class:`PacketImu`.
    """

    kind = "csv"

    def __init__(self, identity: ImuIdentity, opener: TransportOpener, *, clock: Clock,
                 address: str = "", chunk_bytes: int = 65536) -> None:
        super().__init__(identity, opener, clock=clock, address=address, chunk_bytes=chunk_bytes,
                         decoder_factory=CsvLineDecoder)
