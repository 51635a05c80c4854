"""The station file: a full example, malformed files rejected with messages naming the field."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from imucalib.drivers import (
    AcutrolTable,
    CsvLineImu,
    DriverStation,
    EspecP300Chamber,
    MonotonicClock,
    PacketImu,
    load_driver_station,
    load_station_config,
    parse_station_config,
)
from imucalib.drivers.motion import AerosmithTable
from imucalib.errors import ConfigurationError
from imucalib.station.devices import Station

FULL = """
name = "Lab A, station 1"

[site]
latitude_deg = 52.38
heading_deg = 12.5

[table]
kind = "acutrol"
transport = "tcp://127.0.0.1:9878"
[[table.axes]]
name = "pitch"
max_rate_dps = 500.0
max_accel_dps2 = 300.0
controller_max_rate_dps = 1000.0
controller_max_accel_dps2 = 500.0
travel_deg = [-180.0, 180.0]
[[table.axes]]
name = "roll"
max_rate_dps = 500.0
max_accel_dps2 = 300.0

[centrifuge]
kind = "aerosmith"
transport = "serial:///dev/ttyUSB0?baud=9600"
radius_m = 0.6
[[centrifuge.axes]]
name = "spin"
max_rate_dps = 720.0
max_accel_dps2 = 90.0

[chamber]
kind = "espec-p300"
transport = "serial://socket://127.0.0.1:10001"
min_temp_degc = -40.0
max_temp_degc = 85.0
rated_min_temp_degc = -70.0
rated_max_temp_degc = 180.0

[[imu]]
name = "IMU-0001"
kind = "packet"
transport = "serial:///dev/ttyACM0?baud=921600"
sample_rate_hz = 1000.0
gyro_range_dps = 450.0
accel_range_g = 8.0
gyro_lsb_dps = 1e-5
accel_lsb_g = 1e-6

[[imu]]
name = "IMU-0002"
kind = "csv"
transport = "tcp://127.0.0.1:4002"
sample_rate_hz = 200.0
"""


def test_full_example_builds_a_station_without_connecting() -> None:
    cfg = parse_station_config(FULL)
    assert cfg.site.latitude_deg == 52.38 and cfg.table is not None
    assert cfg.table.axes[0].travel_deg == (-180.0, 180.0)
    assert cfg.transports()["chamber"].device == "socket://127.0.0.1:10001"
    clock = MonotonicClock()
    station = DriverStation.from_config(cfg, clock=clock)
    assert isinstance(station, Station)
    assert isinstance(station.table, AcutrolTable)
    assert station.table.axis_names == ("pitch", "roll")
    assert isinstance(station.centrifuge, AerosmithTable)
    assert station.centrifuge.axis_names == ("spin",)
    assert isinstance(station.chamber, EspecP300Chamber)
    assert [type(i) for i in station.imus] == [PacketImu, CsvLineImu]
    assert (station.latitude_deg, station.heading_deg, station.clock) == (52.38, 12.5, clock)
    desc = json.loads(json.dumps(station.describe()))
    assert desc["kind"] == "equipment" and desc["name"] == "Lab A, station 1"
    assert [d["role"] for d in desc["devices"]] == ["table", "centrifuge", "chamber", "imu",
                                                    "imu"]
    assert desc["devices"][3]["gyro_range_rps"] == pytest.approx(450.0 * 3.141592653589793 / 180)


def test_load_from_file_and_resume_time(tmp_path: Path) -> None:
    path = tmp_path / "station.toml"
    path.write_text(FULL, encoding="utf-8")
    assert load_station_config(path).name == "Lab A, station 1"
    station = load_driver_station(path, start_time_s=1000.0)
    assert 1000.0 <= station.clock.now_s() < 1010.0
    with pytest.raises(ConfigurationError, match=r"station file .*nope\.toml does not exist"):
        load_station_config(tmp_path / "nope.toml")


def _variant(old: str, new: str) -> str:
    assert old in FULL
    return FULL.replace(old, new, 1)


BAD = [
    # unknown device kind
    (_variant('kind = "acutrol"', 'kind = "contraves"'),
     "table.kind: unknown table kind 'contraves'; expected 'acutrol' or 'aerosmith'"),
    (_variant('kind = "espec-p300"', 'kind = "votsch"'),
     "chamber.kind: unknown chamber kind 'votsch'; expected 'watlow-f4t' or 'espec-p300'"),
    (_variant('kind = "csv"', 'kind = "xbus"'),
     "imu[1].kind: unknown imu kind 'xbus'; expected 'packet' or 'csv'"),
    # unknown device (section) and key
    (FULL + '\n[oven]\nkind = "x"\n',
     "oven: unknown device or section 'oven'; expected one of name, site, table, centrifuge, "
     "chamber, imu"),
    (_variant("radius_m = 0.6", "radius_m = 0.6\nspeed = 3"), "centrifuge.speed: unknown key "
                                                              "'speed'"),
    # bad port
    (_variant("tcp://127.0.0.1:9878", "tcp://127.0.0.1:70000"),
     "table.transport: port 70000 in 'tcp://127.0.0.1:70000' is outside 1–65535"),
    (_variant("tcp://127.0.0.1:4002", "tcp://127.0.0.1:port"),
     "imu[1].transport: port 'port' in 'tcp://127.0.0.1:port' is not an integer"),
    # rate limit above the table's limit
    (_variant("max_rate_dps = 500.0\nmax_accel_dps2 = 300.0\ncontroller_max_rate_dps",
              "max_rate_dps = 1200.0\nmax_accel_dps2 = 300.0\ncontroller_max_rate_dps"),
     "table.axes[0]: max_rate_dps 1200 °/s exceeds the controller's absolute limit "
     "controller_max_rate_dps 1000 °/s"),
    (_variant("max_accel_dps2 = 300.0\ncontroller_max_rate_dps = 1000.0\n"
              "controller_max_accel_dps2 = 500.0",
              "max_accel_dps2 = 600.0\ncontroller_max_rate_dps = 1000.0\n"
              "controller_max_accel_dps2 = 500.0"),
     "table.axes[0]: max_accel_dps2 600 °/s² exceeds the controller's absolute limit "
     "controller_max_accel_dps2 500 °/s²"),
    # chamber range
    (_variant("max_temp_degc = 85.0", "max_temp_degc = 200.0"),
     "chamber: max_temp_degc 200 °C is above the chamber's rating rated_max_temp_degc 180 °C"),
    (_variant("min_temp_degc = -40.0", "min_temp_degc = 90.0"),
     "chamber: min_temp_degc 90 °C must be below max_temp_degc 85 °C"),
    (_variant("min_temp_degc = -40.0", "min_temp_degc = -80.0"),
     "chamber: min_temp_degc -80 °C is below the chamber's rating rated_min_temp_degc -70 °C"),
    # other structure
    (_variant('name = "spin"', 'name = "arm"'),
     "centrifuge: a centrifuge has one axis named 'spin'; got ['arm']"),
    (_variant("latitude_deg = 52.38", "latitude_deg = 95.0"),
     "site.latitude_deg: Input should be less than or equal to 90 (got 95.0)"),
    (_variant('transport = "serial:///dev/ttyUSB0?baud=9600"',
              'transport = "visa://GPIB0::1::INSTR"'),
     "centrifuge: transport 'visa://GPIB0::1::INSTR': aerosmith controllers are reached over "
     "serial or tcp, not visa"),
    (_variant('name = "IMU-0002"', 'name = "IMU-0001"'),
     "(top level): IMU names must be unique; repeated: ['IMU-0001']"),
    (_variant("[site]\nlatitude_deg = 52.38\n", "[site]\n"),
     "site.latitude_deg: required but missing"),
    (_variant("accel_lsb_g = 1e-6\n", ""),
     "imu[0]: give both gyro_lsb_dps and accel_lsb_g (int32-count frames) or neither"),
]


@pytest.mark.parametrize("text, line", BAD, ids=[b[1].split(":")[0] for b in BAD])
def test_malformed_station_files_name_the_field(text: str, line: str) -> None:
    with pytest.raises(ConfigurationError) as exc:
        parse_station_config(text, "station.toml")
    message = str(exc.value)
    assert message.startswith("invalid station file station.toml:\n")
    assert f"  {line}" in message.splitlines(), message


def test_not_toml() -> None:
    with pytest.raises(ConfigurationError, match=re.escape("station file s.toml is not valid "
                                                           "TOML")):
        parse_station_config("[site\nx=1", "s.toml")
