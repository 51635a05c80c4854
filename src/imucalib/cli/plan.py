"""Commands on plan files: ``plan validate``, ``plan show`` and ``plan schema``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from pydantic import ValidationError
from rich.table import Table

from imucalib.cli._app import app, console, fail, typer_app
from imucalib.errors import CalibrationError, ConfigurationError
from imucalib.plan.bounds import (
    MAX_IMUS,
    MAX_RECORD_S,
    MAX_SAMPLE_RATE_HZ,
    MAX_TABLE_RATE_DPS,
    MIN_SAMPLE_RATE_HZ,
    format_validation_error,
)
from imucalib.plan.budget import format_bytes
from imucalib.plan.schema import Plan

__all__ = ["plan_app"]

#: Most repetitions `plan new p1` writes (each adds 36 steps and the static record).
MAX_REPETITIONS = 50

plan_app = typer_app(help="Validate, show and describe test plans.", no_args_is_help=True)
app.add_typer(plan_app, name="plan")


def _estimate_line(plan: Plan) -> str:
    """One line: the estimated recording size, and on which station facts it rests."""
    from imucalib.plan.budget import estimate_plan_recording

    est = estimate_plan_recording(plan)
    if plan.twin is not None:
        n = len(plan.twin.imus)
        rates = sorted({s.rate_hz for s in est.streams if s.name.startswith("imu/")})
        basis = (f"on its twin: {n} IMU{'s' if n > 1 else ''} at "
                 f"{'/'.join(f'{r:g}' for r in rates)} Hz")
    else:
        basis = (f"for 1 IMU at the plan's least acquisition rate, "
                 f"{plan.equipment.acquisition_rate_min_hz:g} Hz; a station's IMUs and rates "
                 "change it")
    return f"recording ≈ {format_bytes(est.total_bytes)} over {est.duration_s:,.0f} s ({basis})"


@plan_app.command("validate")
def validate(path: Annotated[Path, typer.Argument(help="Plan file (.toml).")]) -> None:
    """Check a plan file against the schema; exit 2 naming every bad field."""
    from imucalib.plan import load_plan, plan_hash

    try:
        plan = load_plan(path)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"{path}: valid plan {plan.name!r}, {len(plan.steps)} steps, "
                  f"sha256 {plan_hash(plan)[:16]}…; {_estimate_line(plan)}", highlight=False,
                  soft_wrap=True)


@plan_app.command("show")
def show(path: Annotated[Path, typer.Argument(help="Plan file (.toml).")]) -> None:
    """Print the expanded step list with each step's least duration and the total."""
    from imucalib.plan import describe_plan, load_plan

    try:
        plan = load_plan(path)
    except CalibrationError as exc:
        raise fail(exc) from exc
    rows = describe_plan(plan)
    table = Table("#", "kind", "label", "what", "≥ s", "tags",
                  title=f"{plan.name} ({plan.procedure or 'no procedure'})")
    for r in rows:
        table.add_row(str(r.index), r.kind, r.label, r.what, f"{r.min_duration_s:,.0f}",
                      ", ".join(r.tags))
    console.print(table)
    total = sum(r.min_duration_s for r in rows)
    console.print(f"{len(rows)} steps; at least {total:,.0f} s ({total / 3600:.2f} h) without "
                  "moves and stability waits", highlight=False)
    console.print(_estimate_line(plan), highlight=False, soft_wrap=True)


#: The options of `plan new` and the generator keyword each sets.
_PLAN_OPTIONS = {"grade": "grade", "repetitions": "repetitions", "static_s": "static_s",
                 "sample_rate_hz": "sample_rate_hz", "seed": "seed", "record_s": "record_s",
                 "temperatures": "temperatures_degc", "serial": "serial", "model": "model",
                 "maker": "maker", "acceptance": "acceptance", "n_imus": "n_imus",
                 "held_out": "held_out_degc", "hysteresis": "hysteresis",
                 "rate_dps": "rate_dps", "revolutions": "revolutions",
                 "pose_order": "pose_order", "radius_m": "static_radius_m",
                 "test_range_g": "test_range_g", "n_rates": "n_rates",
                 "test_load_kg": "test_load_kg", "unbalance_um": "unbalance_um",
                 "tumble": "tumble", "both_directions": "both_directions",
                 "rates": "rates_dps", "n_poses": "n_poses", "full_turns": "full_turns",
                 "tilt_deg": "tilt_deg"}


def _refuse_foreign_options(ctx: typer.Context, procedure: str, plan_options: frozenset[str]
                            ) -> None:
    """Refuse an option given on the command line that `procedure`'s plan generator does not take.

    An option the generator does not take would otherwise be dropped without a word (P1
    calibrates at one temperature: ``plan new p1 --temperatures=…`` would write the same plan).
    The message names the procedures whose plans do take it.
    """
    from imucalib.procedures import registry

    for param, keyword in _PLAN_OPTIONS.items():
        source = ctx.get_parameter_source(param)  # click's ParameterSource (typer vendors it)
        if keyword in plan_options or source is None or source.name == "DEFAULT":
            continue
        flag = "--" + param.replace("_", "-")
        takers = [n for n in registry.names() if keyword in registry.get(n).plan_options]
        where = (f"; the plan of {', '.join(f'`plan new {n} {flag}`' for n in takers)} takes it"
                 if takers else "")
        raise ConfigurationError(f"the {procedure} plan takes no {flag}{where}")


def _numbers(text: str | None, flag: str) -> list[float] | None:
    """Parse '-10,20,60' into numbers (None stays None)."""
    if text is None:
        return None
    try:
        return [float(t) for t in text.split(",") if t.strip()]
    except ValueError as exc:
        raise ConfigurationError(f"{flag} must be numbers separated by commas; got "
                                 f"{text!r}") from exc


@plan_app.command("new")
def new(
    ctx: typer.Context,
    procedure: Annotated[str, typer.Argument(
        help="Procedure: p1, allan, p2, p3, rate-transfer, installation, … (the registry's).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Plan file to write (.toml).")],
    grade: Annotated[str, typer.Option(help="IMU grade: consumer, tactical, navigation.")] =
    "tactical",
    repetitions: Annotated[int, typer.Option(help="Complete calibrations.", min=1,
                                             max=MAX_REPETITIONS)] = 3,
    static_s: Annotated[float, typer.Option(help="Level static record [s].", min=0.0,
                                            max=MAX_RECORD_S)] = 3600.0,
    sample_rate_hz: Annotated[float, typer.Option(help="Twin IMU output rate [Hz].",
                                                  min=MIN_SAMPLE_RATE_HZ,
                                                  max=MAX_SAMPLE_RATE_HZ)] = 1000.0,
    seed: Annotated[int, typer.Option(help="Seed of the twin.", min=-(2**63),
                                      max=2**63 - 1)] = 1,
    record_s: Annotated[float, typer.Option(help="Allan: each static record [s].", min=0.0,
                                            max=MAX_RECORD_S)] = 7200.0,
    temperatures: Annotated[str | None, typer.Option(
        help="Allan: record at these chamber temperatures, e.g. '-10,20,60' [°C].")] = None,
    serial: Annotated[str, typer.Option(help="P1: the unit's serial number.")] = "",
    model: Annotated[str, typer.Option(help="P1: the unit's model.")] = "",
    maker: Annotated[str, typer.Option(help="P1: the unit's maker.")] = "",
    acceptance: Annotated[str, typer.Option(
        help="P1: decision rule, simple or guarded (|value| + 2u within the limit).")] = "simple",
    n_imus: Annotated[int, typer.Option(help="P2: units on the cube (the twin's).", min=1,
                                        max=MAX_IMUS)] = 8,
    held_out: Annotated[str | None, typer.Option(
        help="P2: temperature points held out of the models, e.g. '-10,55' [°C].")] = None,
    hysteresis: Annotated[bool, typer.Option(
        help="P2: visit the points heating then cooling (a hysteresis term).")] = False,
    rate_dps: Annotated[float, typer.Option(help="P2: |ω| of the turns [°/s].", min=1.0,
                                            max=MAX_TABLE_RATE_DPS)] = 60.0,
    revolutions: Annotated[int, typer.Option(help="P2: whole revolutions per turn.", min=1,
                                             max=1000)] = 2,
    pose_order: Annotated[str, typer.Option(
        help="P2: temperature-major (six remounts per point) or pose-major (six sweeps).")]
    = "temperature-major",
    radius_m: Annotated[float, typer.Option(
        help="P3: static radius r_t of the test position [m].", min=0.01, max=20.0)] = 1.0,
    test_range_g: Annotated[float, typer.Option(
        help="P3: specific force at r_t at the top rate [g].", min=0.1, max=1000.0)] = 20.0,
    n_rates: Annotated[int, typer.Option(help="P3: rate points (at least 4).", min=1,
                                         max=100)] = 5,
    test_load_kg: Annotated[float, typer.Option(
        help="P3: the test load mounted for the last configuration [kg].", min=0.0,
        max=1000.0)] = 2.0,
    unbalance_um: Annotated[float, typer.Option(
        help="P3: the twin's rotor-centre shift at the top rate, loaded [µm].", min=0.0,
        max=1000.0)] = 10.0,
    tumble: Annotated[bool, typer.Option(
        help="P3: record the 1 g tumble (K1, K0 of each accelerometer).")] = True,
    both_directions: Annotated[bool, typer.Option(
        help="P3: run every rate at +ω and −ω.")] = False,
    rates: Annotated[str | None, typer.Option(
        help="P3, rate-transfer: the rates, e.g. '5,12.5,18,27' [°/s].")] = None,
    n_poses: Annotated[int, typer.Option(
        help="field: static poses after the initial rest (at least 6).", min=1, max=200)]
    = 12,
    full_turns: Annotated[bool, typer.Option(
        help="field: ± full turns flat on the desk about each axis (the gyro's scale).")]
    = True,
    tilt_deg: Annotated[float, typer.Option(
        help="field: how far the second round of poses leans [°].", min=0.0, max=60.0)]
    = 20.0,
) -> None:
    """Write a procedure's default plan (with a [twin] table to run it on the twin)."""
    from imucalib.plan import describe_plan, write_plan
    from imucalib.procedures import registry

    try:
        proc = registry.get(procedure)
        _refuse_foreign_options(ctx, procedure, proc.plan_options)
        given = {"grade": grade, "repetitions": repetitions, "static_s": static_s,
                 "sample_rate_hz": sample_rate_hz, "seed": seed, "record_s": record_s,
                 "temperatures_degc": _numbers(temperatures, "--temperatures"),
                 "serial": serial, "model": model, "maker": maker, "acceptance": acceptance,
                 "n_imus": n_imus, "held_out_degc": _numbers(held_out, "--held-out"),
                 "hysteresis": hysteresis, "rate_dps": rate_dps, "revolutions": revolutions,
                 "pose_order": pose_order, "static_radius_m": radius_m,
                 "test_range_g": test_range_g, "n_rates": n_rates,
                 "test_load_kg": test_load_kg, "unbalance_um": unbalance_um, "tumble": tumble,
                 "both_directions": both_directions, "rates_dps": _numbers(rates, "--rates"),
                 "n_poses": n_poses, "full_turns": full_turns, "tilt_deg": tilt_deg}
        # only what the command line gave: each generator keeps its own defaults
        explicit = {keyword for param, keyword in _PLAN_OPTIONS.items()
                    if (src := ctx.get_parameter_source(param)) is not None
                    and src.name != "DEFAULT"}
        plan = proc.generate_plan(**{k: v for k, v in given.items()
                                     if k in proc.plan_options and k in explicit})
        write_plan(plan, out)
    except ValidationError as exc:  # options the plan's bounds refuse (NaN passes a range)
        raise fail(ConfigurationError(format_validation_error(
            exc, f"from `plan new {procedure}` (check the options)", "plan"))) from exc
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(ConfigurationError(f"cannot write {out}: {exc.strerror or exc}")) from exc
    total = sum(r.min_duration_s for r in describe_plan(plan))
    console.print(f"wrote {out}: plan {plan.name!r}, {len(plan.steps)} steps, at least "
                  f"{total / 3600:.2f} h", highlight=False)


@plan_app.command("schema")
def schema(
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Write to a file.")] = None,
) -> None:
    """Print (or write) the JSON Schema of plan files, for editors."""
    from imucalib.plan import plan_json_schema

    text = json.dumps(plan_json_schema(), indent=2)
    if out is None:
        typer.echo(text)
    else:
        out.write_text(text + "\n", encoding="utf-8")
        console.print(f"wrote {out}", highlight=False)
