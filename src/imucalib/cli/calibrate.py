"""``imucalib calibrate`` (recording → result) and ``imucalib apply`` (result → corrected data)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from typer.core import TyperCommand

from imucalib.cli._app import app, console, err_console, fail
from imucalib.cli._import_options import ImportOptions, with_import_options
from imucalib.cli._progress import QUIET_HELP, progress_bar
from imucalib.errors import CalibrationError, InvalidInputError
from imucalib.units import DEG_PER_H, G0_MPS2

#: The exit status of a calibration that returned only part of its model (a result's
#: ``omitted`` parts: docs/procedures.md, "Exit status"); 1 is FAIL, 2 an error.
PARTIAL_EXIT_CODE = 3

if TYPE_CHECKING:
    from imucalib.io.import_spec import ImportSpec
    from imucalib.procedures.common.procedure import Procedure

__all__ = ["analysis_options", "apply", "calibrate"]


def analysis_options(procedure: Procedure, recording: Path, model: str,
                     extra: dict[str, Any] | None, settings: Sequence[str]) -> dict[str, Any]:
    """Return the analysis options the command line gave `procedure`.

    `extra` holds the options of the dedicated flags (``--latitude``, ``--gyro-form`` …; None
    when not given), refused by a procedure that does not take them; `settings` the ``--set
    NAME=VALUE`` texts, read by the procedure's analysis options
    (:func:`~imucalib.procedures.common.options.parse_assignment`).

    Raises
    ------
    InvalidInputError, ConfigurationError
        An option the procedure does not take, a value it does not read, an option given twice.
    """
    from imucalib.procedures.common.options import parse_assignment

    name = procedure.name
    options: dict[str, Any] = {"model": model} if "model" in procedure.analysis_options else {}
    given = {k: v for k, v in (extra or {}).items() if v is not None}
    refused = sorted(set(given) - set(procedure.analysis_options))
    if refused:
        raise InvalidInputError(
            f"{recording} is a {name} recording; its analysis does not take "
            f"{', '.join('--' + k.replace('_', '-') for k in refused)}")
    options.update(given)
    for text in settings:
        key, value = parse_assignment(procedure.analysis_options_type, text,
                                      what=f"the {name} analysis")
        if key in given:
            raise InvalidInputError(f"--set {key} repeats an option given by its own flag")
        options[key] = value
    return options


def import_for_calibration(data: Path, steps: Path, imu: str | None, out: Path | None,
                           spec: ImportSpec | None = None) -> tuple[Path, bool]:
    """Import a CSV and its step file into ``<out>/<stem>.imported.h5`` (replaced if there).

    `spec` (the import options: column map, units, counts, time column, header rows …) says how
    to read the CSV; None or an empty one reads it by its detected layout. The step file's roles
    are checked against the registry first (:func:`~imucalib.procedures.registry.check_roles`):
    any procedure's roles are accepted, an unknown one refused before anything is written.
    Returns the Recording and whether it holds a table stream reconstructed from the step file.
    """
    from imucalib.io.csv_recording import recording_from_csv
    from imucalib.io.import_spec import ImportSpec
    from imucalib.io.step_file import load_step_file
    from imucalib.procedures import registry

    step_file = load_step_file(steps)
    registry.check_roles(s.role for s in step_file.used_steps)
    folder = out if out is not None else data.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InvalidInputError(f"cannot create {folder}: {exc.strerror or exc}") from exc
    target = folder / f"{data.stem}.imported.h5"
    path = recording_from_csv(data, step_file, target, unit=imu, overwrite=True,
                              spec=None if spec is None or spec == ImportSpec() else spec,
                              step_file_text=steps.read_text(encoding="utf-8"))
    return path, step_file.has_table


def _pairs(given: list[str] | None, flag: str) -> dict[str, tuple[float, float]] | None:
    """Parse ``UNIT=VALUE,STD`` options into {unit: (value, std)} (None when none given)."""
    if not given:
        return None
    out = {}
    for text in given:
        unit, sep, numbers = text.partition("=")
        parts = numbers.split(",")
        try:
            if not (sep and unit.strip() and len(parts) == 2):
                raise ValueError
            out[unit.strip()] = (float(parts[0]), float(parts[1]))
        except ValueError:
            raise InvalidInputError(f"{flag} wants UNIT=VALUE,STD (e.g. REF-A=1.00002,5e-6); "
                                    f"got {text!r}") from None
    return out


def _accel_instability(text: str | None) -> dict[str, Any]:
    """``--accel-instability-ug`` as field options: a number of µg, or ``auto``."""
    if text is None:
        return {}
    if text.strip().lower() == "auto":
        return {"accel_instability_auto": True}
    try:
        value = float(text)
    except ValueError:
        raise InvalidInputError(f"--accel-instability-ug must be a number of µg or 'auto'; got "
                                f"{text!r}") from None
    return {"accel_instability_mps2": value * 1e-6 * G0_MPS2}


class _CalibrateCommand(TyperCommand):
    """``calibrate``: ``calibrate PROCEDURE --help`` adds that procedure's analysis options."""

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
        """Keep the raw arguments for the help text, then parse as usual."""
        ctx.meta["imucalib.calibrate.args"] = list(args)
        return list(super().parse_args(ctx, args))

    def format_options(self, ctx: Any, formatter: Any) -> None:
        """Write the command's options, then the named procedure's analysis options."""
        super().format_options(ctx, formatter)
        from imucalib.procedures import registry
        from imucalib.procedures.common.options import option_specs

        names = [a for a in ctx.meta.get("imucalib.calibrate.args", ())
                 if a in registry.names()]
        if not names:
            with formatter.section("A procedure's analysis options"):
                formatter.write_text("`imucalib calibrate PROCEDURE --help` lists them (given "
                                     "with --set NAME=VALUE); `imucalib procedures` lists "
                                     "the procedures.")
            return
        specs = option_specs(registry.get(names[0]).analysis_options_type)
        rows = [(f"--set {s.flag[2:]}={s.metavar()}",
                 s.help_with_default()) for s in specs if s.cli]
        rows += [(s.name, f"Python only: {s.info.python_only}") for s in specs if not s.cli]
        with formatter.section(f"Options of the {names[0]} analysis"):
            formatter.write_dl(rows or [("(none)", "this analysis takes no options")])


@app.command(cls=_CalibrateCommand)
@with_import_options
def calibrate(
    recording: Annotated[Path, typer.Argument(
        metavar="[PROCEDURE] RECORDING",
        help="Recording (.h5) of a plan run or a simulation; or a CSV with --steps; or a "
             "procedure's name and its data: `field DATA.csv` calibrates a hand-held log "
             "(docs/field.md).")],
    more: Annotated[list[Path] | None, typer.Argument(
        metavar="[MORE]...", help="Further P2 recordings calibrated with the first as one "
                                  "production lot.")] = None,
    imu: Annotated[str | None, typer.Option(help="IMU stream (default: the only one).")] = None,
    model: Annotated[str, typer.Option(help="triad (full) or per-axis (P1's simple model).")]
    = "triad",
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Folder for the results.")]
    = None,
    steps: Annotated[Path | None, typer.Option(
        "--steps", help="Step file (TOML) saying what each interval of a CSV is; the CSV is "
                        "first imported into OUT/<name>.imported.h5 (docs/import.md).")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help=QUIET_HELP)] = False,
    workers: Annotated[int | None, typer.Option(
        help="P1, P2: windows (P1) or units (P2) analysed in parallel on this many local "
             "processes; the result is the same.")] = None,
    scheduler: Annotated[str | None, typer.Option(
        help="P2: a Dask scheduler address (tcp://host:8786); the workers must see the "
             "recordings at the same paths (the dask extra).")] = None,
    lever_arm: Annotated[str | None, typer.Option(
        help="P2: estimate (default), cancel (accelerometer from static windows) or ignore "
             "the centripetal term (docs/p2.md).")] = None,
    criterion: Annotated[str | None, typer.Option(
        help="P2: how a temperature model's order is chosen: aicc (default) or cv.")] = None,
    max_order: Annotated[int | None, typer.Option(
        help="P2: the highest order of a temperature model (default 3).")] = None,
    reference_a: Annotated[str | None, typer.Option(
        help="P3: reference A's unit (default: the recording's mounting check says).")] = None,
    reference_b: Annotated[str | None, typer.Option(help="P3: reference B's unit.")] = None,
    test: Annotated[str | None, typer.Option(help="P3: the test accelerometer's unit.")] = None,
    k1: Annotated[list[str] | None, typer.Option(
        help="P3: UNIT=VALUE,STD — an accelerometer's scale factor (output per m/s²) and its "
             "standard uncertainty instead of its tumble's; repeat per unit.")] = None,
    k2_target: Annotated[float | None, typer.Option(
        help="P3: the expanded uncertainty (k = 2) K2 must reach [g/g²] (default 1e-7).")]
    = None,
    latitude: Annotated[float | None, typer.Option(
        help="field: the site's latitude [°] (local g as normal gravity there).")] = None,
    height: Annotated[float | None, typer.Option(
        help="field: the site's height above the ellipsoid [m].")] = None,
    gravity: Annotated[float | None, typer.Option(
        help="field: local g [m/s²], instead of normal gravity.")] = None,
    accel_form: Annotated[str | None, typer.Option(
        help="field: auto, gravity-norm (poses of unknown orientation) or six-position "
             "(a fixture's faces).")] = None,
    gyro_form: Annotated[str | None, typer.Option(
        help="field: auto, gravity (imu_tk), turns (Ferraris known angle) or none.")] = None,
    static_threshold: Annotated[float | None, typer.Option(
        help="field: the static detector's multiple of the initial variance (default: "
             "chosen by the smallest gravity-norm χ²/ν).")] = None,
    init_static_s: Annotated[float | None, typer.Option(
        help="field: the initial rest at the start of the log [s] (default 2).")] = None,
    accel_instability_ug: Annotated[str | None, typer.Option(
        help="field: the accelerometer's bias instability from its datasheet [µg], added to "
             "each pose's noise; 'auto': estimated from the poses' scatter (Paule–Mandel, "
             "docs/field.md).")] = None,
    gyro_instability_dph: Annotated[float | None, typer.Option(
        help="field: the gyro's bias instability from its datasheet [°/h].")] = None,
    settings: Annotated[list[str] | None, typer.Option(
        "--set", metavar="NAME=VALUE",
        help="Any option of the recording's analysis, e.g. --set noise-block-s=20; repeat it "
             "for several (`imucalib calibrate PROCEDURE --help` lists a procedure's).")]
    = None,
    db: Annotated[str | None, typer.Option(
        "--db", help="Records database (default: $IMUCALIB_DB, else records.db in the user's "
                     "data directory; docs/records.md).")] = None,
    no_record: Annotated[bool, typer.Option(
        "--no-record", help="Do not record the result in the records database.")] = False,
    reason: Annotated[str, typer.Option(
        "--reason", help="Why the data are analysed again (recorded with the result's new "
                         "version; default: the options given).")] = "",
    config: Annotated[Path | None, typer.Option(
        "--config", help="The laboratory configuration (default: $IMUCALIB_CONFIG, else "
                         "./imucalib.toml, else the user's; docs/configuration.md).")] = None,
    user: Annotated[str | None, typer.Option(
        "--user", help="Who analyses (a registered user once the records have users; "
                       "default: $IMUCALIB_USER, else the configuration's [operator] default; "
                       "docs/records.md).")] = None,
    *,
    import_options: ImportOptions,
) -> None:
    """Estimate every parameter with its uncertainty, verify, and write the result (JSON).

    The recording's procedure decides: a P1 recording gives the calibration, its checks and the
    decision; an Allan recording the noise terms (JSON, Kalibr and OpenVINS YAML, a datasheet
    table, figures); a P2 recording every unit with its temperature models; a P3 recording
    the test accelerometer's K2 on the centrifuge with the unbalance removed. A CSV is
    calibrated through its step file (--steps), or, a hand-held log, by `calibrate field
    DATA.csv` with the import options of `imucalib segments` (docs/field.md). The result is
    recorded in the records database, in the run that recorded the data (``imucalib run``;
    data no run recorded get a run of their own); a second analysis of the same data is the
    result's next version, with ``--reason`` (docs/records.md; ``--no-record`` skips it).
    """
    from imucalib.calibration import calibrate as run_pipeline
    from imucalib.calibration import procedure_of
    from imucalib.procedures import registry

    try:
        procedure_name = None
        if str(recording) in registry.names() and not recording.exists():
            procedure_name = str(recording)
            if not more:
                raise InvalidInputError(f"`imucalib calibrate {procedure_name}` needs the data "
                                        f"to calibrate: imucalib calibrate {procedure_name} "
                                        "DATA")
            recording, more = more[0], more[1:]
        extra: dict[str, Any] = {
            "workers": workers, "scheduler": scheduler, "lever_arm": lever_arm,
            "criterion": criterion, "max_order": max_order, "reference_a": reference_a,
            "reference_b": reference_b, "test": test, "k1": _pairs(k1, "--k1"),
            "k2_target_g_per_g2": k2_target, "latitude_deg": latitude, "height_m": height,
            "gravity_mps2": gravity, "accel_form": accel_form, "gyro_form": gyro_form,
            "static_threshold": static_threshold, "init_static_s": init_static_s,
            **_accel_instability(accel_instability_ug),
            "gyro_instability_rps": None if gyro_instability_dph is None
            else gyro_instability_dph * DEG_PER_H}
        if procedure_name is not None and recording.suffix.lower() not in (".h5", ".hdf5"):
            extra["import_spec"] = import_options.spec()
            if not recording.is_file():
                raise InvalidInputError(f"no such file: {recording}")
        elif procedure_name is None and steps is None and \
                recording.suffix.lower() in (".csv", ".txt", ".tsv"):
            raise InvalidInputError(f"{recording}: a CSV or other log needs --steps (a step "
                                    "file saying what each interval is, docs/import.md); "
                                    "`imucalib segments DATA --step-file FILE` writes one to "
                                    "complete; a hand-held log is calibrated by `imucalib "
                                    "calibrate field DATA` (docs/field.md)")
        if steps is not None:
            recording, table = import_for_calibration(recording, steps, imu, out,
                                                      spec=import_options.spec())
            console.print(f"imported into {recording}" + (" (table stream reconstructed from "
                          "the step file)" if table else ""), highlight=False)
        proc = procedure_of(recording, procedure_name)
        options = analysis_options(proc, recording, model, extra, settings or ())
        from imucalib.cli._user import acting_user
        from imucalib.config import use_config

        with use_config(config):
            who, who_note = acting_user(user, db=db, record=not no_record, action="calibrate")
            with progress_bar(f"calibrate {recording.name}", quiet=quiet) as update:
                done = run_pipeline(recording, procedure=proc.name, options=options, unit=imu,
                                    more=tuple(more or ()), out=out, record=not no_record,
                                    db=db, operator=who, progress=update, reason=reason)
    except CalibrationError as exc:
        raise fail(exc) from exc
    done.procedure.render_console(console, done.result, done.written)
    if done.record_error is not None:
        raise fail(done.record_error)
    if done.record is not None:
        console.print(done.record, highlight=False, soft_wrap=True)
    if who_note:
        console.print(who_note, highlight=False, soft_wrap=True, markup=False)
    if done.result.passed is False:
        raise typer.Exit(code=1)
    if done.result.omitted:
        for part in done.result.omitted:
            err_console.print(f"[yellow]partial result:[/] left out {part}", highlight=False,
                              soft_wrap=True)
        raise typer.Exit(code=PARTIAL_EXIT_CODE)


@app.command()
@with_import_options
def apply(
    result_path: Annotated[Path, typer.Argument(metavar="RESULT", help="Result JSON.")],
    data: Annotated[Path, typer.Argument(help="A recording (.h5) or a CSV/text file (read "
                                              "through the import options).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Corrected CSV to write.")],
    imu: Annotated[str | None, typer.Option(help="IMU stream of a recording.")] = None,
    *,
    import_options: ImportOptions,
) -> None:
    """Correct a recording's IMU stream, or a CSV file, with a calibration result.

    Any procedure's result file: one with a whole triad model (P1, P2, field, ``imucalib
    combine``) applies it; one with part of a triad model (a classical test) applies what it
    estimated, the triad's other parameters nominal (zero), and says so; a noise
    characterisation has no model and is refused.

    A CSV/text file is read in its own layout through the import options (as ``imucalib
    segments`` reads it, docs/import.md) and corrected chunk by chunk, so a log larger than
    memory is corrected; the corrected CSV is in SI with canonical column names.

    A result with temperature models corrects each sample at the IMU's own temperature (the
    stream's or the CSV's ``temperature_degc`` column), its rate and its heating/cooling leg
    (docs/processing-estimation.md, "Temperature models"); temperatures beyond the fitted range
    by more than 5 °C are corrected by extrapolation, with a warning.
    """
    import pandas as pd

    from imucalib.io.import_spec import ImportSpec, iter_imu_table
    from imucalib.models.correct import TemperatureRate, correct_imu_frame
    from imucalib.models.result_document import applicable_calibration, load_result

    try:
        spec = import_options.spec()
        result, nominal = applicable_calibration(load_result(result_path))
        for note in nominal:
            console.print(f"note: {note}", highlight=False, soft_wrap=True)
        accel_file = import_options.given["accel_file"]
        _check_out(out, result_path, data, *([accel_file] if accel_file else []))
        n = 0
        seen = _TemperatureSeen()
        rate = TemperatureRate()

        def correct(df: pd.DataFrame) -> pd.DataFrame:
            fixed = correct_imu_frame(df, result, temperature_rate=rate)
            if result.temperature_models:
                seen.add(df)
            return fixed

        if data.suffix.lower() in (".h5", ".hdf5"):
            from imucalib.io.opening import open_recording

            if spec != ImportSpec():
                raise InvalidInputError(f"{data} is a Recording: the import options (--import, "
                                        "--column-map, --gyro-unit …) apply to a CSV/text file")
            with open_recording(data) as rec:
                unit = imu or result.sensor_id
                info = rec.stream_info("imu", unit)
                with open(out, "w", encoding="utf-8") as fh:
                    for i, chunk in enumerate(rec.iter_stream("imu", unit)):
                        df = pd.DataFrame(chunk.columns,
                                          index=pd.Index(chunk.time_s, name="time_s"))
                        df.attrs["units"] = {c: s.unit for c, s in info.columns.items()}
                        fixed = correct(df)
                        _write_csv(fixed, fh, header=i == 0)
                        n += len(fixed)
        else:  # written beside --out and renamed when complete: a defect leaves no part file
            chunks = iter_imu_table(data, spec)  # the spec and header checked here
            part = out.with_name(out.name + ".part")
            try:
                with open(part, "w", encoding="utf-8") as fh:
                    for i, df in enumerate(chunks):
                        if i == 0:
                            _check_triads(data, df.columns, result)
                        fixed = correct(df)
                        _write_csv(fixed, fh, header=i == 0)
                        n += len(fixed)
                part.replace(out)
            finally:
                part.unlink(missing_ok=True)
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(InvalidInputError(f"cannot write {out}: {exc.strerror or exc}")) from exc
    warning = seen.extrapolation(result)
    if warning:
        err_console.print(f"[yellow]warning:[/] {warning}", highlight=False, soft_wrap=True)
    console.print(f"wrote {out}: {n:,} corrected samples ({result.procedure} {result.model} "
                  f"result of {result.sensor_id}{seen.summary()})", highlight=False,
                  soft_wrap=True)


class _TemperatureSeen:
    """The range of the temperatures a temperature-model result was applied at."""

    def __init__(self) -> None:
        self.low = float("inf")
        self.high = float("-inf")

    def add(self, df: Any) -> None:
        from imucalib.conventions import TEMPERATURE_COLUMN

        column = df[TEMPERATURE_COLUMN]
        if len(column):
            self.low = min(self.low, float(column.min()))
            self.high = max(self.high, float(column.max()))

    def summary(self) -> str:
        if self.low > self.high:
            return ""
        return f"; temperature model applied at {self.low:.1f} … {self.high:.1f} °C"

    def extrapolation(self, result: Any) -> str:
        """Return the warning when the data go beyond the fitted range by more than the margin."""
        from imucalib.models.correct import EXTRAPOLATION_MARGIN_DEGC

        margin = EXTRAPOLATION_MARGIN_DEGC
        fitted = result.temperature_range_degc
        if fitted is None or self.low > self.high:
            return ""
        if self.low >= fitted[0] - margin and self.high <= fitted[1] + margin:
            return ""
        return (f"the data reach {self.low:.1f} … {self.high:.1f} °C, beyond the temperature "
                f"models' fitted range {fitted[0]:.1f} … {fitted[1]:.1f} °C by more than "
                f"{margin:g} °C; those samples are corrected by extrapolating the polynomials")


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
