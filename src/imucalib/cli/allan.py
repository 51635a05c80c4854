"""``imucalib allan DATA``: noise characterisation of a bare static log (CSV or Recording).

No plan is needed: a CSV (canonical names, a ``--column-map``, or a ``rostopic echo -p`` export,
detected by :mod:`imucalib.io.csv_layouts`) or a Recording is analysed as one static record by
the Allan procedure's own analysis (:mod:`imucalib.procedures.allan.analysis`) and written by
:func:`imucalib.exports.outputs.write_outputs` (docs/noise.md, "imucalib allan").
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from imucalib.cli._app import app, console, fail
from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["allan"]


def _read_csv(data: Path, column_map: str | None, units: str | None, gyro_unit: str | None,
              accel_unit: str | None, time_column: str | None, time_unit: str | None,
              sample_rate: float | None) -> tuple[Any, dict[str, Any]]:
    """Read a CSV into (time_s, {canonical column: SI samples}) through its layout."""
    import csv

    import numpy as np

    from imucalib.conventions import TIME_COLUMN
    from imucalib.io.csv_import import read_imu_csv
    from imucalib.io.csv_layouts import build_csv_mapping, parse_pairs

    try:
        with open(data, encoding="utf-8-sig", newline="") as fh:
            headers = next(csv.reader([fh.readline().rstrip("\r\n")]), [])
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidInputError(f"cannot read CSV {data}: {exc}") from exc
    mapping = build_csv_mapping(headers, column_map=parse_pairs(column_map, "--column-map"),
                                units=parse_pairs(units, "--units"), gyro_unit=gyro_unit,
                                accel_unit=accel_unit, time_column=time_column,
                                time_unit=time_unit)
    names = {mapping.column_map.get(h.strip(), h.strip()) for h in headers}
    only = mapping.only
    if sample_rate is not None and TIME_COLUMN not in names:
        frame = _read_without_time(data, mapping)
    else:
        frame = read_imu_csv(data, column_map=mapping.column_map, units=mapping.units, only=only)
    t = np.asarray(frame.index, dtype=np.float64)
    if sample_rate is not None:
        if not sample_rate > 0:
            raise InvalidInputError(f"--sample-rate must be > 0 Hz; got {sample_rate}")
        t = (t - t[0]) / sample_rate if TIME_COLUMN in names else np.arange(t.size) / sample_rate
    return t, {c: frame[c].to_numpy() for c in frame.columns}


def _read_without_time(data: Path, mapping: Any) -> Any:
    """Read a CSV without a time column: a row index is added in a temporary copy."""
    import tempfile

    from imucalib.io.csv_import import read_imu_csv

    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp) / data.name
        with open(data, encoding="utf-8-sig") as src, open(copy, "w", encoding="utf-8") as dst:
            dst.write("time_s," + src.readline())
            for k, line in enumerate(src):
                if line.strip():
                    dst.write(f"{k},{line}")
        only = None if mapping.only is None else ("time_s", *mapping.only)
        return read_imu_csv(copy, column_map=mapping.column_map, units=mapping.units, only=only)


@app.command()
def allan(
    data: Annotated[Path, typer.Argument(help="Static log: CSV (incl. rostopic echo -p) or .h5.")],
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Folder for the results.")]
    = None,
    column_map: Annotated[str | None, typer.Option(
        "--column-map", help="Vendor names: GyrX=gyro_x_rps,AccX=accel_x_mps2,…")] = None,
    units: Annotated[str | None, typer.Option(
        "--units", help="Units of columns: gyro_x_rps=deg/s,…")] = None,
    gyro_unit: Annotated[str | None, typer.Option(help="Unit of every gyro column.")] = None,
    accel_unit: Annotated[str | None, typer.Option(help="Unit of every accel column.")] = None,
    sample_rate: Annotated[float | None, typer.Option(
        help="Sample rate [Hz] when the time column is missing or a sample index.")] = None,
    time_column: Annotated[str | None, typer.Option(help="Name of the time column.")] = None,
    time_unit: Annotated[str | None, typer.Option(help="Unit of the time column: ns|us|ms|s.")]
    = None,
    imu: Annotated[str | None, typer.Option(help="IMU stream of a recording.")] = None,
) -> None:
    """Allan deviations and noise terms of a static log, without a plan (docs/noise.md)."""
    from imucalib.exports.outputs import write_outputs
    from imucalib.procedures.allan.analysis import analyze_allan_arrays, analyze_allan_recording
    from imucalib.report.console import render_result

    try:
        if data.suffix.lower() in (".h5", ".hdf5"):
            result = analyze_allan_recording(data, unit=imu)
        else:
            t, cols = _read_csv(data, column_map, units, gyro_unit, accel_unit, time_column,
                                time_unit, sample_rate)
            result = analyze_allan_arrays(t, cols, source=str(data), unit=imu or "imu")
        folder = out if out is not None else data.parent
        try:
            folder.mkdir(parents=True, exist_ok=True)
            formats = ["noise-json", "noise-table", "figures"]
            seg = result.segments[0]
            if seg.fits("gyro") and seg.fits("accel"):
                formats[1:1] = ["kalibr-yaml", "openvins-yaml"]
            written = write_outputs(result, folder, formats, name=data.stem)
        except OSError as exc:
            raise InvalidInputError(f"cannot write the outputs into {folder}: "
                                    f"{exc.strerror or exc}") from exc
    except CalibrationError as exc:
        raise fail(exc) from exc
    render_result(console, result, written)
