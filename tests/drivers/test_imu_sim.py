"""IMU stream drivers against their simulator servers: samples, counters, injected faults."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import pytest

from imucalib import units
from imucalib.drivers import CsvLineImu, PacketImu
from imucalib.drivers.simulators import CsvImuServer, PacketImuServer, SimTimeBase
from imucalib.drivers.transport import open_transport
from imucalib.errors import DeviceError
from imucalib.sim.rig import TwinRig
from imucalib.station.devices import ImuBlock, ImuIdentity, ImuSource

from ._rigs import make_rig

RATE_HZ = 200.0


def start(rig: TwinRig, tb: SimTimeBase, servers: list[Any], kind: str, *,
          transport: str = "tcp") -> tuple[PacketImuServer | CsvImuServer, PacketImu | CsvLineImu]:
    ident = ImuIdentity("IMU-T1", model="SIM-TWIN", maker="imucalib", sample_rate_hz=RATE_HZ)
    if kind == "csv":
        csv_server = CsvImuServer(rig, tb, "IMU-T1", seed=3).start()
        servers.append(csv_server)
        url = f"tcp://127.0.0.1:{csv_server.port}"
        return csv_server, CsvLineImu(ident, lambda: open_transport(url), clock=tb, address=url)
    counts = kind == "counts"
    server = PacketImuServer(rig, tb, "IMU-T1", counts=counts, gyro_scale_rps=1e-7,
                             accel_scale_mps2=1e-6, seed=3).start()
    servers.append(server)
    url = (f"tcp://127.0.0.1:{server.port}" if transport == "tcp"
           else f"serial://socket://127.0.0.1:{server.port}")
    imu = PacketImu(ident, lambda: open_transport(url), clock=tb, address=url,
                    gyro_scale_rps=1e-7 if counts else None,
                    accel_scale_mps2=1e-6 if counts else None)
    return server, imu


def collect(imu: ImuSource, until_counter: int, timeout_s: float = 10.0) -> ImuBlock:
    """Read until a sample with a counter above `until_counter` arrived."""
    blocks = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        b = imu.read()
        if len(b):
            blocks.append(b)
            if b.counter[-1] > until_counter:
                break
        time.sleep(0.01)
    else:
        raise AssertionError(f"no counter above {until_counter} within {timeout_s} s")
    return ImuBlock(*(np.concatenate([getattr(b, f) for b in blocks]) for f in (
        "time_s", "device_time_s", "counter", "gyro_rps", "accel_mps2", "temperature_degc",
        "saturated")))


def runs(counters: list[int]) -> int:
    """Number of runs of consecutive counters (each run leaves one counter gap)."""
    c = sorted(counters)
    return sum(1 for k in range(len(c)) if k == 0 or c[k] != c[k - 1] + 1)


@pytest.mark.parametrize("kind, transport", [("float", "tcp"), ("counts", "tcp"),
                                             ("float", "serial"), ("csv", "tcp")])
def test_stream_matches_the_twin(kind: str, transport: str, time_base: SimTimeBase,
                                 servers: list[Any]) -> None:
    rig = make_rig(sample_rate_hz=RATE_HZ)
    _, imu = start(rig, time_base, servers, kind, transport=transport)
    assert isinstance(imu, ImuSource)
    t_connect = time_base.now_s()  # samples are stamped from the connection on
    imu.connect()
    ident = imu.identify(wait_s=2.0)
    # pyserial's socket:// discards what arrived before it opened: the first info frame may be
    # lost, and the server repeats it every second
    assert ident.name == "IMU-T1"
    if transport == "tcp":
        assert ident.extra["device_serial"] == "IMU-T1"
    time_base.sleep(2.0)
    b = imu.read()
    assert len(b) > 0.7 * 2.0 * RATE_HZ
    assert np.all(np.diff(b.counter) == 1)
    np.testing.assert_allclose(b.device_time_s, b.counter / RATE_HZ, atol=1e-6)
    assert np.all(np.diff(b.time_s) >= 0) and t_connect <= b.time_s[0]
    assert b.time_s[-1] <= time_base.now_s()
    # level and at rest: the accelerometer reads gravity on z, the gyro little
    np.testing.assert_allclose(np.linalg.norm(b.accel_mps2, axis=1), 9.806, rtol=0.01)
    assert np.all(np.abs(b.gyro_rps) < 0.5 * units.DEG)
    assert np.all(np.abs(b.gyro_rps.mean(axis=0)) < 0.05 * units.DEG)
    assert np.all((15.0 < b.temperature_degc) & (b.temperature_degc < 30.0))
    # the table turns the roll axis: the gyro x follows the twin
    with rig.lock:
        assert rig.table is not None
        rig.table.command_rate(1, 30 * units.DEG, time_base.now_s())
    time_base.sleep(2.0)
    imu.read()
    time_base.sleep(1.0)
    b = imu.read()
    assert np.abs(np.mean(b.gyro_rps[:, 0]) - 30 * units.DEG) < 0.3 * units.DEG
    h = imu.health()
    assert (h.crc_errors, h.counter_gaps, h.missing_samples) == (0, 0, 0)
    assert h.resyncs <= (0 if transport == "tcp" else 1)  # a discarded partial frame
    assert h.frames_ok > 0 and not b.saturated.any()
    imu.disconnect()


@pytest.mark.parametrize("kind", ["float", "csv"])
def test_crc_errors_and_gaps_equal_what_was_injected(kind: str, time_base: SimTimeBase,
                                                     servers: list[Any]) -> None:
    server, imu = start(make_rig(sample_rate_hz=RATE_HZ), time_base, servers, kind)
    imu.connect()
    time_base.sleep(0.5)
    server.set_corruption(0.05)
    server.set_drop_probability(0.03)
    time_base.sleep(4.0)
    server.set_corruption(0.0)
    server.set_drop_probability(0.0)
    time.sleep(0.1)  # a chunk in flight may still carry faults
    stop = server.injected.last_counter
    b = collect(imu, stop)
    corrupted, dropped = server.injected.corrupted, server.injected.dropped
    assert len(corrupted) > 5 and len(dropped) > 3
    h = imu.health()
    assert h.crc_errors == len(corrupted)
    # a sample lost before the first one received leaves no counter gap
    lost = [c for c in corrupted + dropped if c > b.counter[0]]
    assert h.missing_samples == len(lost)
    assert h.counter_gaps == runs(lost)
    assert not set(b.counter.tolist()) & set(corrupted + dropped)
    imu.disconnect()


def test_saturation_flags(time_base: SimTimeBase, servers: list[Any]) -> None:
    server, imu = start(make_rig(sample_rate_hz=RATE_HZ), time_base, servers, "float")
    imu.connect()
    time_base.sleep(0.5)
    server.saturate(True)
    time_base.sleep(1.0)
    server.saturate(False)
    time.sleep(0.1)
    b = collect(imu, server.injected.last_counter + 20)
    hit = np.isin(b.counter, server.injected.saturated)
    assert hit.sum() > 100
    np.testing.assert_array_equal(b.saturated, hit)
    np.testing.assert_allclose(b.gyro_rps[hit, 0], server.gyro_range_rps, rtol=1e-6)
    assert np.all(np.abs(b.gyro_rps[~hit, 0]) < 0.5 * units.DEG)


def test_dropped_stream_raises_after_the_buffered_samples(time_base: SimTimeBase,
                                                          servers: list[Any]) -> None:
    server, imu = start(make_rig(sample_rate_hz=RATE_HZ), time_base, servers, "float")
    imu.connect()
    deadline = time.monotonic() + 5.0
    while imu.health().frames_ok < 50 and time.monotonic() < deadline:
        time.sleep(0.01)
    server.drop_connections()
    time.sleep(0.1)
    assert len(imu.read()) >= 50  # what arrived before the drop
    with pytest.raises(DeviceError, match=r"IMU-T1: stream lost: .*connection closed by the "
                                          r"device"):
        imu.read()
    imu.connect()  # starts over
    time_base.sleep(1.0)
    assert len(imu.read()) > 0 and imu.health().crc_errors == 0
    imu.disconnect()
    with pytest.raises(DeviceError, match="IMU-T1: not connected; call connect\\(\\)"):
        imu.read()
