"""Our binary IMU frame: encoder, and a streaming decoder that resynchronises and counts faults.

This is the frame an MCU bridge (docs/drivers.md, "Sources": SPI burst, time stamp,
CRC-framed packets over USB-CDC or TCP) sends, and the frame that
:class:`~imucalib.drivers.simulators.PacketImuServer` streams. Pure: no I/O.

Frame layout (little-endian, 48 bytes for a sample)
---------------------------------------------------
======  ====  =============  ===============================================================
offset  size  type           field
======  ====  =============  ===============================================================
0       2     u8, u8         sync bytes ``0xAA 0x55``
2       1     u8             kind: 0x01 sample, float32 SI; 0x02 sample, int32 counts;
                             0x10 info text
3       1     u8             body length L (bytes from offset 4 up to the CRC): 42 for samples
4       4     u32            sample counter (wraps at 2³²; gaps are lost samples)
8       8     u64            device time [ns] (the IMU's own clock)
16      12    3 × f32/i32    gyro x, y, z [rad/s] (kind 0x01) or counts (kind 0x02)
28      12    3 × f32/i32    accel x, y, z [m/s²] (kind 0x01) or counts (kind 0x02)
40      4     f32            internal temperature [°C] (NaN: none)
44      2     u16            status flags: bit 0 saturated (a channel at its range),
                             bit 1 temperature invalid; bits 2–15 reserved (passed through)
46      2     u16            CRC-16-CCITT (XMODEM: poly 0x1021, init 0) of bytes 2–45,
                             ``binascii.crc_hqx(frame[2:46], 0)``
======  ====  =============  ===============================================================

An info frame (kind 0x10) carries L ≤ 255 bytes of UTF-8 ``key=value;key=value`` (model, serial,
firmware, …) and its CRC over bytes 2 … 4+L−1; a device sends it on connect.

Decoding
--------
:class:`PacketDecoder` takes chunks as they arrive, finds the sync bytes, checks header and CRC,
and decodes every run of consecutive sample frames at once with ``np.frombuffer`` on a structured
dtype. A frame whose CRC fails is dropped and counted when the next frame starts right after it
(otherwise its sync bytes were data: the decoder skips a byte and searches again); every search
that skips bytes counts one resync. Counter jumps other than +1 count as gaps, with the samples
they imply missing.

Contents
--------
:data:`SYNC`, :data:`SAMPLE_FRAME_SIZE`, :data:`KIND_FLOAT`, :data:`KIND_COUNTS`,
:data:`KIND_INFO`, :data:`FLAG_SATURATED`, :data:`FLAG_TEMPERATURE_INVALID`,
:func:`encode_samples`, :func:`encode_info`, :class:`DecodedSamples`, :class:`PacketDecoder`,
:class:`CounterGaps`, :func:`crc16_xmodem`.
"""

from __future__ import annotations

import binascii
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imucalib._checks import as_array
from imucalib.errors import DeviceError, InvalidInputError

__all__ = [
    "FLAG_SATURATED",
    "FLAG_TEMPERATURE_INVALID",
    "KIND_COUNTS",
    "KIND_FLOAT",
    "KIND_INFO",
    "SAMPLE_BODY_LENGTH",
    "SAMPLE_FRAME_SIZE",
    "SYNC",
    "CounterGaps",
    "DecodedSamples",
    "PacketDecoder",
    "crc16_xmodem",
    "encode_info",
    "encode_samples",
]

SYNC = b"\xaa\x55"
KIND_FLOAT, KIND_COUNTS, KIND_INFO = 0x01, 0x02, 0x10
SAMPLE_BODY_LENGTH = 42
SAMPLE_FRAME_SIZE = 4 + SAMPLE_BODY_LENGTH + 2
FLAG_SATURATED, FLAG_TEMPERATURE_INVALID = 0x0001, 0x0002
_SYNC_U16 = 0x55AA  # the two sync bytes read as a little-endian u16


def _sample_dtype(value: str) -> np.dtype:
    return np.dtype([("sync", "<u2"), ("kind", "u1"), ("length", "u1"), ("counter", "<u4"),
                     ("time_ns", "<u8"), ("gyro", value, (3,)), ("accel", value, (3,)),
                     ("temperature", "<f4"), ("flags", "<u2"), ("crc", "<u2")])


_DT_FLOAT = _sample_dtype("<f4")
_DT_COUNTS = _sample_dtype("<i4")
assert _DT_FLOAT.itemsize == SAMPLE_FRAME_SIZE == _DT_COUNTS.itemsize  # layout sanity


def crc16_xmodem(data: bytes | bytearray | memoryview) -> int:
    """CRC-16-CCITT, XMODEM variant (poly 0x1021, init 0, no reflection, no final XOR).

    Examples
    --------
    >>> hex(crc16_xmodem(b"123456789"))
    '0x31c3'
    """
    return binascii.crc_hqx(data, 0)


def _frame_crcs(raw: bytes | memoryview, offsets: range) -> NDArray[np.uint16]:
    """CRC of each sample frame starting at `offsets` (C speed per frame, ≈0.3 µs)."""
    mv, crc, n = memoryview(raw), binascii.crc_hqx, SAMPLE_FRAME_SIZE - 4
    return np.array([crc(mv[o:o + n], 0) for o in range(offsets.start + 2, offsets.stop + 2,
                                                         offsets.step)], dtype=np.uint16)


def encode_samples(counter: ArrayLike, device_time_s: ArrayLike, gyro: ArrayLike,
                   accel: ArrayLike, temperature_degc: ArrayLike | None = None,
                   flags: ArrayLike | None = None, *, counts: bool = False,
                   gyro_scale_rps: float | None = None,
                   accel_scale_mps2: float | None = None) -> bytes:
    """Encode samples as consecutive frames.

    Parameters
    ----------
    counter : array_like of int, shape (n,)
        Sample counters (taken modulo 2³²).
    device_time_s : array_like, shape (n,)
        Device time stamps, ≥ 0. [s]
    gyro, accel : array_like, shape (n, 3)
        Outputs in SI. [rad/s], [m/s²]
    temperature_degc : array_like, shape (n,), optional
        Internal temperature (NaN or None: none; sets the temperature-invalid flag). [°C]
    flags : array_like of int, shape (n,), optional
        Status flags (:data:`FLAG_SATURATED` …).
    counts : bool
        Send int32 counts (kind 0x02) instead of float32 SI (kind 0x01).
    gyro_scale_rps, accel_scale_mps2 : float, optional
        SI value of one count (required with `counts`). [rad/s], [m/s²]

    Returns
    -------
    bytes
        n · 48 bytes.
    """
    c = np.asarray(counter, dtype=np.int64)
    n = c.shape[0]
    t = as_array(device_time_s, "device_time_s", shape=(n,))
    g = as_array(gyro, "gyro", shape=(n, 3))
    a = as_array(accel, "accel", shape=(n, 3))
    temp = (np.full(n, np.nan) if temperature_degc is None
            else as_array(temperature_degc, "temperature_degc", shape=(n,), allow_nan=True))
    fl = np.zeros(n, dtype=np.uint16) if flags is None else np.asarray(flags, dtype=np.uint16)
    if np.any(t < 0):
        raise InvalidInputError("`device_time_s` must be ≥ 0")
    arr = np.zeros(n, dtype=_DT_COUNTS if counts else _DT_FLOAT)
    arr["sync"], arr["length"] = _SYNC_U16, SAMPLE_BODY_LENGTH
    arr["kind"] = KIND_COUNTS if counts else KIND_FLOAT
    arr["counter"] = (c % (1 << 32)).astype(np.uint32)
    arr["time_ns"] = np.round(t * 1e9).astype(np.uint64)
    if counts:
        if not gyro_scale_rps or not accel_scale_mps2:
            raise InvalidInputError("counts frames need `gyro_scale_rps` and `accel_scale_mps2`")
        lim = np.iinfo(np.int32)
        arr["gyro"] = np.clip(np.round(g / gyro_scale_rps), lim.min, lim.max)
        arr["accel"] = np.clip(np.round(a / accel_scale_mps2), lim.min, lim.max)
    else:
        arr["gyro"], arr["accel"] = g, a
    arr["temperature"] = temp
    arr["flags"] = fl | np.where(np.isnan(temp), FLAG_TEMPERATURE_INVALID, 0).astype(np.uint16)
    raw = arr.tobytes()
    arr["crc"] = _frame_crcs(raw, range(0, n * SAMPLE_FRAME_SIZE, SAMPLE_FRAME_SIZE))
    return arr.tobytes()


def encode_info(fields: dict[str, str]) -> bytes:
    """Encode an info frame carrying ``key=value;…`` (at most 255 bytes of UTF-8).

    Raises
    ------
    InvalidInputError
        If the text is longer than 255 bytes or a key or value holds ``=`` or ``;``.
    """
    for k, v in fields.items():
        if any(ch in f"{k}{v}" for ch in "=;"):
            raise InvalidInputError(f"info field {k!r}={v!r} must not contain '=' or ';'")
    body = ";".join(f"{k}={v}" for k, v in fields.items()).encode("utf-8")
    if len(body) > 255:
        raise InvalidInputError(f"info text must be ≤ 255 bytes; got {len(body)}")
    head = bytes([KIND_INFO, len(body)]) + body
    return SYNC + head + crc16_xmodem(head).to_bytes(2, "little")


@dataclass(frozen=True, eq=False)
class DecodedSamples:
    """Samples decoded from frames, in arrival order.

    Attributes
    ----------
    counter : ndarray of int64, shape (n,)
    device_time_s : ndarray, shape (n,)
        [s]
    gyro_rps, accel_mps2 : ndarray, shape (n, 3)
        [rad/s], [m/s²]
    temperature_degc : ndarray, shape (n,)
        [°C] (NaN where invalid)
    flags : ndarray of uint16, shape (n,)
    """

    counter: NDArray[np.int64]
    device_time_s: NDArray[np.float64]
    gyro_rps: NDArray[np.float64]
    accel_mps2: NDArray[np.float64]
    temperature_degc: NDArray[np.float64]
    flags: NDArray[np.uint16]

    def __len__(self) -> int:
        return int(self.counter.shape[0])

    @property
    def saturated(self) -> NDArray[np.bool_]:
        """Whether each sample carries the saturation flag."""
        return (self.flags & FLAG_SATURATED) != 0

    @staticmethod
    def concatenate(parts: list[DecodedSamples]) -> DecodedSamples:
        """Join blocks in order (an empty block for no parts)."""
        if not parts:
            return DecodedSamples(np.zeros(0, np.int64), np.zeros(0), np.zeros((0, 3)),
                                  np.zeros((0, 3)), np.zeros(0), np.zeros(0, np.uint16))
        if len(parts) == 1:
            return parts[0]
        return DecodedSamples(*(np.concatenate([getattr(p, f) for p in parts]) for f in
                                ("counter", "device_time_s", "gyro_rps", "accel_mps2",
                                 "temperature_degc", "flags")))


class CounterGaps:
    """Count jumps of a wrapping sample counter across blocks.

    Parameters
    ----------
    counter_bits : int
        Counter width; it wraps at 2**counter_bits.

    Attributes
    ----------
    counter_gaps : int
        Jumps other than +1 (a repeat or a reset counts as a gap without missing samples).
    missing_samples : int
        Samples implied missing by forward jumps of less than half the wrap.
    """

    def __init__(self, counter_bits: int = 32) -> None:
        if not 1 <= int(counter_bits) <= 63:
            raise InvalidInputError(f"`counter_bits` must be in 1–63; got {counter_bits}")
        self._wrap = 1 << int(counter_bits)
        self._last: int | None = None
        self.counter_gaps = 0
        self.missing_samples = 0

    def update(self, counter: NDArray[np.int64]) -> None:
        """Account for the next block of counters (in arrival order)."""
        if counter.shape[0] == 0:
            return
        c = np.asarray(counter, dtype=np.int64)
        prev = c[:-1] if self._last is None else np.concatenate(([self._last], c[:-1]))
        nxt = c if self._last is not None else c[1:]
        diff = (nxt - prev) % self._wrap
        gap = diff != 1
        self.counter_gaps += int(np.count_nonzero(gap))
        plausible = gap & (diff > 1) & (diff < self._wrap // 2)
        self.missing_samples += int(np.sum(diff[plausible] - 1))
        self._last = int(c[-1])


class PacketDecoder:
    """Streaming decoder of the frame in the module docstring.

    Parameters
    ----------
    gyro_scale_rps, accel_scale_mps2 : float, optional
        SI value of one count, for int32 frames (kind 0x02). [rad/s], [m/s²]
    counter_bits : int
        Width of the device counter (wrap for the gap count).

    Attributes
    ----------
    frames_ok, crc_errors, resyncs, bytes_skipped : int
        Cumulative counters (:class:`~imucalib.station.devices.ImuHealth`); ``counter_gaps``
        and ``missing_samples`` are properties reading :attr:`gaps`.
    gaps : CounterGaps
        The counter-gap account.
    info : dict of str to str
        Fields of the info frames received so far (later ones win).
    """

    def __init__(self, *, gyro_scale_rps: float | None = None,
                 accel_scale_mps2: float | None = None, counter_bits: int = 32) -> None:
        self.gyro_scale_rps = gyro_scale_rps
        self.accel_scale_mps2 = accel_scale_mps2
        self.gaps = CounterGaps(counter_bits)
        self._buf = b""
        self._skipping = False
        self.frames_ok = self.crc_errors = self.resyncs = self.bytes_skipped = 0
        self.info: dict[str, str] = {}

    @property
    def counter_gaps(self) -> int:
        """Counter jumps other than +1 so far."""
        return self.gaps.counter_gaps

    @property
    def missing_samples(self) -> int:
        """Samples implied missing by those jumps."""
        return self.gaps.missing_samples

    def _skip(self, n: int) -> None:
        if n <= 0:
            return
        self.bytes_skipped += n
        if not self._skipping:
            self.resyncs += 1
            self._skipping = True

    def feed(self, data: bytes) -> DecodedSamples:
        """Decode what `data` completes; keep an incomplete tail for the next call.

        Raises
        ------
        DeviceError
            If a counts frame arrives and no scale factors were given.
        """
        raw = self._buf + bytes(data)
        n, p = len(raw), 0
        parts: list[DecodedSamples] = []
        while True:
            q = raw.find(SYNC, p)
            if q < 0:
                keep = 1 if raw[-1:] == SYNC[:1] else 0
                self._skip(n - keep - p)
                p = max(p, n - keep)
                break
            self._skip(q - p)
            p = q
            if n - p < 4:
                break
            kind, length = raw[p + 2], raw[p + 3]
            if (kind in (KIND_FLOAT, KIND_COUNTS) and length != SAMPLE_BODY_LENGTH) or \
                    kind not in (KIND_FLOAT, KIND_COUNTS, KIND_INFO):
                self._skip(1)
                p += 1
                continue
            total = 4 + length + 2
            if n - p < total:
                break
            if kind == KIND_INFO:
                body = raw[p + 2:p + 4 + length]
                crc = int.from_bytes(raw[p + 4 + length:p + total], "little")
                if crc16_xmodem(body) == crc:
                    self._take_info(body[2:])
                    self._skipping = False
                    p += total
                    continue
            else:
                block, used = self._decode_run(raw, p)
                if used:
                    parts.append(block)
                    p += used
                    continue
            # the frame at p failed its CRC: a frame when the next one starts right after it
            if n - p < total + 2:
                break
            if raw[p + total:p + total + 2] == SYNC:
                self.crc_errors += 1
                self._skipping = False
                p += total
            else:
                self._skip(1)
                p += 1
        self._buf = raw[p:]
        return DecodedSamples.concatenate(parts)

    def _decode_run(self, raw: bytes, p: int) -> tuple[DecodedSamples, int]:
        """Decode the run of good sample frames starting at `p`; return it and its byte size."""
        m = (len(raw) - p) // SAMPLE_FRAME_SIZE
        arr = np.frombuffer(raw, dtype=_DT_FLOAT, count=m, offset=p)
        head_ok = (arr["sync"] == _SYNC_U16) & (arr["length"] == SAMPLE_BODY_LENGTH) & (
            (arr["kind"] == KIND_FLOAT) | (arr["kind"] == KIND_COUNTS))
        k = m if head_ok.all() else int(np.argmin(head_ok))
        crcs = _frame_crcs(raw, range(p, p + k * SAMPLE_FRAME_SIZE, SAMPLE_FRAME_SIZE))
        good = crcs == arr["crc"][:k]
        j = k if good.all() else int(np.argmin(good))
        if j == 0:
            return DecodedSamples.concatenate([]), 0
        arr = arr[:j]
        gyro = arr["gyro"].astype(np.float64)
        accel = arr["accel"].astype(np.float64)
        is_counts = arr["kind"] == KIND_COUNTS
        if is_counts.any():
            if not self.gyro_scale_rps or not self.accel_scale_mps2:
                raise DeviceError("received int32-count IMU frames but no `gyro_scale_rps` / "
                                  "`accel_scale_mps2` is configured")
            ints = np.frombuffer(raw, dtype=_DT_COUNTS, count=j, offset=p)
            gyro[is_counts] = ints["gyro"][is_counts] * float(self.gyro_scale_rps)
            accel[is_counts] = ints["accel"][is_counts] * float(self.accel_scale_mps2)
        counter = arr["counter"].astype(np.int64)
        self.gaps.update(counter)
        self.frames_ok += j
        self._skipping = False
        out = DecodedSamples(counter, arr["time_ns"].astype(np.float64) * 1e-9, gyro, accel,
                             arr["temperature"].astype(np.float64), arr["flags"].copy())
        return out, j * SAMPLE_FRAME_SIZE

    def _take_info(self, body: bytes) -> None:
        text = body.decode("utf-8", errors="replace")
        for item in text.split(";"):
            key, sep, value = item.partition("=")
            if sep and key.strip():
                self.info[key.strip()] = value.strip()
