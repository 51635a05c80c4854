"""Modbus float helpers, the Watlow F4T register map and the Espec P300 codec."""

from __future__ import annotations

import re
import struct

import pytest

from imucalib.drivers import espec_p300, watlow_f4t
from imucalib.drivers.fake import FakeRegisterLink
from imucalib.drivers.modbus import (
    floats_to_registers,
    read_floats,
    read_string,
    registers_to_floats,
    write_float,
)
from imucalib.errors import DeviceError, InvalidInputError


def test_float_registers_low_word_first_known_vectors() -> None:
    # 1.0 = 0x3F800000; 25.5 = 0x41CC0000; -40.0 = 0xC2200000
    assert floats_to_registers([1.0]) == [0x0000, 0x3F80]
    assert floats_to_registers([25.5, -40.0]) == [0x0000, 0x41CC, 0x0000, 0xC220]
    assert floats_to_registers([1.0], low_word_first=False) == [0x3F80, 0x0000]
    assert registers_to_floats([0x0000, 0x41CC]) == [25.5]
    pi32 = struct.unpack(">f", struct.pack(">f", 3.14159))[0]
    assert registers_to_floats(floats_to_registers([3.14159])) == [pi32]


def test_float_registers_errors() -> None:
    with pytest.raises(InvalidInputError, match="floats take two registers each; got 3"):
        registers_to_floats([1, 2, 3])
    with pytest.raises(InvalidInputError, match="registers must be in 0–65535; got \\[70000\\]"):
        registers_to_floats([70000, 0])


def test_register_link_helpers() -> None:
    link = FakeRegisterLink({16: ord("F"), 17: ord("4"), 18: ord("T"), 19: 0})
    write_float(link, 2782, 23.5)
    assert link.writes == [(2782, [0x0000, 0x41BC])]
    assert read_floats(link, 2782) == [23.5]
    assert read_string(link, 16, 15) == "F4T"


def test_f4t_setpoint_writes_without_and_with_ramp() -> None:
    assert watlow_f4t.setpoint_writes(30.0, None) == [
        (2794, [62]), (2782, [0x0000, 0x41F0]), (2730, [10])]
    writes = watlow_f4t.setpoint_writes(30.0, 0.5)  # 0.5 °C/s = 30 °C/min
    assert writes == [(2796, [57]), (2798, [0x0000, 0x41F0]), (2794, [85]),
                      (2782, [0x0000, 0x41F0]), (2730, [10])]
    with pytest.raises(InvalidInputError, match="`ramp_per_s` must be > 0; got -1"):
        watlow_f4t.setpoint_writes(30.0, -1.0)


def test_f4t_alarms_and_units() -> None:
    assert watlow_f4t.alarm_register(0) == 1356 and watlow_f4t.alarm_register(2) == 1556
    assert watlow_f4t.alarm_text(0, 61) is None
    assert watlow_f4t.alarm_text(1, 37) == "alarm 2: high"
    assert watlow_f4t.alarm_text(0, 99) == "alarm 1: state 99"
    assert watlow_f4t.to_celsius(212.0, watlow_f4t.UNITS_F) == pytest.approx(100.0)
    assert watlow_f4t.from_celsius(-40.0, watlow_f4t.UNITS_F) == pytest.approx(-40.0)
    with pytest.raises(DeviceError, match="display units code 7: expected 15 \\(°C\\) or 30"):
        watlow_f4t.to_celsius(1.0, 7)
    assert watlow_f4t.encode_string("F4T", 5) == [70, 52, 84, 0, 0]


def test_p300_commands() -> None:
    assert espec_p300.format_command("TEMP?") == b"TEMP?\r\n"
    assert espec_p300.format_command("TEMP?", address=1) == b"1,TEMP?\r\n"
    assert espec_p300.set_temperature(23.04) == "TEMP, S23.0"
    assert espec_p300.run_ramp_program(20.0, 60.0, 600.0) == \
        "RUN PRGM, TEMP20.0 TIME0:10 GOTEMP60.0"
    assert espec_p300.run_ramp_program(20.0, 21.0, 10.0) == \
        "RUN PRGM, TEMP20.0 TIME0:1 GOTEMP21.0"  # whole minutes, never faster
    assert espec_p300.run_ramp_program(20.0, 80.0, 3700.0).endswith("TIME1:2 GOTEMP80.0")


def test_p300_replies() -> None:
    assert espec_p300.parse_reply(b"OK: TEMP, S23.0", "TEMP, S23.0") == "OK: TEMP, S23.0"
    with pytest.raises(DeviceError, match=re.escape(
            "Espec 'TEMP, S999.0': the chamber refused it: DATA OUT OF RANGE (value outside "
            "the valid range)")):
        espec_p300.parse_reply(b"NA:DATA OUT OF RANGE", "TEMP, S999.0")
    reading = espec_p300.parse_temp("23.50,25.00,130.0,-60.0")
    assert reading == espec_p300.TempReading(23.5, 25.0, 130.0, -60.0)
    with pytest.raises(DeviceError, match="expected 4 values PV,SP,HIGH,LOW; got '1,2'"):
        espec_p300.parse_temp("1,2")
    assert espec_p300.parse_mode("constant") == "CONSTANT"
    with pytest.raises(DeviceError, match="unknown mode 'FLY'"):
        espec_p300.parse_mode("FLY")
    assert espec_p300.parse_alarm("0") == []
    assert espec_p300.parse_alarm("2,5,12") == [5, 12]
    with pytest.raises(DeviceError, match="expected a count then that many codes; got '2,5'"):
        espec_p300.parse_alarm("2,5")


def test_p300_simulator_side_parsers() -> None:
    assert espec_p300.parse_setpoint_args(" S23.0 H80.0 L-40.0") == {"S": 23.0, "H": 80.0,
                                                                     "L": -40.0}
    with pytest.raises(InvalidInputError, match="bad TEMP argument 'X1'"):
        espec_p300.parse_setpoint_args(" X1")
    assert espec_p300.parse_ramp_program(" TEMP20.0 TIME1:30 GOTEMP-10.5") == (20.0, -10.5,
                                                                              5400.0)
