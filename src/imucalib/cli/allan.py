"""``imucalib allan DATA``: noise characterisation of a bare static log (CSV or Recording).

No plan is needed: a CSV (canonical names, a ``--column-map``, or a ``rostopic echo -p`` export,
detected by :mod:`imucalib.io.csv_layouts`) or a Recording is analysed as one static record by
the Allan procedure through the one pipeline (:func:`imucalib.calibration.calibrate`): the noise
JSON, Kalibr and OpenVINS YAML (when every term they need was fitted), the datasheet table and
the figures are written, and the noise terms with their uncertainties are recorded like any
calibration (docs/noise.md, "imucalib allan").
"""

from __future__ import annotations

import getpass
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Any

import typer

from imucalib.cli._app import app, console, fail
from imucalib.cli._import_options import ImportOptions, with_import_options
from imucalib.errors import CalibrationError

__all__ = ["allan"]


def _formats(result: Any) -> Sequence[str]:
    """Return the outputs of a bare log: Kalibr/OpenVINS YAML only when both triads fit."""
    formats = ["noise-json", "noise-table", "figures"]
    seg = result.segments[0]
    if seg.fits("gyro") and seg.fits("accel"):
        formats[1:1] = ["kalibr-yaml", "openvins-yaml"]
    return formats


@app.command()
@with_import_options
def allan(
    data: Annotated[Path, typer.Argument(help="Static log: CSV (incl. rostopic echo -p) or .h5.")],
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Folder for the results.")]
    = None,
    *,
    import_options: ImportOptions,
    imu: Annotated[str | None, typer.Option(help="IMU stream of a recording.")] = None,
    db: Annotated[str | None, typer.Option(
        "--db", help="Records database (default: $IMUCALIB_DB, else records.db in the user's "
                     "data directory; docs/records.md).")] = None,
    no_record: Annotated[bool, typer.Option(
        "--no-record", help="Do not record the noise terms in the records database.")] = False,
) -> None:
    """Allan deviations and noise terms of a static log, without a plan (docs/noise.md)."""
    from imucalib.calibration import RECORDING_SUFFIXES, calibrate

    try:
        log = data.suffix.lower() not in RECORDING_SUFFIXES
        done = calibrate(data, procedure="allan",
                         options={"import_spec": import_options.spec()} if log else None,
                         unit=imu, out=out, formats=_formats, record=not no_record, db=db,
                         operator=getpass.getuser())
    except CalibrationError as exc:
        raise fail(exc) from exc
    done.procedure.render_console(console, done.result, done.written)
    if done.record_error is not None:
        raise fail(done.record_error)
    if done.record is not None:
        console.print(done.record, highlight=False, soft_wrap=True)
