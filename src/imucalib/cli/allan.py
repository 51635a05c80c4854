"""``imucalib allan DATA``: noise characterisation of a bare static log (CSV or Recording).

No plan is needed: a CSV (canonical names, a ``--column-map``, or a ``rostopic echo -p`` export,
detected by :mod:`imucalib.io.csv_layouts`) or a Recording is analysed as one static record by
the Allan procedure's own analysis (:mod:`imucalib.procedures.allan.analysis`) and written by
:func:`imucalib.exports.outputs.write_outputs` (docs/noise.md, "imucalib allan").
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from imucalib.cli._app import app, console, fail
from imucalib.cli._import_options import (
    AccelFile,
    AccelOffset,
    AccelScale,
    AccelUnit,
    ColumnMap,
    Delimiter,
    GyroOffset,
    GyroScale,
    GyroUnit,
    ImportFile,
    SampleRate,
    SkipRows,
    TimeColumn,
    TimeUnit,
    Units,
    import_spec_from_options,
)
from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["allan"]


@app.command()
def allan(
    data: Annotated[Path, typer.Argument(help="Static log: CSV (incl. rostopic echo -p) or .h5.")],
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Folder for the results.")]
    = None,
    import_file: ImportFile = None,
    column_map: ColumnMap = None,
    units: Units = None,
    gyro_unit: GyroUnit = None,
    accel_unit: AccelUnit = None,
    gyro_scale: GyroScale = None,
    accel_scale: AccelScale = None,
    gyro_offset: GyroOffset = None,
    accel_offset: AccelOffset = None,
    time_column: TimeColumn = None,
    time_unit: TimeUnit = None,
    sample_rate_hz: SampleRate = None,
    delimiter: Delimiter = None,
    skip_rows: SkipRows = None,
    accel_file: AccelFile = None,
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
            import numpy as np

            from imucalib.io.import_spec import read_imu_table

            frame = read_imu_table(data, import_spec_from_options(
                    import_file, column_map=column_map, units=units, gyro_unit=gyro_unit,
                    accel_unit=accel_unit, gyro_scale=gyro_scale, accel_scale=accel_scale,
                    gyro_offset=gyro_offset, accel_offset=accel_offset, time_column=time_column,
                    time_unit=time_unit, sample_rate_hz=sample_rate_hz, delimiter=delimiter,
                    skip_rows=skip_rows, accel_file=accel_file))
            t = np.asarray(frame.index, dtype=np.float64)
            cols = {c: frame[c].to_numpy() for c in frame.columns}
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
