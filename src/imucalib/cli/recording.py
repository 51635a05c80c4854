"""Commands on Recordings: ``inspect``, ``recover`` and ``export``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

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
from imucalib.cli._progress import QUIET_HELP, progress_bar
from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["export", "inspect", "recover", "segments"]


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
    step_file: Annotated[Path | None, typer.Option(
        "--step-file", help="Also write the recording's steps as a step file (TOML) here: "
                            "with the CSV, `imucalib calibrate CSV --steps FILE` calibrates "
                            "it (docs/import.md).")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help=QUIET_HELP)] = False,
) -> None:
    """Export a stream, or one step of it, as CSV or MAT (chosen by the file suffix)."""
    from imucalib.exports.streams import export_csv, export_mat
    from imucalib.io.reader import open_recording
    from imucalib.io.step_file import step_file_from_recording, step_file_to_toml

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
                with progress_bar(f"export {stream}", quiet=quiet) as update:
                    export_csv(rec, device, unit, out, step=step, progress=update)
            else:
                export_mat(rec, device, unit, out, step=step)
            if step_file is not None:
                text = step_file_to_toml(step_file_from_recording(
                    rec, unit if device == "imu" else None))
                _write_text(step_file, text, "--step-file")
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"wrote {out}", highlight=False)
    if step_file is not None:
        console.print(f"wrote {step_file}", highlight=False)


def _write_text(path: Path, text: str, option: str) -> None:
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise InvalidInputError(f"cannot write {option} {path}: {exc.strerror or exc}") from exc


@app.command("import")
def import_csv(
    data: Annotated[Path, typer.Argument(help="IMU samples (CSV with time_s and the six gyro "
                                              "and accelerometer columns).")],
    steps: Annotated[Path, typer.Option("--steps", help="Step file (TOML): what each interval "
                                                        "is (docs/import.md).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Recording to write (.h5).")],
    unit: Annotated[str | None, typer.Option(help="The IMU's name (default: the step file's "
                                                  "`unit`, else the CSV's stem).")] = None,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing --out.")] = False,
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
) -> None:
    """Make a Recording from a CSV and its step file, to calibrate like a planned run."""
    from imucalib.io.csv_recording import recording_from_csv
    from imucalib.io.step_file import load_step_file

    try:
        spec = import_spec_from_options(
        import_file, column_map=column_map, units=units, gyro_unit=gyro_unit,
        accel_unit=accel_unit, gyro_scale=gyro_scale, accel_scale=accel_scale,
        gyro_offset=gyro_offset, accel_offset=accel_offset, time_column=time_column,
        time_unit=time_unit, sample_rate_hz=sample_rate_hz, delimiter=delimiter,
        skip_rows=skip_rows, accel_file=accel_file)
        step_file = load_step_file(steps)
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InvalidInputError(f"cannot create {out.parent}: {exc.strerror or exc}") from exc
        recording_from_csv(data, step_file, out, unit=unit, overwrite=overwrite,
                           step_file_text=steps.read_text(encoding="utf-8"), spec=spec)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"wrote {out}: {len(step_file.used_steps)} steps from {steps}; the table "
                  "stream is reconstructed from the commanded states", highlight=False)


def _imu_arrays(path: Path, unit: str | None, spec: Any = None) -> tuple[str, Any, Any, Any]:
    """(source label, time [s], gyro [rad/s], accel [m/s²] or None) of a CSV file or Recording."""
    import numpy as np

    from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS

    if path.suffix.lower() in (".h5", ".hdf5"):
        from imucalib.io.reader import open_recording
        from imucalib.io.streams import DEVICE_IMU

        with open_recording(path) as rec:
            units = [s.unit for s in rec.streams if s.device == DEVICE_IMU]
            if not units:
                raise InvalidInputError(f"{path}: the Recording has no IMU stream")
            chosen = unit or units[0]
            if chosen not in units:
                raise InvalidInputError(f"{path}: no IMU {chosen!r}; the Recording has {units}")
            data = rec.read_stream(DEVICE_IMU, chosen)
            gyro = np.column_stack([data.columns[c] for c in GYRO_COLUMNS])
            accel = np.column_stack([data.columns[c] for c in ACCEL_COLUMNS])
            time_s = data.time_s
            if "counter" in data.columns and time_s.size >= 3:
                # receive times come in bursts (equal times); the counter gives each sample
                # its own time on the same clock (docs/drivers.md, time synchronisation)
                from imucalib.processing import reconstruct_time_base

                time_s = reconstruct_time_base(data.columns["counter"], time_s).time_s
            return f"{path} IMU {chosen}", time_s, gyro, accel
    from imucalib.io.import_spec import read_imu_table

    df = read_imu_table(path, spec)
    missing = [c for c in GYRO_COLUMNS if c not in df.columns]
    if missing:
        raise InvalidInputError(
            f"{path}: segmentation needs the gyro columns {list(GYRO_COLUMNS)}; missing "
            f"{missing} (found {list(df.columns)}); map the file's columns with `--column-map "
            "gx=NAME,gy=NAME,gz=NAME,ax=NAME,…` and give `--gyro-unit` (docs/import.md)")
    accel_cols = [c for c in ACCEL_COLUMNS if c in df.columns]
    if 0 < len(accel_cols) < 3:
        raise InvalidInputError(f"{path}: the accelerometer columns must all be present "
                                f"({list(ACCEL_COLUMNS)}) or none; found only {accel_cols}")
    accel_csv = df[list(ACCEL_COLUMNS)].to_numpy() if len(accel_cols) == 3 else None
    return str(path), df.index.to_numpy(dtype=float), df[list(GYRO_COLUMNS)].to_numpy(), accel_csv


@app.command()
def segments(
    path: Annotated[Path, typer.Argument(help="IMU data: a CSV file or a Recording (.h5).")],
    unit: Annotated[str | None, typer.Option(help="IMU unit of a Recording (default: the "
                                                  "first).")] = None,
    window_s: Annotated[float, typer.Option(help="Moving-window length [s].")] = 1.0,
    min_static_s: Annotated[float, typer.Option(help="Shortest static segment kept [s].")] = 2.0,
    min_rotating_s: Annotated[float, typer.Option(
        help="Shortest rotating segment kept [s].")] = 2.0,
    json_out: Annotated[Path | None, typer.Option("--json", help="Also write the segments "
                                                                 "as JSON here.")] = None,
    step_file: Annotated[Path | None, typer.Option(
        "--step-file", help="Also write a step file skeleton here (TOML, every interval "
                            "'skip'): label the intervals, then `imucalib calibrate DATA "
                            "--steps FILE` (docs/import.md).")] = None,
) -> None:
    """Find the static and constant-rate intervals of IMU data that has no step records."""
    import json

    import numpy as np
    from rich.table import Table

    from imucalib import units
    from imucalib.processing import detect_segments

    try:
        label, t, gyro, accel = _imu_arrays(path, unit)
        result = detect_segments(t, gyro, accel_mps2=accel, window_s=window_s,
                                 min_static_s=min_static_s, min_rotating_s=min_rotating_s)
    except (CalibrationError, OSError) as exc:
        raise fail(exc) from exc
    table = Table(title=f"{len(result.segments)} segments in {label}")
    for col in ("#", "kind", "start [s]", "end [s]", "duration [s]", "samples",
                "mean rate [°/s]", "mean force [g]"):
        table.add_column(col, justify="left" if col == "kind" else "right")
    rows = []
    for i, seg in enumerate(result.segments):
        rate_dps = np.asarray(seg.mean_rate_rps) / units.DEG_PER_S
        force_g = (None if seg.mean_specific_force_mps2 is None
                   else np.asarray(seg.mean_specific_force_mps2) / units.G0_MPS2)
        table.add_row(str(i), seg.kind, f"{seg.start_time_s:.3f}", f"{seg.end_time_s:.3f}",
                      f"{seg.duration_s:.3f}", str(seg.n_samples),
                      " ".join(f"{v:+.4f}" for v in rate_dps),
                      "" if force_g is None else " ".join(f"{v:+.5f}" for v in force_g))
        rows.append({"kind": seg.kind, "start_index": seg.start_index,
                     "stop_index": seg.stop_index, "start_time_s": seg.start_time_s,
                     "end_time_s": seg.end_time_s,
                     "mean_rate_rps": [float(v) for v in seg.mean_rate_rps],
                     "mean_specific_force_mps2": None if seg.mean_specific_force_mps2 is None
                     else [float(v) for v in seg.mean_specific_force_mps2]})
    console.print(table)
    console.print(f"gyro noise floor {result.gyro_noise_floor_rps / units.DEG_PER_S:.3g} °/s per "
                  f"{window_s:g} s window; steady below "
                  f"{result.steady_threshold_rps / units.DEG_PER_S:.3g} °/s; static below "
                  f"{result.static_rate_threshold_rps / units.DEG_PER_S:.3g} °/s", highlight=False)
    if json_out is not None:
        doc = {"source": label, "window_samples": result.window_samples,
               "gyro_noise_floor_rps": result.gyro_noise_floor_rps,
               "steady_threshold_rps": result.steady_threshold_rps,
               "static_rate_threshold_rps": result.static_rate_threshold_rps, "segments": rows}
        try:
            json_out.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
        except OSError as exc:
            raise fail(InvalidInputError(f"cannot write --json {json_out}: "
                                         f"{exc.strerror or exc}")) from exc
        console.print(f"wrote {json_out}", highlight=False)
    if step_file is not None:
        from imucalib.io.step_file import step_file_skeleton

        text = step_file_skeleton([(seg.kind, float(seg.start_time_s), float(seg.end_time_s))
                                   for seg in result.segments], unit=unit)
        try:
            _write_text(step_file, text, "--step-file")
        except CalibrationError as exc:
            raise fail(exc) from exc
        console.print(f"wrote {step_file}", highlight=False)
