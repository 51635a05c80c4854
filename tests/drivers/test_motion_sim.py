"""Motion drivers against their simulator servers over loopback, with the twin's truth behind."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from imucalib import units
from imucalib.drivers import AcutrolTable, AerosmithTable, AxisLimits
from imucalib.drivers.simulators import AclSimServer, AerosmithSimServer, SimTimeBase
from imucalib.drivers.transport import open_transport
from imucalib.errors import DeviceError, LimitExceededError
from imucalib.sim.rig import TwinRig
from imucalib.sim.table import SimRateTable

from ._rigs import make_rig

ARCSEC = units.ARCSEC
URLS = {"tcp": "tcp://127.0.0.1:{port}", "visa": "visa://TCPIP::127.0.0.1::{port}::SOCKET",
        "serial": "serial://socket://127.0.0.1:{port}?baud=9600"}


def start(rig: TwinRig, tb: SimTimeBase, servers: list[Any], dialect: str, transport: str,
          *, device: str = "table", rate_limit_dps: float | None = None
          ) -> tuple[AclSimServer | AerosmithSimServer, AcutrolTable | AerosmithTable]:
    cls = AclSimServer if dialect == "acutrol" else AerosmithSimServer
    server = cls(rig, tb, device=device).start()  # type: ignore[arg-type]
    servers.append(server)
    sim = server.sim
    limits = [AxisLimits((rate_limit_dps * units.DEG if rate_limit_dps else ax.max_rate_rps),
                         ax.max_accel_rps2) for ax in sim.spec.axes]
    url = URLS[transport].format(port=server.port)
    names = [ax.name for ax in sim.spec.axes]
    drv_cls = AcutrolTable if dialect == "acutrol" else AerosmithTable
    driver = drv_cls(device, names, lambda: open_transport(url), clock=tb, limits=limits,
                     address=url, role=device)
    return server, driver


def true_state(sim: SimRateTable, t: float) -> tuple[np.ndarray, np.ndarray]:
    angles = np.array([sim.axis_motion(i, np.array([t]))[0][0] for i in range(sim.n_axes)])
    rates = np.array([sim.axis_motion(i, np.array([t]))[1][0] for i in range(sim.n_axes)])
    return angles, rates


CASES = [("acutrol", "tcp"), ("acutrol", "visa"), ("aerosmith", "serial"), ("aerosmith", "tcp")]


@pytest.mark.parametrize("dialect, transport", CASES)
def test_table_moves_reads_back_and_stops(dialect: str, transport: str, table_rig: TwinRig,
                                          time_base: SimTimeBase, servers: list[Any]) -> None:
    server, table = start(table_rig, time_base, servers, dialect, transport,
                          rate_limit_dps=200.0)
    sim = server.sim
    table.connect()
    assert "SIM" in table.identify()
    assert table.status().interlock_closed
    table.move_to(0, np.pi / 2)
    table.move_to(1, np.pi)
    time_base.sleep(5.0)
    fb = table.poll()
    target = np.array([[np.pi / 2, np.pi]])
    assert np.all(np.abs(fb.angle_rad - target) < 5 * ARCSEC)
    truth, _ = true_state(sim, fb.time_s[0])
    assert np.all(np.abs(fb.angle_rad[0] - truth) < 3 * ARCSEC)  # encoder error ≈ 1.8″ peak
    assert np.all(np.abs(fb.rate_rps[0]) < 0.01 * units.DEG)
    table.set_rate(1, 50 * units.DEG)
    time_base.sleep(3.0)
    fb = table.poll()
    assert abs(fb.rate_rps[0, 1] - 50 * units.DEG) < 0.01 * units.DEG
    assert abs(true_state(sim, fb.time_s[0])[1][1] - 50 * units.DEG) < 0.01 * units.DEG
    st = table.status()
    assert st.modes == ("position", "rate") and st.interlock_closed and st.fault is None
    # software limits: refused before anything is sent
    lines = server.lines_received
    with pytest.raises(LimitExceededError, match="axis 'roll': rate 250 °/s exceeds the "
                                                 "software limit ±200 °/s; nothing was sent"):
        table.set_rate(1, 250 * units.DEG)
    assert server.lines_received == lines
    # poll time stamps: increasing
    stamps = [table.poll().time_s[0] for _ in range(5)]
    assert np.all(np.diff(stamps) > 0)
    table.safe_stop()
    time_base.sleep(0.5)  # the servo's last transient
    t = time_base.now_s()
    _, rates = true_state(sim, t)
    assert np.all(np.abs(rates) < 1e-3 * units.DEG)
    assert [sim.mode(i, t) for i in range(2)] == ["off", "off"]
    st = table.status()
    assert st.modes == ("off", "off") and not st.interlock_closed
    table.disconnect()


def test_dropped_connection_raises_then_safe_stop_recovers(
        table_rig: TwinRig, time_base: SimTimeBase, servers: list[Any]) -> None:
    server, table = start(table_rig, time_base, servers, "acutrol", "tcp")
    table.connect()
    table.set_rate(0, 30 * units.DEG)
    time_base.sleep(1.0)
    assert server.drop_connections() == 1
    with pytest.raises(DeviceError, match=r"connection closed by the device|connection lost"):
        table.poll()
    with pytest.raises(DeviceError, match="not connected \\(link lost"):
        table.set_rate(0, 0.0)
    table.safe_stop()  # reconnects once and stops
    time_base.sleep(0.5)
    t = time_base.now_s()
    assert abs(true_state(server.sim, t)[1][0]) < 1e-3 * units.DEG
    assert server.sim.mode(0, t) == "off"
    assert server.connections_accepted == 2


def test_safe_stop_without_a_controller_never_raises(
        table_rig: TwinRig, time_base: SimTimeBase, servers: list[Any]) -> None:
    server, table = start(table_rig, time_base, servers, "acutrol", "tcp")
    table.connect()
    server.close()
    table.safe_stop()
    with pytest.raises(DeviceError):
        table.poll()


@pytest.mark.parametrize("dialect", ["acutrol", "aerosmith"])
def test_interlock_fault_latched_reported_and_refusing(
        dialect: str, table_rig: TwinRig, time_base: SimTimeBase, servers: list[Any]) -> None:
    server, table = start(table_rig, time_base, servers, dialect, "tcp")
    table.connect()
    table.set_rate(0, 20 * units.DEG)
    time_base.sleep(1.0)
    server.inject_interlock_fault("emergency stop pressed", code=301)
    st = table.status()
    assert not st.interlock_closed and st.modes == ("off", "off")
    expected = ("interlock fault 301: emergency stop pressed" if dialect == "acutrol"
                else "axis 'pitch': emergency stop pressed; axis 'roll': emergency stop pressed")
    assert st.fault == expected
    with pytest.raises(DeviceError, match=r"201|servo off|fault"):
        table.set_rate(0, 10 * units.DEG)
    with pytest.raises(DeviceError, match="emergency stop pressed"):
        table.connect()  # the cause is still active: the interlock cannot close
    time_base.sleep(2.0)
    assert abs(true_state(server.sim, time_base.now_s())[1][0]) < 1e-3 * units.DEG
    server.clear_fault_cause()
    table.connect()  # reset clears the latch, the interlock closes
    st = table.status()
    assert st.fault is None and st.interlock_closed


@pytest.mark.parametrize("dialect", ["acutrol", "aerosmith"])
def test_drift_past_5_arcsec_is_seen_and_corrected(
        dialect: str, table_rig: TwinRig, time_base: SimTimeBase, servers: list[Any]) -> None:
    server, table = start(table_rig, time_base, servers, dialect, "tcp")
    table.connect()
    table.move_to(0, 0.0)
    time_base.sleep(2.0)
    assert abs(table.poll().angle_rad[0, 0]) < 3 * ARCSEC
    server.inject_drift(0, 20 * ARCSEC, duration_s=2.0)
    time_base.sleep(4.0)
    fb = table.poll()
    assert 15 * ARCSEC < fb.angle_rad[0, 0] < 25 * ARCSEC  # past the 5″ guard
    assert true_state(server.sim, fb.time_s[0])[0][0] > 15 * ARCSEC  # the axis really moved
    table.move_to(0, 0.0)  # automatic correction
    time_base.sleep(2.0)
    assert abs(table.poll().angle_rad[0, 0]) < 3 * ARCSEC


@pytest.mark.parametrize("dialect", ["acutrol", "aerosmith"])
def test_rate_error_past_half_dps_is_seen(
        dialect: str, table_rig: TwinRig, time_base: SimTimeBase, servers: list[Any]) -> None:
    server, table = start(table_rig, time_base, servers, dialect, "tcp")
    table.connect()
    table.set_rate(1, 50 * units.DEG)
    time_base.sleep(2.0)
    server.inject_rate_error(1, 0.8 * units.DEG)
    time_base.sleep(2.0)
    fb = table.poll()
    assert fb.rate_rps[0, 1] == pytest.approx(50.8 * units.DEG, abs=0.01 * units.DEG)
    server.clear_faults()
    time_base.sleep(2.0)
    assert table.poll().rate_rps[0, 1] == pytest.approx(50 * units.DEG, abs=0.01 * units.DEG)
    table.safe_stop()


def test_feedback_offset_is_an_encoder_fault_only(
        table_rig: TwinRig, time_base: SimTimeBase, servers: list[Any]) -> None:
    server, table = start(table_rig, time_base, servers, "acutrol", "tcp")
    table.connect()
    server.offset_feedback(1, angle_rad=10 * ARCSEC, rate_rps=0.6 * units.DEG)
    fb = table.poll()
    truth = true_state(server.sim, fb.time_s[0])
    assert fb.angle_rad[0, 1] - truth[0][1] == pytest.approx(10 * ARCSEC, abs=3 * ARCSEC)
    assert fb.rate_rps[0, 1] == pytest.approx(0.6 * units.DEG, abs=1e-4)
    assert abs(truth[1][1]) < 1e-6
    assert server.injected.feedback_offsets == [(1, 10 * ARCSEC, 0.6 * units.DEG)]


@pytest.mark.parametrize("dialect", ["acutrol", "aerosmith"])
def test_centrifuge_spins_and_stops(dialect: str, time_base: SimTimeBase,
                                    servers: list[Any]) -> None:
    rig = make_rig(table="none", centrifuge=True)
    _, fuge = start(rig, time_base, servers, dialect, "tcp", device="centrifuge")
    assert fuge.axis_names == ("spin",)
    fuge.connect()
    fuge.set_rate(0, 120 * units.DEG)
    time_base.sleep(8.0)
    fb = fuge.poll()
    assert fb.rate_rps[0, 0] == pytest.approx(120 * units.DEG, abs=0.01 * units.DEG)
    with pytest.raises(DeviceError, match="only be positioned at rest"):
        fuge.move_to(0, 0.0)
    fuge.safe_stop()
    time_base.sleep(1.0)
    t = time_base.now_s()
    assert abs(rig.centrifuge.table.axis_motion(0, np.array([t]))[1][0]) < 1e-3  # type: ignore[union-attr]
    assert rig.centrifuge.table.mode(0, t) == "off"  # type: ignore[union-attr]
