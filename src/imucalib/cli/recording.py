"""Commands on Recordings: ``inspect``, ``recover`` and ``export``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from imucalib.cli._app import app, console, fail
from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["export", "inspect", "recover"]


@app.command()
def inspect(
    path: Annotated[Path, typer.Argument(help="Recording (.h5).")],
) -> None:
    """Summarise a Recording: streams, units, steps, durations, sample rates, gaps."""
    from imucalib.io.inspect import summarize_recording

    try:
        summary = summarize_recording(path)
    except CalibrationError as exc:
        raise fail(exc) from exc
    summary.render(console)


@app.command()
def recover(
    path: Annotated[Path, typer.Argument(help="Recording left open by a crashed writer.")],
    out: Annotated[Path | None,
                   typer.Option("--out", "-o", help="Where to write the copy.")] = None,
) -> None:
    """Copy what a crashed writer flushed into a new, cleanly closed Recording."""
    from imucalib.io.recover import recover_recording

    try:
        report = recover_recording(path, out)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(report.summary(), highlight=False)


@app.command()
def export(
    path: Annotated[Path, typer.Argument(help="Recording (.h5).")],
    stream: Annotated[str, typer.Option(help="Stream as DEVICE/UNIT, e.g. imu/IMU-0001.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output file (.csv or .mat).")],
    step: Annotated[int | None, typer.Option(help="Only this step's valid window.")] = None,
) -> None:
    """Export a stream, or one step of it, as CSV or MAT (chosen by the file suffix)."""
    from imucalib.io.export import export_csv, export_mat
    from imucalib.io.reader import open_recording

    device, _, unit = stream.partition("/")
    try:
        if not unit:
            raise InvalidInputError(
                f"--stream must be DEVICE/UNIT (e.g. imu/IMU-0001); got {stream!r}"
            )
        suffix = out.suffix.lower()
        if suffix not in {".csv", ".mat"}:
            raise InvalidInputError(f"--out must end in .csv or .mat; got {out.name!r}")
        with open_recording(path) as rec:
            if suffix == ".csv":
                export_csv(rec, device, unit, out, step=step)
            else:
                export_mat(rec, device, unit, out, step=step)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"wrote {out}", highlight=False)
