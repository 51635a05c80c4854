"""``imucalib station check`` against simulator servers started in the test."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from imucalib.cli import _app, app
from imucalib.drivers.simulators import AclSimServer, F4TSimServer, LoopbackStation

from ._rigs import SPEED, make_rig

runner = CliRunner()
WIDE = {"COLUMNS": "400"}


@pytest.fixture(autouse=True)
def wide_console(monkeypatch: pytest.MonkeyPatch) -> None:
    """Rich fixes the width when the console is made: widen it so no cell is cut."""
    monkeypatch.setattr(_app.console, "width", 400)
    monkeypatch.setattr(_app.err_console, "width", 400)


@pytest.fixture
def sim() -> Iterator[LoopbackStation]:
    with LoopbackStation(make_rig(chamber=True), speed=SPEED) as station:
        yield station


def test_check_identifies_everything_and_moves_nothing(sim: LoopbackStation,
                                                       tmp_path: Path) -> None:
    path = sim.write_station_file(tmp_path / "station.toml")
    result = runner.invoke(app, ["station", "check", str(path), "--listen-s", "0.2"], env=WIDE)
    assert result.exit_code == 0, result.output
    out = result.output
    for text in ("ACUTRONIC,ACUTROL3000-SIM", "Watlow F4T F4T-SIM-TWIN-01",
                 "SIM-TWIN serial IMU-T1", "interlock open", "running", "nothing was moved"):
        assert text in out, text
    acl = sim.servers["table"]
    assert isinstance(acl, AclSimServer)
    assert not acl.remote and acl.interlock == ["open", "open"]  # no lockout, no servo
    t = sim.time_base.now_s()
    assert [acl.sim.mode(i, t) for i in range(2)] == ["off", "off"]
    assert np.all(acl.sim.axis_motion(0, np.array([t]))[1] == 0.0)


def test_check_serial_dialects(tmp_path: Path) -> None:
    with LoopbackStation(make_rig(chamber=True), speed=SPEED, table="aerosmith",
                          table_transport="serial", chamber="espec-p300", imu="csv") as sim:
        path = sim.write_station_file(tmp_path / "station.toml")
        result = runner.invoke(app, ["station", "check", str(path), "--listen-s", "0.2"],
                               env=WIDE)
    assert result.exit_code == 0, result.output
    assert "AERO4000-SIM" in result.output and "Espec T,P300" in result.output


def test_check_fails_on_an_alarm(sim: LoopbackStation, tmp_path: Path) -> None:
    chamber = sim.servers["chamber"]
    assert isinstance(chamber, F4TSimServer)
    chamber.raise_alarm(0, 37)
    path = sim.write_station_file(tmp_path / "station.toml")
    result = runner.invoke(app, ["station", "check", str(path), "--listen-s", "0.1"], env=WIDE)
    assert result.exit_code == 2
    assert "station check failed" in result.output
    assert "chamber main: running; ALARM alarm 1: high" in result.output


def test_check_fails_on_an_unreachable_device(sim: LoopbackStation, tmp_path: Path) -> None:
    path = sim.write_station_file(tmp_path / "station.toml")
    port = sim.servers["imu[IMU-T1]"].port
    sim.servers["imu[IMU-T1]"].close()
    result = runner.invoke(app, ["station", "check", str(path), "--listen-s", "0.1"], env=WIDE)
    assert result.exit_code == 2
    assert f"IMU-T1: tcp://127.0.0.1:{port}: cannot connect" in result.output


def test_check_rejects_a_malformed_file(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text('[site]\nlatitude_deg = 45.0\n[table]\nkind = "hexapod"\n'
                    'transport = "tcp://127.0.0.1:1"\n[[table.axes]]\nname = "a"\n'
                    "max_rate_dps = 1.0\nmax_accel_dps2 = 1.0\n", encoding="utf-8")
    result = runner.invoke(app, ["station", "check", str(path)], env=WIDE)
    assert result.exit_code == 2
    assert "table.kind: unknown table kind 'hexapod'" in result.output
    assert "imu: required but missing" in result.output
