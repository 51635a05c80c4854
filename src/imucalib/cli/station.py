"""Commands on real station equipment: ``station check``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from imucalib.cli._app import app, console, err_console, fail, typer_app
from imucalib.errors import CalibrationError

__all__ = ["check", "station_app"]

station_app = typer_app(
    name="station",
    help="Real station equipment: check the station file and every device.",
    no_args_is_help=True,
)
app.add_typer(station_app, name="station")


@station_app.command()
def check(
    path: Annotated[Path, typer.Argument(metavar="STATION.toml", help="Station file.")],
    listen_s: Annotated[float, typer.Option(
        help="How long to listen to each IMU stream [s].", min=0.05, max=60.0)] = 0.5,
) -> None:
    """Connect to each device, identify it, read its status and one reading; move nothing.

    Exits with code 2 when the station file is invalid, a device cannot be reached, or a
    device reports a fault, an alarm or an unhealthy stream.
    """
    from imucalib.drivers import DriverStation, load_station_config
    from imucalib.drivers.imus import CsvLineImu, PacketImu

    try:
        station = DriverStation.from_config(load_station_config(path))
    except CalibrationError as exc:
        raise fail(exc) from exc
    table = Table("device", "kind", "address", "identity", "state", "reading",
                  title=f"station check — {station.name}", title_justify="left")
    problems: list[str] = []
    for dev in station.drivers:
        try:
            result = (dev.check(listen_s=listen_s) if isinstance(dev, PacketImu | CsvLineImu)
                      else dev.check())
        except CalibrationError as exc:
            label = f"{getattr(dev, 'role', '')} {dev.name}".strip()
            problems.append(f"{label}: {exc}")
            table.add_row(label, getattr(dev, "kind", "?"), getattr(dev, "address", "?"),
                          "—", "[bold red]unreachable[/]", str(exc))
            continue
        state = result.state if result.ok else f"[bold red]{result.state}[/]"
        label = result.name if result.name == result.role else f"{result.role} {result.name}"
        table.add_row(label, result.kind, result.address,
                      result.identity, state, result.reading)
        if not result.ok:
            problems.append(f"{label}: {result.state}")
    console.print(table)
    if problems:
        err_console.print("[bold red]error:[/] station check failed:\n  " + "\n  ".join(problems),
                          highlight=False)
        raise typer.Exit(code=2)
    console.print(f"all {len(station.drivers)} device(s) answered; nothing was moved",
                  highlight=False)
