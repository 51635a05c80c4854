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
from imucalib.cli._import_options import ImportOptions, with_import_options
from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["allan"]


@app.command()
@with_import_options
def allan(
    data: Annotated[Path, typer.Argument(help="Static log: CSV (incl. rostopic echo -p) or .h5.")],
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Folder for the results.")]
    = None,
    *,
    import_options: ImportOptions,
    imu: Annotated[str | None, typer.Option(help="IMU stream of a recording.")] = None,
) -> None:
    """Allan deviations and noise terms of a static log, without a plan (docs/noise.md)."""
    from imucalib.exports.outputs import write_outputs
    from imucalib.procedures import registry
    from imucalib.procedures.allan.analysis import analyze_allan_arrays, analyze_allan_recording

    try:
        if data.suffix.lower() in (".h5", ".hdf5"):
            result = analyze_allan_recording(data, unit=imu)
        else:
            import numpy as np

            from imucalib.io.import_spec import read_imu_table

            frame = read_imu_table(data, import_options.spec())
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
    registry.get(result.procedure).render_console(console, result, written)
