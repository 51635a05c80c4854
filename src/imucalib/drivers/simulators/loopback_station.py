"""Simulator servers for a whole twin rig, and the station file that reaches them.

:class:`LoopbackStation` starts one protocol-faithful server per device of a
:class:`~imucalib.sim.rig.TwinRig` on 127.0.0.1 (OS-assigned ports), all on one
:class:`~imucalib.drivers.simulators.SimTimeBase`, and writes the station TOML that points the
real drivers at them, so a station run against it exercises the exact code path used with real
equipment. (The in-process twin station, without drivers or sockets, is
:class:`imucalib.station.sim.SimStation`.)

Example
-------
>>> from imucalib.drivers import DriverStation, parse_station_config
>>> with LoopbackStation.from_scenario("dual-axis-p1", speed=20.0) as sim:   # doctest: +SKIP
...     cfg = parse_station_config(sim.station_toml())
...     station = DriverStation.from_config(cfg, clock=sim.time_base)
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

from imucalib import units
from imucalib.drivers.simulators._base import SimServer, SimTimeBase
from imucalib.drivers.simulators.acl_server import AclSimServer
from imucalib.drivers.simulators.aerosmith_server import AerosmithSimServer
from imucalib.drivers.simulators.f4t_server import F4TSimServer
from imucalib.drivers.simulators.imu_server import CsvImuServer, PacketImuServer
from imucalib.drivers.simulators.p300_server import P300SimServer
from imucalib.errors import ConfigurationError
from imucalib.sim.rig import TwinRig
from imucalib.sim.scenario import Scenario, load_scenario
from imucalib.sim.table import SimRateTable

__all__ = ["LoopbackStation"]

MotionKind = Literal["acutrol", "aerosmith"]
MotionTransport = Literal["tcp", "visa", "serial"]


def _url(port: int, transport: str) -> str:
    if transport == "tcp":
        return f"tcp://127.0.0.1:{port}"
    if transport == "visa":
        return f"visa://TCPIP::127.0.0.1::{port}::SOCKET"
    if transport == "serial":
        return f"serial://socket://127.0.0.1:{port}?baud=9600"
    raise ConfigurationError(f"transport must be tcp, visa or serial; got {transport!r}")


class LoopbackStation:
    """Start simulator servers for every device of `rig`.

    Parameters
    ----------
    rig : TwinRig
        The twin behind the servers.
    speed : float
        Simulated seconds per wall second (shared :class:`SimTimeBase`).
    table, centrifuge : {"acutrol", "aerosmith"}
        Dialect of the motion controllers.
    table_transport, centrifuge_transport : {"tcp", "visa", "serial"}
        How the station file tells the driver to reach them (all served over TCP; serial goes
        through pyserial's ``socket://``, VISA through pyvisa-py's ``TCPIP::…::SOCKET``).
    chamber : {"watlow-f4t", "espec-p300"}
        Chamber dialect.
    imu : {"packet", "csv"}
        IMU stream format (all IMUs).
    seed : int
        Seed of the IMU fault hooks.

    Attributes
    ----------
    time_base : SimTimeBase
        Shared simulated time (use it as the station clock in tests).
    servers : dict of str to SimServer
        ``table``, ``centrifuge``, ``chamber``, ``imu[NAME]``.
    """

    def __init__(self, rig: TwinRig, *, speed: float = 1.0, table: MotionKind = "acutrol",
                 table_transport: MotionTransport = "tcp", centrifuge: MotionKind = "acutrol",
                 centrifuge_transport: MotionTransport = "tcp",
                 chamber: Literal["watlow-f4t", "espec-p300"] = "watlow-f4t",
                 imu: Literal["packet", "csv"] = "packet", seed: int = 0) -> None:
        self.rig = rig
        self.time_base = SimTimeBase(speed)
        self.kinds: dict[str, str] = {}
        self.transports: dict[str, str] = {}
        self.servers: dict[str, SimServer] = {}
        try:
            for role, kind, transport, present in (
                    ("table", table, table_transport, rig.table is not None),
                    ("centrifuge", centrifuge, centrifuge_transport, rig.centrifuge is not None)):
                if not present:
                    continue
                device: Literal["table", "centrifuge"] = \
                    "table" if role == "table" else "centrifuge"
                motion = (AclSimServer(rig, self.time_base, device=device) if kind == "acutrol"
                          else AerosmithSimServer(rig, self.time_base, device=device))
                self._add(role, kind, transport, motion)
            if rig.chamber is not None:
                server: SimServer = (F4TSimServer(rig, self.time_base) if chamber == "watlow-f4t"
                                     else P300SimServer(rig, self.time_base))
                self._add("chamber", chamber, "tcp", server)
            for k, name in enumerate(rig.imu_names):
                server = (PacketImuServer(rig, self.time_base, name, seed=seed + k)
                          if imu == "packet" else
                          CsvImuServer(rig, self.time_base, name, seed=seed + k))
                self._add(f"imu[{name}]", imu, "tcp", server)
        except Exception:
            self.close()
            raise

    def _add(self, role: str, kind: str, transport: str, server: SimServer) -> None:
        self.servers[role] = server.start()
        self.kinds[role] = kind
        self.transports[role] = _url(server.port, transport)

    @classmethod
    def from_scenario(cls, scenario: str | Scenario, **kwargs: Any) -> LoopbackStation:
        """Build the rig of a scenario (built-in name, TOML file or object) and serve it."""
        from imucalib.sim.build import build_rig

        sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
        return cls(build_rig(sc).rig, **kwargs)

    def __enter__(self) -> LoopbackStation:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def close(self) -> None:
        """Stop every server."""
        for server in self.servers.values():
            server.close()

    @staticmethod
    def _axes_toml(role: str, sim: SimRateTable) -> list[str]:
        lines = []
        for ax in sim.spec.axes:
            rate, acc = ax.max_rate_rps / units.DEG, ax.max_accel_rps2 / units.DEG
            lines += [f"[[{role}.axes]]", f'name = "{ax.name}"', f"max_rate_dps = {rate:.6f}",
                      f"max_accel_dps2 = {acc:.6f}", f"controller_max_rate_dps = {rate:.6f}",
                      f"controller_max_accel_dps2 = {acc:.6f}"]
        return lines

    def station_toml(self, *, name: str = "simulated station", timeout_s: float = 2.0,
                     stop_timeout_s: float = 60.0) -> str:
        """Return the station file (TOML) that points the drivers at these servers."""
        site = self.rig.site
        lines = [f'name = "{name}"', "", "[site]", f"latitude_deg = {site.latitude_deg!r}",
                 f"heading_deg = {site.heading_deg!r}", ""]
        for role in ("table", "centrifuge"):
            if role not in self.servers:
                continue
            fuge = self.rig.centrifuge
            sim = self.rig.table if role == "table" else (None if fuge is None else fuge.table)
            if sim is None:
                continue
            lines += [f"[{role}]", f'kind = "{self.kinds[role]}"',
                      f'transport = "{self.transports[role]}"', f"timeout_s = {timeout_s!r}",
                      f"stop_timeout_s = {stop_timeout_s!r}", *self._axes_toml(role, sim), ""]
        if "chamber" in self.servers and self.rig.chamber is not None:
            spec = self.rig.chamber.spec
            lines += ["[chamber]", f'kind = "{self.kinds["chamber"]}"',
                      f'transport = "{self.transports["chamber"]}"',
                      f"min_temp_degc = {spec.min_temp_degc!r}",
                      f"max_temp_degc = {spec.max_temp_degc!r}",
                      f"rated_min_temp_degc = {spec.min_temp_degc!r}",
                      f"rated_max_temp_degc = {spec.max_temp_degc!r}",
                      f"timeout_s = {timeout_s!r}", ""]
        for name_ in self.rig.imu_names:
            model = self.rig.imus[name_].model
            role = f"imu[{name_}]"
            lines += ["[[imu]]", f'name = "{name_}"', f'kind = "{self.kinds[role]}"',
                      f'transport = "{self.transports[role]}"',
                      f"sample_rate_hz = {model.sample_rate_hz!r}", 'model = "SIM-TWIN"',
                      'maker = "imucalib"']
            if model.gyro_output.range is not None:
                lines.append(f"gyro_range_dps = {model.gyro_output.range / units.DEG!r}")
            if model.accel_output.range is not None:
                lines.append(f"accel_range_g = {model.accel_output.range / units.G0_MPS2!r}")
            lines.append("")
        return "\n".join(lines)

    def write_station_file(self, path: str | Path, **kwargs: Any) -> Path:
        """Write :meth:`station_toml` to `path`; returns the path."""
        p = Path(path)
        p.write_text(self.station_toml(**kwargs), encoding="utf-8")
        return p
