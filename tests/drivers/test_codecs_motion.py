"""ACL and Aerosmith codecs: literal bytes in, literal bytes out."""

from __future__ import annotations

import pytest

from imucalib.drivers import acl, aerosmith
from imucalib.drivers.acl import AclCommand, AclCommandError
from imucalib.errors import DeviceError, InvalidInputError


# --- ACL: commands ------------------------------------------------------------------------------
def test_acl_safe_sequence_commands() -> None:
    assert acl.lockout(True) == ":U:L ON"
    assert acl.lockout(False) == ":U:L OFF"
    assert acl.interlock_open(1) == ":I:O 1"
    assert acl.interlock_open("ALL") == ":I:O ALL"
    assert acl.interlock_reset() == ":I:R"
    assert acl.interlock_close(2) == ":I:C 2"
    assert acl.mode(1, "rate") == ":M:R 1"
    assert acl.mode("ALL", "off") == ":M:O ALL"
    assert acl.demand_rate(1, 0.0) == ":D:R 1,0.000000"
    assert acl.demand_position(2, -90.5) == ":D:P 2,-90.500000"
    assert acl.limit_rate("P", 1, 120.0) == ":LIM:RATE P,1,120.000000"
    assert acl.limit_accel("R", 2, 50.0) == ":LIM:ACC R,2,50.000000"


def test_acl_chained_readback_and_message_bytes() -> None:
    assert acl.read_feedback([1, 2]) == ":R:P? 1;P? 2;R? 1;R? 2"
    assert acl.join_commands([acl.mode(1, "position"), acl.demand_position(1, 90.0)]) == \
        b":M:P 1;:D:P 1,90.000000\n"


@pytest.mark.parametrize("bad", [0, -1, "2", True, 1.5])
def test_acl_rejects_bad_axis(bad: object) -> None:
    with pytest.raises(InvalidInputError, match="ACL axis numbers are integers ≥ 1"):
        acl.interlock_close(bad)  # type: ignore[arg-type]


def test_acl_queries_refuse_all_and_nan() -> None:
    with pytest.raises(InvalidInputError, match="ACL queries take one axis, not ALL"):
        acl.mode_query("ALL")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="`rate_dps` must be finite; got nan"):
        acl.demand_rate(1, float("nan"))


# --- ACL: replies -------------------------------------------------------------------------------
def test_acl_reply_header_round_trip() -> None:
    assert acl.encode_reply(0, "90.0;1.5") == b"00000008" + b"90.0;1.5\n"
    reply = acl.parse_reply(b"0000000890.0;1.5\n")
    assert reply.ok and reply.code == 0 and reply.values() == ["90.0", "1.5"]
    assert acl.parse_floats(reply, 2, "feedback") == [90.0, 1.5]
    err = acl.parse_reply(b"02010005oops!")
    assert not err.ok and err.code == 201 and err.payload == "oops!"
    assert acl.parse_reply(b"00000000\n").values() == []


@pytest.mark.parametrize("line, message", [
    (b"0000\n", "expected an 8-digit header"),
    (b"ab000000\n", "expected an 8-digit header"),
    (b"00000005abc\n", "header announces 5 payload byte\\(s\\); got 3"),
])
def test_acl_reply_malformed(line: bytes, message: str) -> None:
    with pytest.raises(DeviceError, match=message):
        acl.parse_reply(line)


def test_acl_parse_floats_counts_and_numbers() -> None:
    with pytest.raises(DeviceError, match="expected 4 value\\(s\\); got 2"):
        acl.parse_floats(acl.AclReply(0, "1;2"), 4, "feedback")
    with pytest.raises(DeviceError, match="non-numeric answer in '1;x'"):
        acl.parse_floats(acl.AclReply(0, "1;x"), 2, "feedback")
    assert acl.parse_floats(acl.AclReply(0, "1000.0,500.0"), 2, "limits") == [1000.0, 500.0]


# --- ACL: the simulator's parser ----------------------------------------------------------------
def test_acl_parse_message_short_forms_and_chaining() -> None:
    cmds = acl.parse_message(":R:P? 1;P? 2;R? 1;:Demand:Position 3,10.5;*IDN?")
    assert cmds == [
        AclCommand(("READ", "POSITION"), True, ("1",)),
        AclCommand(("READ", "POSITION"), True, ("2",)),
        AclCommand(("READ", "RATE"), True, ("1",)),
        AclCommand(("DEMAND", "POSITION"), False, ("3", "10.5")),
        AclCommand(("*IDN",), True, ()),
    ]
    assert acl.parse_message(":d:p 3,10.5") == acl.parse_message(":DEMAND:POSITION 3,10.5")
    assert acl.parse_message(":LIM:ABS? 1")[0].path == ("LIMIT", "ABSOLUTE")
    assert acl.parse_message(":M? 2")[0] == AclCommand(("MODE",), True, ("2",))


def test_acl_parse_message_ambiguous_and_unknown() -> None:
    with pytest.raises(AclCommandError, match="ambiguous header 'A' under :LIMIT") as exc:
        acl.parse_message(":L:A? 1")
    assert exc.value.code == 100
    with pytest.raises(AclCommandError, match="unknown header 'X' under the root"):
        acl.parse_message(":X:Y 1")


# --- Aerosmith ----------------------------------------------------------------------------------
def test_aerosmith_format() -> None:
    assert aerosmith.format_command("MOV", 90.0) == b"MOV90.000000\r\n"
    assert aerosmith.format_command("jog", -50.0) == b"JOG-50.000000\r\n"
    assert aerosmith.format_command("SRV", 1, axis=2) == b"2SRV1\r\n"
    assert aerosmith.format_command("PPO") == b"PPO\r\n"
    assert not aerosmith.expects_reply("JOG") and aerosmith.expects_reply("STO")
    with pytest.raises(InvalidInputError, match="unknown Aerosmith command 'XYZ'"):
        aerosmith.format_command("XYZ")


def test_aerosmith_responses_and_status() -> None:
    assert aerosmith.parse_response(b"12.5", "PPO") == "12.5"
    assert aerosmith.parse_number("12.5", "PPO") == 12.5
    with pytest.raises(DeviceError, match="Aerosmith MOV: the controller refused it: servo off"):
        aerosmith.parse_response(b"ERROR servo off", "MOV")
    with pytest.raises(DeviceError, match="Aerosmith PVE: expected a number; got 'abc'"):
        aerosmith.parse_number("abc", "PVE")
    st = aerosmith.parse_status("JOG,1,NONE")
    assert st == aerosmith.AerosmithStatus("JOG", True, None)
    assert aerosmith.parse_status("OFF,0,interlock open") == aerosmith.AerosmithStatus(
        "OFF", False, "interlock open")
    assert aerosmith.encode_status(aerosmith.AerosmithStatus("OFF", False, "a,b")) == "OFF,0,a;b"
    with pytest.raises(DeviceError, match="expected <OFF\\|POS\\|JOG\\|STOP>,<0\\|1>,<fault>"):
        aerosmith.parse_status("RUN,1,NONE")
    assert aerosmith.parse_command_line("2MOV45.0") == (2, "MOV", "45.0")
    assert aerosmith.parse_command_line("sta") == (None, "STA", "")
