"""Driver throughput: IMU frame and CSV decoding, and ACL round trips over loopback.

Run: ``.venv/bin/python bench/bench_drivers.py``. Prints rates and, for the frame decoder, the
ratio against a straightforward per-frame ``struct.unpack`` decoder run in the same process (the
peer a hand-written driver would be). Nothing is asserted: speed is reported, not tested.
"""

from __future__ import annotations

import binascii
import struct
import time

import numpy as np

from imucalib.drivers.imu_csv import CsvLineDecoder, format_header, format_lines
from imucalib.drivers.imu_packet import (
    SAMPLE_FRAME_SIZE,
    SYNC,
    DecodedSamples,
    PacketDecoder,
    encode_samples,
)

N = 200_000
CHUNKS = (4096, 65536)


def _samples(n: int) -> DecodedSamples:
    rng = np.random.default_rng(1)
    k = np.arange(n)
    accel = rng.normal(0, 0.01, (n, 3))
    accel[:, 2] += 9.8
    return DecodedSamples(k, k * 1e-3, rng.normal(0, 0.01, (n, 3)), accel, np.full(n, 25.0),
                          np.zeros(n, np.uint16))


def _per_frame(raw: bytes) -> int:
    """A per-frame decoder: find sync, check CRC, struct.unpack each frame."""
    fmt = struct.Struct("<IQ3f3ffH")
    out, p, n = [], 0, len(raw)
    while p + SAMPLE_FRAME_SIZE <= n:
        if raw[p:p + 2] != SYNC:
            p += 1
            continue
        frame = raw[p:p + SAMPLE_FRAME_SIZE]
        if binascii.crc_hqx(frame[2:46], 0) == int.from_bytes(frame[46:48], "little"):
            out.append(fmt.unpack_from(frame, 4))
        p += SAMPLE_FRAME_SIZE
    return len(out)


def _timed(fn, *args):  # type: ignore[no-untyped-def]
    t0 = time.perf_counter()
    result = fn(*args)
    return result, time.perf_counter() - t0


def bench_frames() -> None:
    s = _samples(N)
    raw = encode_samples(s.counter, s.device_time_s, s.gyro_rps, s.accel_mps2,
                         s.temperature_degc, s.flags)

    def chunked(chunk: int) -> int:
        dec = PacketDecoder()
        return sum(len(dec.feed(raw[i:i + chunk])) for i in range(0, len(raw), chunk))

    n_peer, t_peer = _timed(_per_frame, raw)
    print(f"IMU frames, per-frame struct.unpack peer: {N / t_peer / 1e6:6.2f} M frames/s")
    for chunk in CHUNKS:
        n_ours, t_ours = _timed(chunked, chunk)
        assert n_ours == n_peer == N
        print(f"IMU frames, PacketDecoder ({chunk:5d}-byte chunks): {N / t_ours / 1e6:6.2f} "
              f"M frames/s, {t_peer / t_ours:4.1f}× the peer")
    _, t_enc = _timed(encode_samples, s.counter, s.device_time_s, s.gyro_rps, s.accel_mps2,
                      s.temperature_degc, s.flags)
    print(f"IMU frame encoding (simulator side): {N / t_enc / 1e6:6.2f} M frames/s")


def bench_csv() -> None:
    n = N // 4
    text = (format_header() + "\n" + "\n".join(format_lines(_samples(n))) + "\n").encode()

    def chunked(chunk: int) -> int:
        dec = CsvLineDecoder()
        return sum(len(dec.feed(text[i:i + chunk])) for i in range(0, len(text), chunk))

    for chunk in CHUNKS:
        got, t = _timed(chunked, chunk)
        assert got == n
        print(f"CSV lines ({chunk:5d}-byte chunks): {n / t / 1e3:8.1f} k lines/s")


def bench_acl_round_trip() -> None:
    from imucalib.drivers import AcutrolTable, AxisLimits
    from imucalib.drivers.simulators import AclSimServer, SimTimeBase
    from imucalib.drivers.transport import open_transport
    from imucalib.sim.build import build_rig
    from imucalib.sim.scenario import load_scenario

    rig = build_rig(load_scenario("dual-axis-p1")).rig
    tb = SimTimeBase(1.0)
    with AclSimServer(rig, tb).start() as server:
        url = f"tcp://127.0.0.1:{server.port}"
        table = AcutrolTable("t", ["pitch", "roll"], lambda: open_transport(url), clock=tb,
                             limits=[AxisLimits(1.0, 1.0)] * 2)
        table.open_link()
        m = 2000
        _, t = _timed(lambda: [table.poll() for _ in range(m)])
        table.disconnect()
    print(f"ACL poll (:R:P? 1;P? 2;R? 1;R? 2) over loopback: {t / m * 1e6:7.1f} µs per poll")


if __name__ == "__main__":
    bench_frames()
    bench_csv()
    bench_acl_round_trip()
