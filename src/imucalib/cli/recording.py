"""Commands on Recordings: ``inspect``, ``recover``, ``compact``, ``export``, ``import``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from imucalib.cli._app import app, console, fail
from imucalib.cli._import_options import ImportOptions, with_import_options
from imucalib.cli._progress import QUIET_HELP, progress_bar
from imucalib.errors import CalibrationError, InvalidInputError

__all__ = ["compact", "export", "inspect", "recover", "segments"]

_COMPRESSION_HELP = (
    "gzip (the default: HDF5's shuffle + deflate, which every HDF5 tool reads: h5py, MATLAB, "
    "HDFView, Octave), blosc-lz4 or blosc-zstd (faster, but readable outside imucalib only with "
    "the HDF5 Blosc plugin), lzf or none (docs/recording-format.md, Size and compression).")


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
    compression: Annotated[str | None, typer.Option(
        "--compression", metavar="NAME",
        help="Compression of the copy's columns: " + _COMPRESSION_HELP)] = None,
) -> None:
    """Copy what a crashed writer flushed into a new, cleanly closed Recording."""
    from imucalib.io.compression import DEFAULT_COMPRESSION, compression_from_name
    from imucalib.io.recover import recover_recording

    try:
        codec = (DEFAULT_COMPRESSION if compression is None
                 else compression_from_name(compression, "--compression"))
        report = recover_recording(path, out, compression=codec)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(report.summary(), highlight=False)


@app.command()
def compact(
    path: Annotated[Path, typer.Argument(metavar="FILE",
                                         help="A cleanly closed Recording (.h5).")],
    compression: Annotated[str | None, typer.Option(
        "--compression", metavar="NAME",
        help="The compression to convert to: " + _COMPRESSION_HELP)] = None,
) -> None:
    """Rewrite a closed Recording in place with another compression of its columns.

    For instance ``--compression gzip`` makes a Blosc-compressed file readable by every HDF5
    tool. The copy is written beside the file, verified (every check of opening, every column's
    SHA-256) and only then renamed over it; the values do not change.
    """
    from imucalib.io.compression import DEFAULT_COMPRESSION, compression_from_name
    from imucalib.io.recover import compact_recording
    from imucalib.io.storage import format_bytes

    try:
        codec = (DEFAULT_COMPRESSION if compression is None
                 else compression_from_name(compression, "--compression"))
        before = path.stat().st_size if path.is_file() else 0
        had = compact_recording(path, codec)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"compacted {path}: {had or 'none'} → {codec or 'none'}, "
                  f"{format_bytes(before)} → {format_bytes(path.stat().st_size)}",
                  highlight=False, soft_wrap=True)


@app.command()
def export(
    path: Annotated[Path, typer.Argument(help="Recording (.h5), or a result (.result.json) "
                                              "with --format.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output file (.csv or .mat); for a "
                                                          "result, a folder.")],
    stream: Annotated[str | None, typer.Option(
        help="Stream as DEVICE/UNIT, e.g. imu/IMU-0001 (a recording).")] = None,
    fmt: Annotated[str | None, typer.Option(
        "--format", help="For a result: result-json (the result file, format version 4), "
                         "parameters-csv, report-pdf, report-html, c-runtime (a C99 header "
                         "and library that apply it in firmware, docs/c-runtime.md), mat, "
                         "mat73, ros-yaml, kalibr-imu or openvins-imu (docs/exports.md).")]
    = None,
    temperature: Annotated[float | None, typer.Option(
        "--temperature", help="For a result with temperature models and --format kalibr-imu or "
                              "openvins-imu: the temperature (°C) to evaluate the parameters "
                              "at; those formats hold constant intrinsics "
                              "(docs/exports.md).")] = None,
    drop_terms: Annotated[bool, typer.Option(
        "--drop-terms", help="For --format kalibr-imu or openvins-imu: write a result whose "
                             "accelerometer K2 or K3 those tools' models lack without "
                             "them; the file "
                             "states the error left (docs/exports.md). Refused otherwise, with "
                             "that error.")] = False,
    step: Annotated[int | None, typer.Option(help="Only this step's valid window.")] = None,
    step_file: Annotated[Path | None, typer.Option(
        "--step-file", help="Also write the recording's steps as a step file (TOML) here: "
                            "with the CSV, `imucalib calibrate CSV --steps FILE` calibrates "
                            "it (docs/import.md).")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help=QUIET_HELP)] = False,
) -> None:
    """Export a stream (or one step of it) as CSV or MAT, or a result in another format.

    A recording's stream goes to CSV or MAT by the file suffix; a calibration result
    (``.result.json``) to ``--format`` (the C99 runtime, docs/c-runtime.md).
    """
    from imucalib.exports.streams import export_csv, export_mat
    from imucalib.io.opening import open_recording
    from imucalib.io.step_file import step_file_from_recording, step_file_to_toml

    if path.suffix.lower() == ".json" or fmt is not None:
        _export_result(path, out, fmt, temperature, drop_terms)
        return
    if drop_terms:
        raise fail(InvalidInputError("--drop-terms is for a result exported with --format "
                                     "kalibr-imu or openvins-imu, not a recording"))
    if temperature is not None:
        raise fail(InvalidInputError("--temperature is for a result exported with --format "
                                     "kalibr-imu or openvins-imu, not a recording"))
    if stream is None:
        raise fail(InvalidInputError("--stream DEVICE/UNIT is needed to export a recording"))

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


def _export_result(path: Path, out: Path, fmt: str | None, temperature_degc: float | None,
                   drop_terms: bool = False) -> None:
    """Write a result file in `fmt` into the folder `out` (at `temperature_degc`)."""
    from imucalib.exports.outputs import OUTPUT_FORMATS, TEMPERATURE_FORMATS, write_outputs
    from imucalib.models.result_document import load_result

    allowed = tuple(f for f in OUTPUT_FORMATS if f != "report-json")
    try:
        if fmt not in allowed:
            raise InvalidInputError(f"--format must be one of {', '.join(allowed)} for a "
                                    f"result; got {fmt!r}")
        if temperature_degc is not None and fmt not in TEMPERATURE_FORMATS:
            raise InvalidInputError(
                f"--temperature applies to --format {' or '.join(TEMPERATURE_FORMATS)} only; "
                f"{fmt} holds the result as it is (mat, mat73 and ros-yaml carry its "
                "temperature models)")
        if drop_terms and fmt not in TEMPERATURE_FORMATS:
            raise InvalidInputError(
                f"--drop-terms applies to --format {' or '.join(TEMPERATURE_FORMATS)} only "
                f"(their tools' models lack K2 and K3); {fmt} holds every term of the result")
        result = load_result(path)
        out.mkdir(parents=True, exist_ok=True)
        written = write_outputs(result, out, formats=(fmt,), name=path.name.split(".")[0],
                                temperature_degc=temperature_degc, drop_terms=drop_terms)
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(InvalidInputError(f"cannot write into {out}: {exc.strerror or exc}")) from exc
    console.print("wrote " + ", ".join(str(p) for p in written), highlight=False)


def _write_text(path: Path, text: str, option: str) -> None:
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise InvalidInputError(f"cannot write {option} {path}: {exc.strerror or exc}") from exc


@app.command("import")
@with_import_options
def import_csv(
    data: Annotated[Path, typer.Argument(help="IMU samples (CSV with time_s and the six gyro "
                                              "and accelerometer columns).")],
    steps: Annotated[Path, typer.Option("--steps", help="Step file (TOML): what each interval "
                                                        "is (docs/import.md).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Recording to write (.h5).")],
    unit: Annotated[str | None, typer.Option(help="The IMU's name (default: the step file's "
                                                  "`unit`, else the CSV's stem).")] = None,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing --out.")] = False,
    *,
    import_options: ImportOptions,
) -> None:
    """Make a Recording from a CSV and its step file, to calibrate like a planned run.

    The step file may give any procedure's roles (`imucalib procedures NAME` lists them); a role
    its procedure does not have is refused before anything is written.
    """
    from imucalib.io.csv_recording import recording_from_csv
    from imucalib.io.step_file import load_step_file
    from imucalib.procedures import registry

    try:
        spec = import_options.spec()
        step_file = load_step_file(steps)
        registry.check_roles(s.role for s in step_file.used_steps)
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InvalidInputError(f"cannot create {out.parent}: {exc.strerror or exc}") from exc
        recording_from_csv(data, step_file, out, unit=unit, overwrite=overwrite,
                           step_file_text=steps.read_text(encoding="utf-8"), spec=spec)
    except CalibrationError as exc:
        raise fail(exc) from exc
    table = "; the table stream is reconstructed from the commanded states"
    console.print(f"wrote {out}: {len(step_file.used_steps)} steps from {steps}"
                  + (table if step_file.has_table else ""), highlight=False)


def _imu_arrays(path: Path, unit: str | None, spec: Any = None) -> tuple[str, Any, Any, Any]:
    """(source label, time [s], gyro [rad/s], accel [m/s²] or None) of a CSV file or Recording."""
    import numpy as np

    from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS

    if path.suffix.lower() in (".h5", ".hdf5"):
        from imucalib.io.opening import open_recording
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
@with_import_options
def segments(
    path: Annotated[Path, typer.Argument(help="IMU data: a CSV/text file or a Recording (.h5).")],
    unit: Annotated[str | None, typer.Option(help="IMU unit of a Recording (default: the "
                                                  "first).")] = None,
    detector: Annotated[str, typer.Option(
        help="'table': static and constant-rate intervals of a planned run (a rate threshold); "
             "'variance': static intervals by the accelerometer and gyro variance (Tedaldi et "
             "al. 2014), independent of the gyro bias, and the hand rotations between them "
             "with their integrated angles (docs/import.md).")] = "table",
    window_s: Annotated[float | None, typer.Option(
        help="Moving-window length [s] (default 1 for table, 0.5 for variance).")] = None,
    min_static_s: Annotated[float | None, typer.Option(
        help="Shortest static segment kept [s] (default 2 for table, 1 for variance).")] = None,
    min_rotating_s: Annotated[float, typer.Option(
        help="Shortest rotating segment kept [s] (table).")] = 2.0,
    static_threshold: Annotated[float | None, typer.Option(
        help="Variance: static below this multiple of the initial static interval's "
             "variance (default: chosen as Tedaldi et al. do, by the smallest gravity-norm "
             "χ²/ν of the poses it finds; docs/field.md).")] = None,
    init_static_s: Annotated[float, typer.Option(
        help="Variance: length of the initial static interval at the start of the log [s].")]
    = 2.0,
    min_rotation_deg: Annotated[float, typer.Option(
        help="Variance: smallest integrated angle reported as a rotation [°].")] = 5.0,
    figure: Annotated[Path | None, typer.Option(
        "--figure", help="Also draw the signals with the intervals shaded here (PNG).")] = None,
    json_out: Annotated[Path | None, typer.Option("--json", help="Also write the segments "
                                                                 "as JSON here.")] = None,
    step_file: Annotated[Path | None, typer.Option(
        "--step-file", help="Also write a step file skeleton here (TOML, every interval "
                            "'skip'): label the intervals, then `imucalib calibrate DATA "
                            "--steps FILE` (docs/import.md).")] = None,
    *,
    import_options: ImportOptions,
) -> None:
    """Find the static and rotating intervals of IMU data that has no step records."""
    from imucalib.processing import detect_segments

    try:
        if detector not in ("table", "variance"):
            raise InvalidInputError(f"--detector must be 'table' or 'variance'; got {detector!r}")
        spec = import_options.spec()
        label, t, gyro, accel = _imu_arrays(path, unit, spec)
        if detector == "variance":
            if accel is None:
                raise InvalidInputError(f"{path}: --detector variance needs the accelerometer "
                                        "columns (map them with --column-map ax=…,ay=…,az=…)")
            import numpy as np

            from imucalib.models.earth import normal_gravity_mps2
            from imucalib.procedures.common.static_intervals import FieldLog, find_intervals

            found = find_intervals(
                FieldLog(unit or label, label, np.asarray(t, dtype=float),
                         np.asarray(gyro, dtype=float), np.asarray(accel, dtype=float)),
                threshold_factor=static_threshold,
                window_s=0.5 if window_s is None else window_s, init_static_s=init_static_s,
                min_static_s=1.0 if min_static_s is None else min_static_s,
                min_rotation_deg=min_rotation_deg, gravity_mps2=normal_gravity_mps2(45.0))
            _report_variance(found, label, json_out, step_file, unit, figure, t, gyro, accel,
                             static_threshold is not None)
            return
        win = 1.0 if window_s is None else window_s
        result = detect_segments(t, gyro, accel_mps2=accel, window_s=win,
                                 min_static_s=2.0 if min_static_s is None else min_static_s,
                                 min_rotating_s=min_rotating_s)
        _report_table(result, label, win, json_out, step_file, unit, figure, t, gyro, accel)
    except (CalibrationError, OSError) as exc:
        raise fail(exc) from exc


def _segment_row(seg: Any) -> dict[str, Any]:
    return {"kind": seg.kind, "start_index": seg.start_index, "stop_index": seg.stop_index,
            "start_time_s": seg.start_time_s, "end_time_s": seg.end_time_s,
            "mean_rate_rps": [float(v) for v in seg.mean_rate_rps],
            "mean_specific_force_mps2": None if seg.mean_specific_force_mps2 is None
            else [float(v) for v in seg.mean_specific_force_mps2]}


def _write_outputs(doc: dict[str, Any], intervals: list[tuple[str, float, float]],
                   json_out: Path | None, step_file: Path | None, unit: str | None) -> None:
    import json

    if json_out is not None:
        try:
            json_out.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
        except OSError as exc:
            raise InvalidInputError(f"cannot write --json {json_out}: "
                                    f"{exc.strerror or exc}") from exc
        console.print(f"wrote {json_out}", highlight=False)
    if step_file is not None:
        from imucalib.io.step_file import step_file_skeleton

        _write_text(step_file, step_file_skeleton(intervals, unit=unit), "--step-file")
        console.print(f"wrote {step_file}", highlight=False)


def _save_figure(figure: Path, **kwargs: Any) -> None:
    from imucalib.report.segments_figure import save_segments_figure

    try:
        save_segments_figure(figure, **kwargs)
    except OSError as exc:
        raise InvalidInputError(f"cannot write --figure {figure}: {exc.strerror or exc}") from exc
    console.print(f"wrote {figure}", highlight=False)


def _report_table(result: Any, label: str, window_s: float, json_out: Path | None,
                  step_file: Path | None, unit: str | None, figure: Path | None,
                  t: Any, gyro: Any, accel: Any) -> None:
    import numpy as np
    from rich.table import Table

    from imucalib import units

    table = Table(title=f"{len(result.segments)} segments in {label}")
    for col in ("#", "kind", "start [s]", "end [s]", "duration [s]", "samples",
                "mean rate [°/s]", "mean force [g]"):
        table.add_column(col, justify="left" if col == "kind" else "right")
    for i, seg in enumerate(result.segments):
        rate_dps = np.asarray(seg.mean_rate_rps) / units.DEG_PER_S
        force_g = (None if seg.mean_specific_force_mps2 is None
                   else np.asarray(seg.mean_specific_force_mps2) / units.G0_MPS2)
        table.add_row(str(i), seg.kind, f"{seg.start_time_s:.3f}", f"{seg.end_time_s:.3f}",
                      f"{seg.duration_s:.3f}", str(seg.n_samples),
                      " ".join(f"{v:+.4f}" for v in rate_dps),
                      "" if force_g is None else " ".join(f"{v:+.5f}" for v in force_g))
    console.print(table)
    console.print(f"gyro noise floor {result.gyro_noise_floor_rps / units.DEG_PER_S:.3g} °/s per "
                  f"{window_s:g} s window; steady below "
                  f"{result.steady_threshold_rps / units.DEG_PER_S:.3g} °/s; static below "
                  f"{result.static_rate_threshold_rps / units.DEG_PER_S:.3g} °/s", highlight=False)
    if not result.static and accel is not None:
        console.print("no static interval below the rate threshold: for a hand-held log, or a "
                      "gyro bias above it, try `--detector variance` (independent of the bias)",
                      highlight=False)
    doc = {"source": label, "detector": "table", "window_samples": result.window_samples,
           "gyro_noise_floor_rps": result.gyro_noise_floor_rps,
           "steady_threshold_rps": result.steady_threshold_rps,
           "static_rate_threshold_rps": result.static_rate_threshold_rps,
           "segments": [_segment_row(seg) for seg in result.segments]}
    _write_outputs(doc, [(seg.kind, float(seg.start_time_s), float(seg.end_time_s))
                         for seg in result.segments], json_out, step_file, unit)
    if figure is not None:
        _save_figure(figure, time_s=t, gyro_rps=gyro, accel_mps2=accel,
                     static=[(s.start_time_s, s.end_time_s) for s in result.static],
                     rotating=[(s.start_time_s, s.end_time_s) for s in result.rotating],
                     title=f"{label}: table detector")


def _report_variance(found: Any, label: str, json_out: Path | None, step_file: Path | None,
                     unit: str | None, figure: Path | None, t: Any, gyro: Any,
                     accel: Any, static_threshold_given: bool = True) -> None:
    import numpy as np
    from rich.table import Table

    from imucalib import units

    table = Table(title=f"{len(found.static)} static intervals and {len(found.rotations)} "
                        f"rotations in {label}")
    for col in ("#", "kind", "start [s]", "end [s]", "duration [s]", "mean rate [°/s]",
                "mean force [g] / angle [°]"):
        table.add_column(col, justify="left" if col == "kind" else "right")
    items = sorted([(s.start_time_s, "static", s) for s in found.static]
                   + [(r.start_time_s, "rotating", r) for r in found.rotations],
                   key=lambda item: (item[0], item[1] == "static"))
    rows = []
    for i, (_, kind, x) in enumerate(items):
        if kind == "static":
            rate = " ".join(f"{v:+.4f}" for v in np.asarray(x.mean_rate_rps) / units.DEG_PER_S)
            last = " ".join(f"{v:+.5f}" for v in
                            np.asarray(x.mean_specific_force_mps2) / units.G0_MPS2)
            rows.append(_segment_row(x))
        else:
            rate = ""
            last = " ".join(f"{v:+.2f}" for v in np.rad2deg(x.angle_rad)) + \
                f" (‖θ‖ {np.rad2deg(x.angle_norm_rad):.2f})"
            rows.append({"kind": "rotating", "start_index": x.start_index,
                         "stop_index": x.stop_index, "start_time_s": x.start_time_s,
                         "end_time_s": x.end_time_s,
                         "angle_rad": [float(v) for v in x.angle_rad],
                         "angle_deg": float(np.rad2deg(x.angle_norm_rad)),
                         "bias_rps": [float(v) for v in x.bias_rps]})
        table.add_row(str(i), kind, f"{x.start_time_s:.3f}", f"{x.end_time_s:.3f}",
                      f"{x.duration_s:.3f}", rate, last)
    console.print(table)
    chosen = "" if static_threshold_given else " (chosen by the smallest gravity-norm χ²/ν)"
    console.print(f"static where the accelerometer variance is below {found.threshold_factor:g} × "
                  f"that of the initial static interval ({found.accel_threshold:.3g} (m/s²)²; "
                  f"gyro {found.gyro_threshold:.3g} (rad/s)²), window {found.window_samples} "
                  f"samples{chosen}", highlight=False)
    doc = {"source": label, "detector": "variance", "window_samples": found.window_samples,
           "threshold_factor": found.threshold_factor,
           "accel_variance_threshold": found.accel_threshold,
           "gyro_variance_threshold": found.gyro_threshold, "segments": rows}
    _write_outputs(doc, [(r["kind"], float(r["start_time_s"]), float(r["end_time_s"]))
                         for r in rows], json_out, step_file, unit)
    if figure is not None:
        _save_figure(figure, time_s=t, gyro_rps=gyro, accel_mps2=accel,
                     static=[(s.start_time_s, s.end_time_s) for s in found.static],
                     rotating=[(r.start_time_s, r.end_time_s) for r in found.rotations],
                     rotation_angles_deg=[np.rad2deg(r.angle_norm_rad) for r in found.rotations],
                     statistic=found.accel_variance, threshold=found.accel_threshold,
                     title=f"{label}: variance detector (Tedaldi et al. 2014)")
