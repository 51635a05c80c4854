"""The binary IMU frame: layout, CRC, and the streaming decoder's resync and fault counts."""

from __future__ import annotations

import binascii
import struct

import numpy as np
import pytest

from imucalib.drivers.imu_packet import (
    FLAG_SATURATED,
    FLAG_TEMPERATURE_INVALID,
    SAMPLE_FRAME_SIZE,
    CounterGaps,
    PacketDecoder,
    crc16_xmodem,
    encode_info,
    encode_samples,
)
from imucalib.errors import DeviceError, InvalidInputError


def _frames(n: int, start: int = 0) -> bytes:
    k = np.arange(start, start + n)
    return encode_samples(k, k * 0.01, np.outer(k, [0.1, 0.2, 0.3]) * 1e-3,
                          np.tile([0.0, 0.0, 9.80665], (n, 1)), np.full(n, 25.0))


def test_crc16_xmodem_known_vectors() -> None:
    assert crc16_xmodem(b"123456789") == 0x31C3 == binascii.crc_hqx(b"123456789", 0)
    assert crc16_xmodem(b"") == 0x0000
    assert crc16_xmodem(b"A") == 0x58E5


def test_frame_layout_literal_bytes() -> None:
    frame = encode_samples([7], [0.5], [[1.0, -2.0, 0.5]], [[0.0, 0.25, 9.75]], [25.5],
                           [FLAG_SATURATED])
    body = (bytes([0x01, 42]) + struct.pack("<IQ", 7, 500_000_000)
            + struct.pack("<3f", 1.0, -2.0, 0.5) + struct.pack("<3f", 0.0, 0.25, 9.75)
            + struct.pack("<fH", 25.5, 1))
    expected = b"\xaa\x55" + body + struct.pack("<H", binascii.crc_hqx(body, 0))
    assert len(frame) == SAMPLE_FRAME_SIZE == 48
    assert frame == expected


def test_counts_frame_literal_bytes_and_decode() -> None:
    frame = encode_samples([1], [0.0], [[1e-3, 0.0, 0.0]], [[0.0, 0.0, 9.8]], None,
                           counts=True, gyro_scale_rps=1e-6, accel_scale_mps2=1e-3)
    assert frame[2] == 0x02
    assert struct.unpack("<3i", frame[16:28]) == (1000, 0, 0)
    assert struct.unpack("<3i", frame[28:40]) == (0, 0, 9800)
    assert struct.unpack("<H", frame[44:46])[0] == FLAG_TEMPERATURE_INVALID
    dec = PacketDecoder(gyro_scale_rps=1e-6, accel_scale_mps2=1e-3)
    out = dec.feed(frame)
    np.testing.assert_allclose(out.gyro_rps, [[1e-3, 0.0, 0.0]])
    np.testing.assert_allclose(out.accel_mps2, [[0.0, 0.0, 9.8]])
    assert np.isnan(out.temperature_degc[0])
    with pytest.raises(DeviceError, match="no `gyro_scale_rps` / `accel_scale_mps2`"):
        PacketDecoder().feed(frame)


def test_decoder_round_trip_in_any_chunking() -> None:
    raw = encode_info({"model": "X1", "serial": "S-9"}) + _frames(20)
    for cut in range(1, len(raw)):
        dec = PacketDecoder()
        a, b = dec.feed(raw[:cut]), dec.feed(raw[cut:])
        counters = np.concatenate([a.counter, b.counter])
        assert counters.tolist() == list(range(20)), cut
        assert (dec.frames_ok, dec.crc_errors, dec.resyncs, dec.counter_gaps) == (20, 0, 0, 0)
        assert dec.info == {"model": "X1", "serial": "S-9"}
    out = PacketDecoder().feed(raw)
    np.testing.assert_allclose(out.device_time_s, np.arange(20) * 0.01)
    np.testing.assert_allclose(out.accel_mps2[:, 2], 9.80665, rtol=1e-7)
    np.testing.assert_allclose(out.temperature_degc, 25.0)


def test_decoder_counts_crc_errors_and_the_gaps_they_leave() -> None:
    raw = bytearray(_frames(30))
    for k in (3, 4, 17):  # two adjacent bad frames and one more
        raw[k * SAMPLE_FRAME_SIZE + 46] ^= 0xFF
    dec = PacketDecoder()
    out = dec.feed(bytes(raw))
    assert dec.crc_errors == 3
    assert dec.counter_gaps == 2 and dec.missing_samples == 3
    assert dec.resyncs == 0 and dec.frames_ok == 27
    assert 3 not in out.counter and 17 not in out.counter


def test_decoder_resynchronises_after_garbage() -> None:
    raw = _frames(10)
    garbage = b"\x00\xaa\x13\xaa\x55\x01\x07"  # includes a false sync
    dec = PacketDecoder()
    out = dec.feed(b"\x55\x55" + raw[:5 * 48] + garbage + raw[5 * 48:])
    assert out.counter.tolist() == list(range(10))
    assert dec.resyncs == 2 and dec.bytes_skipped == 2 + len(garbage)
    assert dec.crc_errors == 0 and dec.counter_gaps == 0


def test_decoder_false_sync_inside_damaged_frame_is_not_a_crc_error() -> None:
    raw = bytearray(_frames(4))
    raw[48 + 10:48 + 12] = b"\xaa\x55"  # sync bytes inside frame 1's data: CRC now fails
    dec = PacketDecoder()
    out = dec.feed(bytes(raw))
    assert out.counter.tolist() == [0, 2, 3]
    assert dec.crc_errors == 1  # frame 1 (followed by frame 2's sync); the false sync skipped


def test_counter_gaps_wrap_and_reset() -> None:
    gaps = CounterGaps(8)
    gaps.update(np.array([250, 251, 252, 253, 254, 255, 0, 1]))
    assert (gaps.counter_gaps, gaps.missing_samples) == (0, 0)
    gaps.update(np.array([4, 5]))  # 2, 3 lost
    assert (gaps.counter_gaps, gaps.missing_samples) == (1, 2)
    gaps.update(np.array([5]))  # a repeat
    gaps.update(np.array([200]))  # 195 ahead: more than half the wrap, taken as a reset
    assert (gaps.counter_gaps, gaps.missing_samples) == (3, 2)
    gaps.update(np.array([210]))  # 9 lost
    assert (gaps.counter_gaps, gaps.missing_samples) == (4, 11)


def test_encode_checks_inputs() -> None:
    with pytest.raises(InvalidInputError, match="`gyro` must have shape \\(2, 3\\); got \\(2,\\)"):
        encode_samples([0, 1], [0.0, 0.1], [1.0, 2.0], np.zeros((2, 3)))
    with pytest.raises(InvalidInputError, match="counts frames need `gyro_scale_rps`"):
        encode_samples([0], [0.0], np.zeros((1, 3)), np.zeros((1, 3)), counts=True)
    with pytest.raises(InvalidInputError, match="info text must be ≤ 255 bytes; got 302"):
        encode_info({"k": "x" * 300})
