"""Station time stamps of streamed IMU samples: device time plus the lower envelope of offsets."""

from __future__ import annotations

import numpy as np

from imucalib.drivers.imu_packet import PacketDecoder, encode_samples
from imucalib.drivers.imus import PacketImu
from imucalib.station.devices import ImuIdentity

RATE_HZ = 200.0
OFFSET_S = 100.0  # station time − device time, plus the smallest delay


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def now_s(self) -> float:
        return self.t


def chunks(n_chunks: int, per_chunk: int, delays_s: np.ndarray):
    """(arrival time, decoded chunk) pairs: chunk k's last sample arrives delays_s[k] late."""
    dec = PacketDecoder()
    k0 = 0
    for k in range(n_chunks):
        counter = np.arange(k0, k0 + per_chunk)
        dev = counter / RATE_HZ
        raw = encode_samples(counter, dev, np.zeros((per_chunk, 3)), np.zeros((per_chunk, 3)))
        samples = dec.feed(raw)
        yield OFFSET_S + dev[-1] + delays_s[k], samples
        k0 += per_chunk


def stamp(imu: PacketImu, pairs) -> np.ndarray:
    return np.concatenate([imu._back_dated(t, s) for t, s in pairs])


def make_imu() -> PacketImu:
    ident = ImuIdentity(name="IMU-T", sample_rate_hz=RATE_HZ)
    return PacketImu(ident, lambda: None, clock=Clock())  # never connected: no transport


def test_delay_spikes_move_no_sample():
    rng = np.random.default_rng(3)
    delays = 0.002 + rng.exponential(0.003, 400)
    delays[[50, 51, 200]] = [0.35, 0.2, 0.15]  # a loaded host: late chunks
    t = stamp(make_imu(), list(chunks(400, 20, delays)))
    dt = np.diff(t)
    # evenly spaced at the device's period: no gap, no bunching (the old per-chunk stamping
    # opened a 0.35 s gap at chunk 50 and bunched the samples after it)
    assert np.abs(dt - 1 / RATE_HZ).max() < 0.004
    # and within the smallest delay seen of device time + offset, after the first chunks
    dev = np.arange(t.size) / RATE_HZ
    assert np.abs(t[200:] - (dev[200:] + OFFSET_S + delays.min())).max() < 0.005


def test_window_follows_a_drifting_device_clock():
    """A device clock 200 ppm fast: the offset is re-estimated within the window."""
    n_chunks, per = 3000, 20  # 300 s of device time
    delays = np.full(n_chunks, 0.001)
    pairs = []
    for (t_arr, s), k in zip(chunks(n_chunks, per, delays), range(n_chunks), strict=True):
        dev_last = (k + 1) * per / RATE_HZ - 1 / RATE_HZ
        pairs.append((t_arr + 200e-6 * dev_last, s))  # station time runs 200 ppm ahead
    imu = make_imu()
    t = stamp(imu, pairs)
    dev = np.arange(t.size) / RATE_HZ
    truth = OFFSET_S + 0.001 + dev * (1 + 200e-6)
    # the lag of a 10 s window at 200 ppm is at most 2 ms
    assert np.abs(t - truth).max() < 0.0025
