"""``imucalib calibrate`` (recording → result) and ``imucalib apply`` (result → corrected data)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from imucalib import units
from imucalib.cli._app import app, console, fail
from imucalib.errors import CalibrationError, ConfigurationError, InvalidInputError

if TYPE_CHECKING:
    from imucalib.procedures.p1.analysis import P1Analysis

__all__ = ["apply", "calibrate", "render_calibration", "run_calibration"]

# display unit of each parameter symbol: (unit text, SI value of one display unit)
_DISPLAY = {
    ("accel", "bias"): ("µg", units.UG), ("accel", "b"): ("µg", units.UG),
    ("gyro", "bias"): ("°/h", units.DEG_PER_H), ("gyro", "b"): ("°/h", units.DEG_PER_H),
    ("accel", "K"): ("ppm of 1", units.PPM), ("gyro", "K"): ("ppm of 1", units.PPM),
    ("accel", "M"): ("ppm | µrad", units.PPM), ("gyro", "M"): ("ppm | µrad", units.PPM),
    ("gyro", "G"): ("(°/h)/g", units.DEG_PER_H / units.G0_MPS2),
}


def _display(name: str, value: float, sigma: float) -> tuple[str, str, str]:
    triad, symbol = name.split("_")[0], name.split("_")[1]
    unit, scale = _DISPLAY.get((triad, symbol), ("SI", 1.0))
    shown = value - 1.0 if symbol == "K" else value  # a scale factor as its deviation from 1
    return f"{shown / scale:+.4f}", f"{sigma / scale:.4f}", unit


def run_calibration(recording: Path, imu: str | None, model: str, out: Path | None
                    ) -> tuple[P1Analysis, Path, Path]:
    """Analyse a recording with its plan's procedure; write the result and the report JSON."""
    from imucalib.io.reader import open_recording
    from imucalib.plan.io import parse_plan
    from imucalib.procedures.p1.analysis import P1Options, analyze_p1

    with open_recording(recording) as rec:
        plan_toml = rec.metadata.get("plan_toml")
    if not plan_toml:
        raise ConfigurationError(f"{recording} holds no plan: `imucalib calibrate` needs a "
                                 "recording made by `imucalib run`")
    procedure = parse_plan(str(plan_toml), str(recording)).procedure
    if procedure == "allan":
        raise _AllanProcedure
    if procedure != "p1":
        raise ConfigurationError(f"{recording}: plan procedure {procedure!r} has no analysis "
                                 "here; known: p1, allan")
    if model not in ("triad", "per-axis"):
        raise InvalidInputError(f"--model must be 'triad' or 'per-axis'; got {model!r}")
    analysis = analyze_p1(recording, imu, P1Options(model=model))  # type: ignore[arg-type]
    folder = out if out is not None else recording.parent
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"{recording.stem}.{analysis.result.sensor_id}.{procedure}"
    result_path = folder / f"{stem}.result.json"
    report_path = folder / f"{stem}.report.json"
    result_path.write_text(analysis.result.to_json() + "\n", encoding="utf-8")
    report_path.write_text(json.dumps(analysis.to_dict(), indent=1, allow_nan=True) + "\n",
                           encoding="utf-8")
    return analysis, result_path, report_path


def render_calibration(analysis: P1Analysis, result_path: Path, report_path: Path) -> None:
    """Print the parameters, the checks and the decision."""
    result = analysis.result
    repeat = {r.name: r for c in analysis.checks if c.name == "repeatability" for r in c.rows}
    table = Table("parameter", "value", "std. uncertainty", "unit", "repeatability",
                  title=f"{result.sensor_id}: {result.procedure.upper()} {result.model} model")
    std = result.std()
    for name in result.param_names:
        value, sigma, unit = _display(name, result.value(name), std[name])
        row = repeat.get(name)
        rep = "—" if row is None else ("[green]pass[/]" if row.passed else "[red]FAIL[/]")
        table.add_row(name, value, sigma, unit, rep)
    console.print(table)
    checks = Table("check", "verdict", "summary", title="verification")
    for c in analysis.checks:
        verdict = ("not assessed" if c.passed is None
                   else "[green]pass[/]" if c.passed else "[red]FAIL[/]")
        checks.add_row(c.name, verdict, c.summary)
    console.print(checks)
    if not math.isnan(analysis.kalman_max_difference_sigma):
        console.print(f"Kalman refinement agrees with least squares to "
                      f"{analysis.kalman_max_difference_sigma:.2g} σ; reported σ / Cramér–Rao "
                      f"bound: {max(analysis.crlb_ratio.values()):.4f}", highlight=False)
    colour = "green" if analysis.decision.passed else "red"
    console.print(f"[bold {colour}]{analysis.decision.summary()}[/]", highlight=False)
    console.print(f"wrote {result_path}\n      {report_path}", highlight=False)


class _AllanProcedure(Exception):  # noqa: N818 - a control-flow signal, not an error
    """The recording is an Allan plan's: the noise characterisation applies."""


def run_noise_characterization(recording: Path, imu: str | None, out: Path | None
                               ) -> tuple[Any, list[Path]]:
    """Analyse an Allan recording; write its JSON, Kalibr/OpenVINS YAML, table and figures."""
    from imucalib.exports.noise import format_noise_table, write_kalibr_yaml, write_openvins_yaml
    from imucalib.procedures.allan.analysis import analyze_allan_recording
    from imucalib.report.allan_figure import save_allan_figures

    result = analyze_allan_recording(recording, unit=imu)
    folder = out if out is not None else recording.parent
    folder.mkdir(parents=True, exist_ok=True)
    stem = f"{recording.stem}.{result.unit}.allan"
    written = [result.save(folder / f"{stem}.json")]
    for i, seg in enumerate(result.segments):
        suffix = "" if len(result.segments) == 1 else f".{i}"
        params = seg.noise_parameters()
        written.append(write_kalibr_yaml(folder / f"{stem}{suffix}.kalibr.yaml", params))
        written.append(write_openvins_yaml(folder / f"{stem}{suffix}.openvins.yaml", params))
        table = folder / f"{stem}{suffix}.table.md"
        table.write_text(format_noise_table(seg.fits(), fmt="markdown") + "\n",
                         encoding="utf-8")
        written.append(table)
    written += save_allan_figures(result, folder / f"{stem}.figures")
    return result, written


def render_noise_characterization(result: Any, written: list[Path]) -> None:
    """Print each record's noise-term table and the files written."""
    from imucalib.exports.noise import format_noise_table

    for seg in result.segments:
        temp = "" if seg.temperature_degc is None else f", {seg.temperature_degc:.1f} °C"
        console.print(f"[bold]{seg.label}[/]: {seg.n_samples:,} samples at "
                      f"{seg.sample_rate_hz:g} Hz{temp}", highlight=False)
        console.print(format_noise_table(seg.fits(), fmt="text"), highlight=False,
                      soft_wrap=True)
    console.print("wrote " + "\n      ".join(str(p) for p in written), highlight=False)


@app.command()
def calibrate(
    recording: Annotated[Path, typer.Argument(help="Recording of a plan run (.h5).")],
    imu: Annotated[str | None, typer.Option(help="IMU stream (default: the only one).")] = None,
    model: Annotated[str, typer.Option(help="triad (full) or per-axis (SPEC.md P1's).")] = "triad",
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Folder for the results.")]
    = None,
) -> None:
    """Estimate every parameter with its uncertainty, verify, and write the result (JSON).

    A P1 recording gives the calibration, its checks and the decision; an Allan recording the
    noise terms (JSON, Kalibr and OpenVINS YAML, a datasheet table, figures).
    """
    try:
        try:
            analysis, result_path, report_path = run_calibration(recording, imu, model, out)
        except _AllanProcedure:
            noise, written = run_noise_characterization(recording, imu, out)
            render_noise_characterization(noise, written)
            return
    except CalibrationError as exc:
        raise fail(exc) from exc
    render_calibration(analysis, result_path, report_path)
    if not analysis.decision.passed:
        raise typer.Exit(code=1)


@app.command()
def apply(
    result_path: Annotated[Path, typer.Argument(metavar="RESULT", help="Result JSON.")],
    data: Annotated[Path, typer.Argument(help="A recording (.h5) or a CSV file.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Corrected CSV to write.")],
    imu: Annotated[str | None, typer.Option(help="IMU stream of a recording.")] = None,
) -> None:
    """Correct a recording's IMU stream, or a CSV file, with a calibration result."""
    import pandas as pd

    from imucalib.models.correct import correct_imu_frame
    from imucalib.models.result import CalibrationResult

    try:
        result = CalibrationResult.load(result_path)
        _check_out(out, result_path, data)
        n = 0
        if data.suffix.lower() in (".h5", ".hdf5"):
            from imucalib.io.reader import open_recording

            with open_recording(data) as rec:
                unit = imu or result.sensor_id
                info = rec.stream_info("imu", unit)
                with open(out, "w", encoding="utf-8") as fh:
                    for i, chunk in enumerate(rec.iter_stream("imu", unit)):
                        df = pd.DataFrame(chunk.columns,
                                          index=pd.Index(chunk.time_s, name="time_s"))
                        df.attrs["units"] = {c: s.unit for c, s in info.columns.items()}
                        fixed = correct_imu_frame(df, result)
                        _write_csv(fixed, fh, header=i == 0)
                        n += len(fixed)
        else:
            from imucalib.io.csv_import import read_imu_csv

            df = read_imu_csv(data)
            _check_triads(data, df.columns, result)
            fixed = correct_imu_frame(df, result)
            with open(out, "w", encoding="utf-8") as fh:
                _write_csv(fixed, fh, header=True)
            n = len(fixed)
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(InvalidInputError(f"cannot write {out}: {exc.strerror or exc}")) from exc
    console.print(f"wrote {out}: {n:,} corrected samples ({result.procedure} {result.model} "
                  f"result of {result.sensor_id})", highlight=False)


def _check_out(out: Path, *inputs: Path) -> None:
    """Refuse an output path that is one of the inputs (it would be truncated before read)."""
    for path in inputs:
        try:
            same = out.exists() and path.exists() and out.samefile(path)
        except OSError:
            same = False
        if same:
            raise InvalidInputError(f"--out {out} is the input file {path}; write the "
                                    "corrected data to another file")


def _check_triads(data: Path, columns: Any, result: Any) -> None:
    """Refuse data holding none of the triads the result corrects (nothing would change)."""
    from imucalib.conventions import ACCEL_COLUMNS, GYRO_COLUMNS

    wanted = {t: c for t, c in (("gyro", GYRO_COLUMNS), ("accel", ACCEL_COLUMNS))
              if result.has_triad(t)}
    if not any(c in columns for cols in wanted.values() for c in cols):
        raise InvalidInputError(
            f"{data}: none of the columns the result corrects "
            f"({', '.join(c for cols in wanted.values() for c in cols)}); found {list(columns)}")


def _write_csv(df: object, fh: object, *, header: bool) -> None:
    import pandas as pd

    assert isinstance(df, pd.DataFrame)
    units_map = df.attrs.get("units", {})
    frame = df.reset_index()
    if header:
        names = [f"{c} [{units_map.get(c, 's' if c == 'time_s' else '1')}]"
                 for c in frame.columns]
        fh.write(",".join(names) + "\n")  # type: ignore[attr-defined]
    frame.to_csv(fh, header=False, index=False, na_rep="NaN",  # type: ignore[call-overload]
                 lineterminator="\n")
