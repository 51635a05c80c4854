"""Chamber drivers against their simulator servers over loopback, with the twin chamber behind."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from imucalib.drivers import EspecP300Chamber, ModbusTcpLink, WatlowF4TChamber
from imucalib.drivers.simulators import F4TSimServer, P300SimServer, SimTimeBase
from imucalib.drivers.transport import open_transport
from imucalib.errors import DeviceError, LimitExceededError
from imucalib.sim.chamber import SimChamber

from ._rigs import make_rig


def start(kind: str, tb: SimTimeBase, servers: list[Any], transport: str = "tcp"
          ) -> tuple[F4TSimServer | P300SimServer, WatlowF4TChamber | EspecP300Chamber,
                     SimChamber]:
    rig = make_rig(chamber=True)
    assert rig.chamber is not None
    if kind == "watlow-f4t":
        f4t = F4TSimServer(rig, tb).start()
        servers.append(f4t)
        port = f4t.port
        chamber: WatlowF4TChamber | EspecP300Chamber = WatlowF4TChamber(
            "chamber", lambda: ModbusTcpLink("127.0.0.1", port, timeout_s=1.0), clock=tb,
            min_temp_degc=-40, max_temp_degc=85, address=f"tcp://127.0.0.1:{port}")
        return f4t, chamber, rig.chamber
    p300 = P300SimServer(rig, tb).start()
    servers.append(p300)
    url = (f"tcp://127.0.0.1:{p300.port}" if transport == "tcp"
           else f"serial://socket://127.0.0.1:{p300.port}?baud=9600")
    chamber = EspecP300Chamber("chamber", lambda: open_transport(url), clock=tb,
                               min_temp_degc=-40, max_temp_degc=85, address=url)
    return p300, chamber, rig.chamber


@pytest.fixture
def time_base() -> SimTimeBase:
    """Chambers are slow: run them 100 times faster than the wall."""
    return SimTimeBase(100.0)


def near_truth(value: float, ch: SimChamber, t: float, what: str, *, slack_s: float = 2.0,
               tol: float = 0.02) -> bool:
    """Whether `value` lies within the twin's `what` over t ± slack (exchange time unknown)."""
    times = np.linspace(t - slack_s, t + slack_s, 21)
    ref = ch.air_temperature_degc(times) if what == "air" else ch.setpoint_degc(times)
    return bool(ref.min() - tol <= value <= ref.max() + tol)


@pytest.mark.parametrize("kind, transport", [("watlow-f4t", "tcp"), ("espec-p300", "tcp"),
                                             ("espec-p300", "serial")])
def test_chamber_setpoint_ramp_readback_and_standby(
        kind: str, transport: str, time_base: SimTimeBase, servers: list[Any]) -> None:
    server, chamber, twin = start(kind, time_base, servers, transport)
    chamber.connect()
    ident = chamber.identify()
    assert ("F4T-SIM-TWIN" in ident) if kind == "watlow-f4t" else ("P300-SIM" in ident)
    st = chamber.status()
    assert st.running and st.alarm is None
    r0 = chamber.poll()
    assert r0.temperature_degc[0] == pytest.approx(20.0, abs=0.05)
    chamber.set_temperature(30.0, ramp_degc_ps=10.0 / 60.0)  # whole minutes suit the P300
    time_base.sleep(30.0)
    r = chamber.poll()
    assert 23.0 < r.setpoint_degc[0] < 27.0  # still ramping, at 10 °C/min
    assert near_truth(r.setpoint_degc[0], twin, r.time_s[0], "setpoint")
    assert near_truth(r.temperature_degc[0], twin, r.time_s[0], "air")
    time_base.sleep(45.0)
    r = chamber.poll()
    assert r.setpoint_degc[0] == pytest.approx(30.0, abs=0.01)
    assert 28.0 < r.temperature_degc[0] < 30.0  # the air lags (10 s time constant)
    assert near_truth(r.temperature_degc[0], twin, r.time_s[0], "air")
    # the range is checked before anything is sent
    before = server.requests if isinstance(server, F4TSimServer) else server.lines_received
    with pytest.raises(LimitExceededError, match="chamber: setpoint 100 °C is outside the range "
                                                 "\\[-40, 85\\] °C; nothing was sent"):
        chamber.set_temperature(100.0)
    after = server.requests if isinstance(server, F4TSimServer) else server.lines_received
    assert after == before
    chamber.standby()
    assert not chamber.status().running
    stamps = [chamber.poll().time_s[0] for _ in range(3)]
    assert np.all(np.diff(stamps) > 0)
    chamber.disconnect()


@pytest.mark.parametrize("kind", ["watlow-f4t", "espec-p300"])
def test_chamber_alarm_is_reported_not_raised(kind: str, time_base: SimTimeBase,
                                              servers: list[Any]) -> None:
    server, chamber, _ = start(kind, time_base, servers)
    chamber.connect()
    if isinstance(server, F4TSimServer):
        server.raise_alarm(1, 37)
        expected = "alarm 2: high"
    else:
        server.raise_alarm(12)
        expected = "alarm codes [12]"
    st = chamber.status()
    assert st.alarm == expected and st.running
    server.clear_alarms()
    assert chamber.status().alarm is None


@pytest.mark.parametrize("kind", ["watlow-f4t", "espec-p300"])
def test_chamber_dropped_connection(kind: str, time_base: SimTimeBase,
                                    servers: list[Any]) -> None:
    server, chamber, _ = start(kind, time_base, servers)
    chamber.connect()
    chamber.poll()
    server.drop_connections()
    with pytest.raises(DeviceError):
        chamber.poll()
    chamber.standby()  # never raises; reconnects to do it
    assert not chamber.status().running


def test_chamber_refusal_from_the_controller(time_base: SimTimeBase, servers: list[Any]) -> None:
    _, chamber, _ = start("espec-p300", time_base, servers)
    chamber.max_temp_degc = 200.0  # a wrong software range: the controller refuses
    chamber.connect()
    with pytest.raises(DeviceError, match="the chamber refused it: DATA OUT OF RANGE"):
        chamber.set_temperature(150.0)
