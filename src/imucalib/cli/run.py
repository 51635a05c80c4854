"""``imucalib run``: execute a plan on the twin or on real equipment, with a live view."""

from __future__ import annotations

import sys
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from imucalib.cli._app import app, console, err_console, fail
from imucalib.cli._progress import make_progress, shows_progress
from imucalib.errors import CalibrationError, ConfigurationError

if TYPE_CHECKING:  # imported where used: `imucalib --help` does not load the station
    from rich.table import Table

    from imucalib.plan.schema import Plan
    from imucalib.station.devices import Station
    from imucalib.station.operator import Operator, OperatorAnswer
    from imucalib.station.runner import RunStatus, RunSummary

__all__ = ["run"]


class _PromptOperator:
    """Asks at the terminal; records the operator's name."""

    def __init__(self, who: str) -> None:
        self.who = who

    def confirm(self, item: str) -> OperatorAnswer:
        from imucalib.station.operator import OperatorAnswer

        ok = typer.confirm(f"[operator check] {item} — confirmed?", default=False)
        return OperatorAnswer(ok, self.who)


def _view(status: RunStatus) -> Table:
    from rich.table import Table

    table = Table(show_header=False, title=f"imucalib run — {status.plan}", title_justify="left")
    table.add_column(style="bold")
    table.add_column()
    table.add_row("step", f"{status.step_index + 1}/{status.n_steps} {status.step_label} "
                          f"(attempt {status.attempt + 1})")
    table.add_row("progress", f"{status.steps_done} done, {status.steps_invalid} invalid; "
                              f"≥{status.remaining_min_s:,.0f} s of steps left")
    table.add_row("station time", f"{status.time_s:,.1f} s")
    if status.table_angle_deg:
        table.add_row("table", "  ".join(f"{a:9.4f}° {r:+8.3f}°/s" for a, r in
                                         zip(status.table_angle_deg, status.table_rate_dps,
                                             strict=False)))
    if status.chamber_degc is not None:
        table.add_row("chamber", f"{status.chamber_degc:.2f} °C")
    for name, rate in status.imu_rate_hz.items():
        temp = status.imu_temperature_degc.get(name, float("nan"))
        table.add_row(name, f"{rate:7.1f} Hz  {temp:6.2f} °C  {status.imu_errors.get(name, '')}")
    if status.last_event:
        table.add_row("last event", status.last_event)
    return table


def _report(summary: RunSummary) -> None:
    colour = "green" if summary.status == "done" else "red"
    console.print(f"[{colour}]{summary.status}[/]: {summary.steps_done} step(s) done, "
                  f"{summary.steps_invalid} invalid attempt(s); recording {summary.path}",
                  highlight=False)
    for trip in summary.trips:
        console.print(f"  trip: {trip}", highlight=False)
    if summary.reason:
        console.print(f"  {'stopped' if summary.status != 'done' else 'note'}: {summary.reason}",
                      highlight=False)
    if summary.storage_note:
        console.print(f"  note: {summary.storage_note}", highlight=False)


@app.command()
def run(
    plan_path: Annotated[Path | None, typer.Argument(
        metavar="PLAN", help="Plan file (.toml); not needed with --resume.")] = None,
    station: Annotated[str, typer.Option(
        help="'sim' (the plan's [twin]) or a station file STATION.toml.")] = "sim",
    out: Annotated[Path, typer.Option("--out", "-o", help=(
        "Folder for the recording (named PLAN-TIME.h5), or the recording itself (.h5)."))]
    = Path("out"),
    resume: Annotated[Path | None, typer.Option(
        help="Continue this interrupted run's recording.")] = None,
    operator: Annotated[str | None, typer.Option(help="Operator's name (recorded).")] = None,
    yes: Annotated[bool, typer.Option("--yes", help="Confirm operator checks automatically.")]
    = False,
    tick_s: Annotated[float | None, typer.Option(
        help="Acquisition interval [s]; default 2 on the twin (virtual), 0.5 on equipment.")]
    = None,
    live: Annotated[bool, typer.Option(
        help="Show the live view (on a terminal's stderr only).")] = True,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No live view nor progress bar "
                                        "(none is drawn anyway when stderr is not a terminal).")]
    = False,
    db: Annotated[str | None, typer.Option(
        "--db", help="Records database (default: $IMUCALIB_DB, else records.db in the user's "
                     "data directory; docs/records.md).")] = None,
    no_record: Annotated[bool, typer.Option(
        "--no-record", help="Do not record the run in the records database (the "
                            "equipment's due dates are checked all the same).")] = False,
    override_due: Annotated[str | None, typer.Option(
        "--override-due", help="Run although the station's equipment is overdue for "
                               "calibration; the reason is recorded with the run.")] = None,
    customer: Annotated[str | None, typer.Option(
        "--customer", help="Who the calibration is for (recorded with the run and in the "
                           "recording; the certificate states it).")] = None,
    compression: Annotated[str | None, typer.Option(
        "--compression", metavar="NAME",
        help="Compression of the recording once closed: gzip (the default; every HDF5 tool "
             "reads it: h5py, MATLAB, HDFView, Octave), blosc-lz4 or blosc-zstd (faster to "
             "close and read, but readable outside imucalib only with the HDF5 Blosc plugin), "
             "lzf or none (docs/recording-format.md, Size and compression). A resumed run "
             "keeps its recording's.")] = None,
) -> None:
    """Run a plan on the twin or on real equipment, writing a crash-safe recording.

    On a terminal, stderr shows a live view of the station and a progress bar: station time
    done of the plan's least station time, with an ETA. The run is recorded in the records
    database with its plan, operator, station, equipment, start and end times and recording
    hash (``--no-record`` skips it); ``imucalib calibrate`` of the recording attaches its result
    to that run. A station whose registered equipment is overdue for calibration is refused,
    with or without ``--no-record``, unless ``--override-due REASON`` (recorded with the run
    and in the recording).
    """
    from rich.console import Group
    from rich.live import Live

    from imucalib.cli._user import acting_user
    from imucalib.drivers.station_spec import make_station
    from imucalib.plan import load_plan, plan_hash
    from imucalib.records.run_entry import run_environment, run_metadata
    from imucalib.station.operator import AutoOperator
    from imucalib.station.runner import RunOptions, resume_run, run_plan

    try:
        codec = _compression_option(compression, resume)
        who, who_note = acting_user(operator, db=db, record=not no_record,
                                    action="run a plan")
    except CalibrationError as exc:
        raise fail(exc) from exc
    op: Operator
    if yes:
        op = AutoOperator(who)
    elif sys.stdin.isatty():
        op = _PromptOperator(who)
    else:
        op = AutoOperator(who)  # checked below: only when the plan has no operator checks
    last_draw = [0.0]
    shown = live and shows_progress(quiet)
    live_view = (Live(console=err_console, auto_refresh=False, transient=True) if shown
                 else None)
    bar = make_progress()
    task = bar.add_task("run", total=1.0, detail="")

    def on_status(status: RunStatus) -> None:
        now = time.monotonic()
        if live_view is not None and now - last_draw[0] > 0.1:
            last_draw[0] = now
            planned = status.time_s + status.remaining_min_s
            bar.update(task, completed=status.time_s / planned if planned > 0 else 0.0,
                       detail=f"{status.steps_done}/{status.n_steps} steps")
            live_view.update(Group(_view(status), bar), refresh=True)

    tick = tick_s if tick_s is not None else (2.0 if station == "sim" else 0.5)
    options = RunOptions(tick_s=tick, operator=op, on_status=on_status, compression=codec)
    try:
        if resume is not None:
            def factory(plan: Plan, start_time_s: float) -> Station:
                st, _ = make_station(station, plan, start_time_s)
                return st

            with live_view or _nothing():
                summary = resume_run(resume, factory, options=options)
        else:
            if plan_path is None:
                raise ConfigurationError("give a PLAN file, or --resume FILE")
            plan = load_plan(plan_path)
            station_name = "sim" if station == "sim" else Path(station).stem
            equipment, overdue = _check_due(db, station_name, override_due,
                                            create=not no_record)
            if not yes and not sys.stdin.isatty() and any(
                    s.kind == "operator-check" for s in plan.steps):
                raise ConfigurationError(
                    f"plan {plan.name!r} has operator checks; run it at a terminal or pass --yes "
                    "to confirm them automatically (recorded as such)")
            st, station_toml = make_station(station, plan)
            options.station_toml = station_toml
            options.truth = getattr(st, "truth", None)
            if out.suffix.lower() in (".h5", ".hdf5"):
                path = out
            else:
                stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%SZ")
                path = out / f"{plan.name}-{stamp}.h5"
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise ConfigurationError(f"cannot create {path.parent}: "
                                         f"{exc.strerror or exc}") from exc
            started = datetime.now(UTC)
            with live_view or _nothing():
                summary = run_plan(plan, st, path, options=options,
                                   extra_metadata=run_metadata(who, equipment, overdue,
                                                                override_due, customer))
            ended = datetime.now(UTC)
    except CalibrationError as exc:
        raise fail(exc) from exc
    except KeyboardInterrupt:
        console.print("[red]interrupted[/]: equipment stopped safely; resume with "
                      "`imucalib run --resume FILE`")
        raise typer.Exit(code=130) from None
    _report(summary)
    if not no_record and resume is None:
        from imucalib.records import open_records

        try:
            with open_records(db) as records:
                run_id = records.record_run(
                    plan_name=plan.name, plan_hash=plan_hash(plan), procedure=plan.procedure,
                    recording=summary.path, operator=who,
                    station=station_name if equipment else None,
                    equipment=[e.equipment_id for e in equipment],
                    environment=run_environment(summary.status, overdue, override_due,
                                                 customer),
                    started_utc=started, ended_utc=ended)
                console.print(f"recorded run {run_id} in {records.url}", highlight=False,
                              soft_wrap=True)
        except CalibrationError as exc:
            raise fail(exc) from exc
    if who_note:
        console.print(who_note, highlight=False, soft_wrap=True, markup=False)
    if summary.status != "done":
        raise typer.Exit(code=1)


def _compression_option(name: str | None, resume: Path | None) -> str | None:
    """Return the compression ``--compression`` names (none given: the default).

    Refused with ``--resume``: a resumed run keeps its recording's compression.
    """
    from imucalib.errors import InvalidInputError
    from imucalib.io.compression import DEFAULT_COMPRESSION, compression_from_name

    if name is None:
        return DEFAULT_COMPRESSION
    if resume is not None:
        raise InvalidInputError(
            "--compression is for a new run; a resumed run closes its recording with the "
            "compression it had (convert it afterwards: `imucalib compact FILE --compression "
            "NAME`)")
    return compression_from_name(name, "--compression")


def _check_due(db: str | None, station_name: str, override: str | None, *,
               create: bool = True) -> tuple[list[Any], list[Any]]:
    """:func:`imucalib.records.run_entry.check_due`, with the terminal's overdue warning."""
    from imucalib.records.run_entry import check_due

    mine, overdue = check_due(db, station_name, override, create=create)
    if overdue:
        err_console.print(f"[yellow]warning:[/] running with overdue equipment: {override}",
                          highlight=False)
    return mine, overdue


class _nothing:  # noqa: N801 - a no-op context manager
    def __enter__(self) -> None:
        return None

    def __exit__(self, *args: object) -> None:
        return None
