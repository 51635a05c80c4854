"""IMU stream simulators: the twin IMU's samples as binary frames or CSV lines, in real time.

A generator thread wakes every `chunk_period_s` wall seconds, asks the rig for the IMU's samples
up to the current simulated time (``rig.generate_imu``), applies the injected faults and sends
the bytes to every connected client (the twin keeps generating while no client listens, so its
clock stays consistent). A client first gets an info frame (packet) or comment and header lines
(CSV), and again every `greeting_period_s` wall seconds: a serial port opened mid-stream (or one
that discards its input buffer on open, as pyserial's ``socket://`` does) still learns them.

Contents
--------
:class:`PacketImuServer`
    Frames of :mod:`imucalib.drivers.imu_packet` (float32 SI, or int32 counts).
:class:`CsvImuServer`
    Lines of :mod:`imucalib.drivers.imu_csv` (gyro in °/s, accel in g).
:class:`InjectedImuFaults`
    Counters of the samples each fault touched (only while a client was connected).

Fault hooks
-----------
``set_corruption(probability)`` (bad CRC, or a garbled CSV line), ``set_drop_probability(p)``
(samples not sent: counter gaps), ``saturate(on)`` (gyro x at full scale with the saturation
flag), and :meth:`~imucalib.drivers.simulators.SimServer.drop_connections`. Random choices use
the server's seeded generator.
"""

from __future__ import annotations

import logging
import socket
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from imucalib.drivers.imu_csv import format_header, format_lines
from imucalib.drivers.imu_packet import (
    FLAG_SATURATED,
    SAMPLE_FRAME_SIZE,
    DecodedSamples,
    encode_info,
    encode_samples,
)
from imucalib.drivers.simulators._base import SimServer, SimTimeBase
from imucalib.errors import InvalidInputError
from imucalib.sim.rig import TwinRig

__all__ = ["CsvImuServer", "InjectedImuFaults", "PacketImuServer"]

_LOG = logging.getLogger(__name__)


@dataclass
class InjectedImuFaults:
    """Counters of the samples each fault touched, as sent to connected clients.

    Attributes
    ----------
    corrupted : list of int
        Counters of the samples sent with a bad CRC (or a garbled line).
    dropped : list of int
        Counters of the samples not sent.
    saturated : list of int
        Counters of the samples the hook saturated.
    sent : int
        Samples sent (corrupted ones included).
    last_counter : int
        Counter of the last sample generated while a client was connected (-1: none).
    """

    corrupted: list[int] = field(default_factory=list)
    dropped: list[int] = field(default_factory=list)
    saturated: list[int] = field(default_factory=list)
    sent: int = 0
    last_counter: int = -1


class _ImuStreamServer(SimServer):
    """Generator thread, client set and fault hooks shared by the two stream formats."""

    def __init__(self, name: str, rig: TwinRig, time_base: SimTimeBase, imu_name: str, *,
                 chunk_period_s: float = 0.02, greeting_period_s: float = 1.0, seed: int = 0,
                 port: int = 0) -> None:
        super().__init__(name, port=port)
        if imu_name not in rig.imus:
            raise InvalidInputError(f"no IMU named {imu_name!r} on the rig; have "
                                    f"{list(rig.imus)}")
        self.rig, self.time_base, self.imu_name = rig, time_base, imu_name
        self.model = rig.imus[imu_name].model
        self.gyro_range_rps = float(self.model.gyro_output.range or 2000.0 * np.pi / 180.0)
        self.chunk_period_s = float(chunk_period_s)
        self.greeting_period_s = float(greeting_period_s)
        self._rng = np.random.default_rng(seed)
        self._corrupt_p = 0.0
        self._drop_p = 0.0
        self._saturate = False
        self.injected = InjectedImuFaults()
        self._streaming: set[socket.socket] = set()
        self._gen_thread = threading.Thread(target=self._generate_loop, name=f"{name}-gen",
                                            daemon=True)

    def start(self) -> SimServer:
        """Start accepting clients and generating samples; returns self."""
        super().start()
        self._gen_thread.start()
        return self

    def close(self) -> None:
        """Stop generating and close (idempotent)."""
        super().close()
        if self._gen_thread.is_alive():
            self._gen_thread.join(timeout=2.0)

    # --- fault hooks --------------------------------------------------------------------------
    def set_corruption(self, probability: float) -> None:
        """Send each sample with a bad CRC (packet) or garbled (CSV) with `probability`."""
        self._corrupt_p = self._probability(probability)

    def set_drop_probability(self, probability: float) -> None:
        """Leave each sample out with `probability` (its counter is skipped)."""
        self._drop_p = self._probability(probability)

    def saturate(self, on: bool = True) -> None:
        """Send gyro x at +full scale with the saturation flag (while `on`)."""
        self._saturate = bool(on)

    @staticmethod
    def _probability(p: float) -> float:
        value = float(p)
        if not 0.0 <= value < 1.0:
            raise InvalidInputError(f"probability must be in [0, 1); got {p}")
        return value

    # --- clients ------------------------------------------------------------------------------
    def greeting(self) -> bytes:  # pragma: no cover - abstract
        """Bytes a new client receives first."""
        raise NotImplementedError

    def encode(self, samples: DecodedSamples, corrupt: np.ndarray) -> bytes:  # pragma: no cover
        """Bytes of `samples`, with the `corrupt` ones damaged."""
        raise NotImplementedError

    def handle(self, conn: socket.socket) -> None:
        """Send the greeting, stream, and discard whatever the client sends."""
        with self._clients_lock:
            conn.sendall(self.greeting())
            self._streaming.add(conn)
        try:
            while not self._closed.is_set():
                if not conn.recv(4096):
                    return
        finally:
            with self._clients_lock:
                self._streaming.discard(conn)

    def _generate_loop(self) -> None:
        next_t = time.monotonic()
        next_greeting = next_t + self.greeting_period_s
        while not self._closed.is_set():
            next_t += self.chunk_period_s
            time.sleep(max(0.0, next_t - time.monotonic()))
            try:
                with self.rig.lock:
                    s = self.rig.generate_imu(self.imu_name, self.time_base.now_s())
            except Exception:
                _LOG.exception("%s: the twin failed to generate samples; stopping", self.name)
                return
            if len(s) == 0:
                continue
            with self._clients_lock:
                listening = bool(self._streaming)
            if not listening:
                continue
            n = len(s)
            flags = np.where(s.saturated, FLAG_SATURATED, 0).astype(np.uint16)
            gyro = np.array(s.gyro_rps)
            if self._saturate:
                gyro[:, 0] = self.gyro_range_rps
                flags |= FLAG_SATURATED
            keep = (self._rng.random(n) >= self._drop_p) if self._drop_p > 0 else np.ones(n, bool)
            corrupt = ((self._rng.random(n) < self._corrupt_p) if self._corrupt_p > 0
                       else np.zeros(n, bool))
            corrupt &= keep
            self.injected.dropped += s.counter[~keep].tolist()
            self.injected.corrupted += s.counter[corrupt].tolist()
            if self._saturate:
                self.injected.saturated += s.counter[keep].tolist()
            self.injected.sent += int(np.count_nonzero(keep))
            self.injected.last_counter = int(s.counter[-1])
            samples = DecodedSamples(s.counter[keep], s.device_time_s[keep], gyro[keep],
                                     s.accel_mps2[keep], s.temperature_degc[keep], flags[keep])
            data = self.encode(samples, corrupt[keep])
            if time.monotonic() >= next_greeting:
                next_greeting += self.greeting_period_s
                data = self.greeting() + data
            with self._clients_lock:
                targets = list(self._streaming)
            for conn in targets:
                try:
                    conn.sendall(data)
                except OSError:
                    with self._clients_lock:
                        self._streaming.discard(conn)


class PacketImuServer(_ImuStreamServer):
    """The twin IMU `imu_name` as binary frames on 127.0.0.1.

    Parameters
    ----------
    rig : TwinRig
        The twin.
    time_base : SimTimeBase
        Shared simulated time.
    imu_name : str
        Which of the rig's IMUs.
    counts : bool
        Send int32 counts (with `gyro_scale_rps` / `accel_scale_mps2`) instead of float32 SI.
    gyro_scale_rps, accel_scale_mps2 : float
        SI value of one count. [rad/s], [m/s²]
    chunk_period_s : float
        Wall seconds between chunks. [s]
    greeting_period_s : float
        Wall seconds between repetitions of the info frame. [s]
    seed : int
        Seed of the fault hooks' random choices.
    port : int
        0: the OS picks.
    """

    def __init__(self, rig: TwinRig, time_base: SimTimeBase, imu_name: str, *,
                 counts: bool = False, gyro_scale_rps: float = 1e-7,
                 accel_scale_mps2: float = 1e-6, chunk_period_s: float = 0.02,
                 greeting_period_s: float = 1.0, seed: int = 0, port: int = 0) -> None:
        super().__init__("imu-packet-sim", rig, time_base, imu_name,
                         chunk_period_s=chunk_period_s, greeting_period_s=greeting_period_s,
                         seed=seed, port=port)
        self.counts = counts
        self.gyro_scale_rps, self.accel_scale_mps2 = gyro_scale_rps, accel_scale_mps2

    def greeting(self) -> bytes:
        """Return an info frame: model, serial, maker, nominal rate, format."""
        return encode_info({"model": "SIM-TWIN", "serial": self.imu_name, "maker": "imucalib",
                            "rate_hz": f"{self.model.sample_rate_hz:g}",
                            "format": "counts" if self.counts else "float"})

    def encode(self, samples: DecodedSamples, corrupt: np.ndarray) -> bytes:
        """Frames of `samples`; the `corrupt` ones get an inverted CRC."""
        data = encode_samples(samples.counter, samples.device_time_s, samples.gyro_rps,
                              samples.accel_mps2, samples.temperature_degc, samples.flags,
                              counts=self.counts, gyro_scale_rps=self.gyro_scale_rps,
                              accel_scale_mps2=self.accel_scale_mps2)
        if corrupt.any():
            buf = bytearray(data)
            for k in np.flatnonzero(corrupt):
                o = int(k) * SAMPLE_FRAME_SIZE + SAMPLE_FRAME_SIZE - 2
                buf[o] ^= 0xFF
                buf[o + 1] ^= 0xFF
            data = bytes(buf)
        return data


class CsvImuServer(_ImuStreamServer):
    """The twin IMU `imu_name` as CSV lines (gyro °/s, accel g) on 127.0.0.1.

    Parameters
    ----------
    rig, time_base, imu_name, chunk_period_s, greeting_period_s, seed, port
        As for :class:`PacketImuServer`.
    """

    def __init__(self, rig: TwinRig, time_base: SimTimeBase, imu_name: str, *,
                 chunk_period_s: float = 0.02, greeting_period_s: float = 1.0, seed: int = 0,
                 port: int = 0) -> None:
        super().__init__("imu-csv-sim", rig, time_base, imu_name, chunk_period_s=chunk_period_s,
                         greeting_period_s=greeting_period_s, seed=seed, port=port)

    def greeting(self) -> bytes:
        """Return a comment line with the identity, then the header line."""
        return (f"# model=SIM-TWIN;serial={self.imu_name};maker=imucalib;"
                f"rate_hz={self.model.sample_rate_hz:g}\n{format_header()}\n").encode("ascii")

    def encode(self, samples: DecodedSamples, corrupt: np.ndarray) -> bytes:
        """Lines of `samples`; the `corrupt` ones have a garbled field."""
        lines = format_lines(samples)
        for k in np.flatnonzero(corrupt):
            fields = lines[int(k)].split(",")
            fields[3] = "#?"
            lines[int(k)] = ",".join(fields)
        return ("\n".join(lines) + "\n").encode("ascii")
