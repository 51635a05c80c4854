"""Device classes on scripted transports: exact bytes, checks before sending, never-raise stops."""

from __future__ import annotations

import re
from collections.abc import Iterator

import numpy as np
import pytest

from imucalib import units
from imucalib.drivers import (
    AcutrolTable,
    AerosmithTable,
    AxisLimits,
    FakeRegisterLink,
    FakeTransport,
    MonotonicClock,
    WatlowF4TChamber,
)
from imucalib.drivers import watlow_f4t as f4t
from imucalib.drivers.acl import encode_reply
from imucalib.drivers.modbus import floats_to_registers
from imucalib.errors import DeviceError, LimitExceededError
from imucalib.station.devices import ChamberDevice, MotionDevice

LIMITS = [AxisLimits(100 * units.DEG, 50 * units.DEG)]


def ok(payload: str = "") -> bytes:
    return encode_reply(0, payload)


def _opener(*fakes: FakeTransport):  # type: ignore[no-untyped-def]
    it: Iterator[FakeTransport] = iter(fakes)
    return lambda: next(it)


CONNECT = [
    (b"*IDN?\n", ok("ACUTRONIC,SIM,1,2")),
    (b":LIM:ABS? 1\n", ok("1000.000000,500.000000")),
    (b":U:L ON\n", ok()),
    (b":I:O 1\n", ok()),
    (b":I:R\n", ok()),
    (b":I:C 1\n", ok()),
    (b":LIM:RATE P,1,100.000000;:LIM:RATE R,1,100.000000;:LIM:ACC P,1,50.000000;"
     b":LIM:ACC R,1,50.000000\n", ok()),
    (b":M:R 1;:D:R 1,0.000000\n", ok()),
]


def test_acutrol_connect_follows_the_safe_sequence() -> None:
    fake = FakeTransport(CONNECT)
    table = AcutrolTable("t", ["spin"], _opener(fake), clock=MonotonicClock(), limits=LIMITS)
    assert isinstance(table, MotionDevice)
    table.connect()
    assert fake.pending == 0
    assert table.describe()["identity"] == "ACUTRONIC,SIM,1,2"


def test_acutrol_limits_checked_before_sending() -> None:
    fake = FakeTransport(CONNECT)
    table = AcutrolTable("t", ["spin"], _opener(fake), clock=MonotonicClock(), limits=LIMITS)
    table.connect()
    sent = len(fake.written)
    with pytest.raises(LimitExceededError, match="t: axis 'spin': rate 150 °/s exceeds the "
                                                 "software limit ±100 °/s; nothing was sent"):
        table.set_rate(0, 150 * units.DEG)
    with pytest.raises(LimitExceededError, match="rate limit 200 °/s exceeds the configured "
                                                 "maximum 100 °/s; nothing was sent"):
        table.set_limits(0, rate_rps=200 * units.DEG, accel_rps2=10 * units.DEG)
    assert len(fake.written) == sent
    fake.expect(b":D:R 1,-90.000000\n", ok())  # already in rate mode: no :M:R
    table.set_rate(0, -90 * units.DEG)
    fake.expect(b":M:P 1;:D:P 1,45.000000\n", ok())
    table.move_to(0, 45 * units.DEG)


def test_acutrol_absolute_limit_refused_on_connect() -> None:
    fake = FakeTransport(CONNECT[:2])
    limits = [AxisLimits(1200 * units.DEG, 50 * units.DEG)]
    table = AcutrolTable("t", ["spin"], _opener(fake), clock=MonotonicClock(), limits=limits)
    with pytest.raises(LimitExceededError, match="axis 'spin': configured max_rate 1200 °/s "
                                                 "exceeds the controller's absolute limit 1000"):
        table.connect()


def test_acutrol_status_reads_the_fault_text() -> None:
    fake = FakeTransport([
        (b":M? 1;:I? 1\n", ok("O;Fault")),
        (b":S:CSR? SI\n", ok("301")),
        (b":Q:E? 301\n", ok("emergency stop pressed")),
        (b":M? 1;:I? 1\n", ok("R;Closed")),
    ])
    table = AcutrolTable("t", ["spin"], _opener(fake), clock=MonotonicClock(), limits=LIMITS)
    table.open_link()
    st = table.status()
    assert st.modes == ("off",) and not st.interlock_closed
    assert st.fault == "interlock fault 301: emergency stop pressed"
    st = table.status()
    assert st.modes == ("rate",) and st.interlock_closed and st.fault is None


def test_acutrol_refusal_raises_device_error() -> None:
    fake = FakeTransport([(b":M:P 1;:D:P 1,10.000000\n", encode_reply(201, "interlock open"))])
    table = AcutrolTable("t", ["spin"], _opener(fake), clock=MonotonicClock(), limits=LIMITS)
    table.open_link()
    with pytest.raises(DeviceError, match=re.escape(
            "refused ':M:P 1;:D:P 1,10.000000': error 201: interlock open")):
        table.move_to(0, 10 * units.DEG)


def test_acutrol_safe_stop_reconnects_after_a_drop_and_never_raises() -> None:
    dropped = FakeTransport([(b":M:O ALL\n", DeviceError("connection lost"))])
    fresh = FakeTransport([(b":M:O ALL\n", ok()), (b":R:P? 1;R? 1\n", ok("12.0;0.0")),
                           (b":I:O ALL\n", ok())])
    table = AcutrolTable("t", ["spin"], _opener(dropped, fresh), clock=MonotonicClock(),
                         limits=LIMITS)
    table.open_link()
    table.safe_stop()
    assert fresh.pending == 0 and dropped.closed
    # no controller at all: still no exception
    table2 = AcutrolTable("t", ["spin"], _opener(), clock=MonotonicClock(), limits=LIMITS)
    table2.safe_stop()


def test_acutrol_poll_stamps_and_converts() -> None:
    clock = MonotonicClock()
    fake = FakeTransport([(b":R:P? 1;P? 2;R? 1;R? 2\n", ok("90.0;-45.0;0.5;-1.0"))])
    table = AcutrolTable("t", ["pitch", "roll"], _opener(fake), clock=clock,
                         limits=LIMITS * 2)
    table.open_link()
    before = clock.now_s()
    fb = table.poll()
    assert before <= fb.time_s[0] <= clock.now_s()
    np.testing.assert_allclose(fb.angle_rad, [[np.pi / 2, -np.pi / 4]])
    np.testing.assert_allclose(fb.rate_rps, [[0.5 * units.DEG, -units.DEG]])


def test_acutrol_commands_after_a_lost_link_raise() -> None:
    fake = FakeTransport([(b"*IDN?\n", DeviceError("connection reset"))])
    table = AcutrolTable("t", ["spin"], _opener(fake), clock=MonotonicClock(), limits=LIMITS)
    table.open_link()
    with pytest.raises(DeviceError, match="connection reset"):
        table.identify()
    with pytest.raises(DeviceError, match="t: not connected \\(link lost: connection reset\\)"):
        table.poll()


def test_aerosmith_replies_prompt_and_jog_without_reply() -> None:
    fake = FakeTransport([
        (b"VER\r\n", b"AERO SIM\r\n>\r\n"),
        (b"VEL100.000000\r\n", b"OK\r\n>\r\n"),
        (b"ACL50.000000\r\n", b"OK\r\n>\r\n"),
        (b"SRV1\r\n", b"OK\r\n>\r\n"),
        (b"JOG-20.000000\r\n", b""),
        (b"STA\r\n", b"JOG,1,NONE\r\n>\r\n"),
        (b"PPO\r\n", b"1.5\r\n>\r\n"),
        (b"PVE\r\n", b"-20.0\r\n>\r\n"),
    ])
    table = AerosmithTable("a", ["spin"], _opener(fake), clock=MonotonicClock(), limits=LIMITS)
    table.connect()
    table.set_rate(0, -20 * units.DEG)
    fb = table.poll()
    np.testing.assert_allclose(fb.rate_rps, [[-20 * units.DEG]])
    assert fake.pending == 0


def test_watlow_writes_and_range_check() -> None:
    link = FakeRegisterLink({f4t.DISPLAY_UNITS: f4t.UNITS_C, f4t.CONTROL_MODE: f4t.MODE_AUTO})
    for k in range(2):
        link.registers[f4t.alarm_register(k)] = 61
    chamber = WatlowF4TChamber("c", lambda: link, clock=MonotonicClock(), min_temp_degc=-40,
                               max_temp_degc=85, n_alarms=2)
    assert isinstance(chamber, ChamberDevice)
    chamber.connect()
    with pytest.raises(LimitExceededError, match="c: setpoint 90 °C is outside the range "
                                                 "\\[-40, 85\\] °C; nothing was sent"):
        chamber.set_temperature(90.0)
    assert link.writes == []
    chamber.set_temperature(30.0, ramp_degc_ps=0.5)
    assert link.writes == f4t.setpoint_writes(30.0, 0.5)
    link.registers.update(zip([f4t.PROCESS_VALUE, f4t.PROCESS_VALUE + 1],
                              floats_to_registers([21.5]), strict=True))
    link.registers.update(zip([f4t.WORKING_SETPOINT, f4t.WORKING_SETPOINT + 1],
                              floats_to_registers([22.0]), strict=True))
    r = chamber.poll()
    assert (r.temperature_degc[0], r.setpoint_degc[0]) == (21.5, 22.0)
    link.registers[f4t.alarm_register(1)] = 53
    st = chamber.status()
    assert st.running and st.alarm == "alarm 2: low"
    chamber.standby()
    assert link.registers[f4t.CONTROL_MODE] == f4t.MODE_OFF
    assert not chamber.status().running
    link.fail_with = DeviceError("link down")
    chamber.standby()  # never raises


def test_watlow_fahrenheit_display() -> None:
    link = FakeRegisterLink({f4t.DISPLAY_UNITS: f4t.UNITS_F})
    chamber = WatlowF4TChamber("c", lambda: link, clock=MonotonicClock(), min_temp_degc=-40,
                               max_temp_degc=85)
    chamber.connect()
    chamber.set_temperature(100.0 - 15.0)
    assert (f4t.SETPOINT, floats_to_registers([185.0])) in link.writes


def test_acutrol_sends_the_mode_again_after_a_refused_demand() -> None:
    fake = FakeTransport([
        *CONNECT,
        (b":D:R 1,10.000000\n", encode_reply(202, "axis 1 is in mode O, not R")),
        (b":M:R 1;:D:R 1,10.000000\n", ok()),
    ])
    table = AcutrolTable("t", ["spin"], _opener(fake), clock=MonotonicClock(), limits=LIMITS)
    table.connect()
    with pytest.raises(DeviceError, match="error 202"):
        table.set_rate(0, 10 * units.DEG)
    table.set_rate(0, 10 * units.DEG)
    assert fake.pending == 0
