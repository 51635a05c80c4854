"""Commands on plan files: ``plan new NAME``, ``plan validate``, ``plan show``, ``plan schema``.

``plan show PLAN --predict`` prints the plan's predicted uncertainty (docs/test-design.md).

``plan new`` has one subcommand per registered procedure, whose flags are built from the
procedure's plan-options dataclass (:mod:`imucalib.cli.options_cli`): a procedure added to the
registry gets its ``plan new`` with no edit here.
"""

from __future__ import annotations

import inspect
import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from typer.core import TyperGroup

from imucalib.cli._app import app, console, fail, typer_app
from imucalib.cli.options_cli import (
    GroupedHelpCommand,
    flags_of,
    given_values,
    spec_parameters,
)
from imucalib.errors import CalibrationError, ConfigurationError, InsufficientExcitationError
from imucalib.procedures.common.options import option_specs

if TYPE_CHECKING:
    from imucalib.plan.schema import Plan

__all__ = ["plan_app"]

plan_app = typer_app(help="Validate, show and describe test plans.", no_args_is_help=True)
app.add_typer(plan_app, name="plan")


def _estimate_line(plan: Plan) -> str:
    """One line: the disk a run needs, its closed file's size, and the station facts used."""
    from imucalib.plan.budget import estimate_plan_recording, format_bytes

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
    from imucalib.io.compression import DEFAULT_COMPRESSION

    return (f"recording over {est.duration_s:,.0f} s ({basis}): ≈ "
            f"{format_bytes(est.total_bytes)} of disk at the most (the file as written, then its "
            f"compressed copy at close), ≈ {format_bytes(est.closed_bytes)} once closed "
            f"({DEFAULT_COMPRESSION})")


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
def show(
    path: Annotated[Path, typer.Argument(help="Plan file (.toml).")],
    predict: Annotated[bool, typer.Option(
        "--predict", help="Print each parameter's predicted σ (Cramér–Rao bound of the "
                          "plan's design with the unit's noise model), the identifiability and "
                          "the station time, instead of the steps (docs/test-design.md).")] = False,
    as_json: Annotated[bool, typer.Option(
        "--json", help="With --predict: print the prediction as JSON.")] = False,
) -> None:
    """Print the expanded step list with each step's least duration and the total.

    With ``--predict``, the plan's predicted uncertainty instead (docs/test-design.md); a plan
    that cannot identify a parameter exits 2 naming the confounded ones.
    """
    from rich.table import Table

    from imucalib.plan import describe_plan, load_plan

    if as_json and not predict:
        raise fail(ConfigurationError("--json goes with --predict "
                                      "(`imucalib plan show PLAN --predict --json`)"))
    try:
        plan = load_plan(path)
    except CalibrationError as exc:
        raise fail(exc) from exc
    if predict:
        _show_prediction(plan, as_json)
        return
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


def _show_prediction(plan: Plan, as_json: bool) -> None:
    """``plan show --predict``: the table or the JSON; exit 2 when something is confounded."""
    from rich.table import Table

    from imucalib.procedures import registry
    from imucalib.procedures.common.prediction import predict_plan
    from imucalib.report.console import display_unit

    try:
        if not plan.procedure:
            raise ConfigurationError(f"plan {plan.name!r} names no procedure: nothing to "
                                     "predict")
        prediction = predict_plan(registry.get(plan.procedure), plan)
    except CalibrationError as exc:
        raise fail(exc) from exc
    if as_json:
        typer.echo(json.dumps(prediction.to_dict(), indent=2))
    else:
        table = Table("parameter", "predicted σ", "unit",
                      title=f"{plan.name} ({plan.procedure}): predicted uncertainty")
        for p in prediction.parameters:
            unit, scale = display_unit(p.name, p.unit)
            sigma = "—" if p.predicted_std is None else f"{p.predicted_std / scale:.3g}"
            table.add_row(p.name, sigma, unit)
        console.print(table)
        for g in prediction.groups:
            kappa = "∞" if g.condition_number == float("inf") else f"{g.condition_number:.3g}"
            console.print(f"{g.name}: rank {g.rank} of {g.n_parameters}, condition number "
                          f"{kappa}", highlight=False)
        t = prediction.station_time_s
        console.print(f"station time with moves and settling: {t:,.0f} s ({t / 3600:.2f} h)",
                      highlight=False)
        for note in prediction.notes:
            console.print(f"note: {note}", highlight=False, soft_wrap=True)
    if prediction.confounded:
        raise fail(InsufficientExcitationError(
            prediction.confounded,
            f"plan {plan.name!r} cannot identify {', '.join(prediction.confounded)} "
            "(confounded)"))


def _write_new_plan(procedure: str, out: Path, given: dict[str, Any]) -> None:
    """Generate `procedure`'s plan from the options `given`, write it to `out`, say so."""
    from pydantic import ValidationError

    from imucalib.plan import describe_plan, write_plan
    from imucalib.plan.bounds import format_validation_error
    from imucalib.procedures import registry

    try:
        plan = registry.get(procedure).generate_plan(**given)
        write_plan(plan, out)
    except ValidationError as exc:  # options the plan's bounds refuse
        raise fail(ConfigurationError(format_validation_error(
            exc, f"from `plan new {procedure}` (check the options)", "plan"))) from exc
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(ConfigurationError(f"cannot write {out}: {exc.strerror or exc}")) from exc
    total = sum(r.min_duration_s for r in describe_plan(plan))
    console.print(f"wrote {out}: plan {plan.name!r}, {len(plan.steps)} steps, at least "
                  f"{total / 3600:.2f} h", highlight=False)


def _plan_command(name: str) -> Any:
    """Return the ``plan new NAME`` command, its flags built from the procedure's options."""
    from imucalib.procedures import registry

    proc = registry.get(name)
    specs = option_specs(proc.plan_options_type)
    known = flags_of(specs) | {"--out", "-o", "--help"}

    class Command(GroupedHelpCommand):
        """``plan new NAME``: a flag this plan does not take names the plans that do."""

        def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
            """Refuse a flag of another procedure's plan in one line, then parse."""
            for arg in args:
                flag = arg.split("=", 1)[0]
                if flag.startswith("--") and flag not in known:
                    raise fail(ConfigurationError(_foreign_flag(name, flag)))
            return list(super().parse_args(ctx, args))

    Command.specs = specs

    def callback(ctx: typer.Context, out: Path, **_: Any) -> None:
        try:
            given = given_values(ctx, specs)
        except CalibrationError as exc:
            raise fail(exc) from exc
        _write_new_plan(name, out, given)

    out_param = inspect.Parameter(
        "out", inspect.Parameter.KEYWORD_ONLY,
        annotation=Annotated[Path, typer.Option("--out", "-o", help="Plan file to write "
                                                                     "(.toml).")])
    ctx_param = inspect.Parameter("ctx", inspect.Parameter.POSITIONAL_OR_KEYWORD,
                                  annotation=typer.Context)
    callback.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
        [ctx_param, out_param, *spec_parameters(specs)])
    one = typer_app(add_completion=False)
    one.command(name=name, cls=Command, short_help=proc.description,
                help=f"Write the {name} plan: {proc.description}. The plan carries a [twin] "
                     "table to run it on the twin (docs/procedures.md).")(callback)
    return typer.main.get_command(one)


def _loadable() -> list[str]:
    """Return the registered procedures that load; a broken plug-in is left out of listings."""
    from imucalib.procedures import registry

    out = []
    for n in registry.names():
        try:
            registry.get(n)
        except CalibrationError:
            continue
        out.append(n)
    return out


def _foreign_flag(name: str, flag: str) -> str:
    """Return the error line for `flag` given to `name`'s plan: which plans take it."""
    from imucalib.procedures import registry

    takers = [n for n in _loadable() if n != name and
              flag in flags_of(option_specs(registry.get(n).plan_options_type))]
    where = (f"; the plan of {', '.join(f'`plan new {n} {flag}`' for n in takers)} takes it"
             if takers else "")
    return f"the {name} plan takes no {flag}{where}"


class _PlanNewGroup(TyperGroup):
    """``plan new``: one subcommand per registered procedure, built when asked for."""

    def list_commands(self, ctx: Any) -> list[str]:
        """Return the registered procedures that load (`imucalib procedures` names the rest)."""
        return _loadable()

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        """Return the procedure's ``plan new`` command; an unknown name is one error line."""
        from imucalib.procedures import registry

        try:
            registry.get(cmd_name)
        except ConfigurationError as exc:
            if ctx.resilient_parsing:
                return None
            raise fail(exc) from exc
        return _plan_command(cmd_name)


plan_new_app = typer_app(
    cls=_PlanNewGroup, no_args_is_help=True,
    help="Write a procedure's default plan: `imucalib plan new NAME --out FILE [options]`; "
         "`imucalib plan new NAME --help` lists that procedure's options with units and "
         "defaults.")
plan_app.add_typer(plan_new_app, name="new")


@plan_new_app.callback()
def _plan_new() -> None:
    """Write a procedure's default plan (`plan new NAME --help`: its options)."""


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


@plan_app.command("optimize")
def optimize(
    procedure: Annotated[str, typer.Argument(help="The procedure whose plan is optimised.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Plan file to write (.toml).")],
    target_default: Annotated[bool, typer.Option(
        "--target-default", help="Targets: each parameter's σ no worse than the default "
                                 "plan's (the default).")] = False,
    target: Annotated[str | None, typer.Option(
        "--target", help="Targets NAME=σ,… in SI units (a NAME may be a prefix: gyro_bias, "
                         "accel_M).")] = None,
    target_from_spec: Annotated[bool, typer.Option(
        "--target-from-spec", help="Targets σ ≤ limit/k of each parameter the plan's "
                                   "[imu.limits] limits.")] = False,
    k: Annotated[float, typer.Option("--k", help="The k of --target-from-spec.")] = 3.0,
    time_budget: Annotated[float | None, typer.Option(
        "--time-budget", help="Station time allowed [h]: the best criterion within it "
                              "instead of the least time.")] = None,
    criterion: Annotated[str, typer.Option(
        "--criterion", help="targets (worst σ/target), D (log det) or A (trace) of the "
                            "normalised covariance; D and A need --time-budget.")] = "targets",
    grade: Annotated[str, typer.Option("--grade", help="The IMU's grade.")] = "tactical",
    min_repetitions: Annotated[int, typer.Option(
        "--min-repetitions", help="Margin: complete calibrations kept (the repeatability "
                                  "check; docs/p1.md rule 6 asks for three).")] = 3,
    min_static: Annotated[float, typer.Option(
        "--min-static", help="Margin: the least level static record [s] (the procedure's "
                             "60 min; a shorter one rests the biases' flicker on the "
                             "grade's declared noise, docs/test-design.md).")] = 3600.0,
    min_dof: Annotated[int, typer.Option(
        "--min-dof", help="Margin: least lack-of-fit ν of each triad's fit.")] = 6,
    coarse: Annotated[bool, typer.Option("--coarse", help="A small search grid (quick).")]
    = False,
    noise_characterization: Annotated[Path | None, typer.Option(
        "--noise-characterization", help="The unit's noise characterisation (the JSON "
                                         "`imucalib allan` writes): both plans are predicted "
                                         "with its noise instead of the grade's, and carry it "
                                         "as [imu.noise].")] = None,
) -> None:
    """Write the plan that meets σ targets in the least station time (docs/test-design.md).

    Prints the default plan against the optimised one: station time, each parameter's
    predicted σ and its ratio to the target, and the worst ratio.
    """
    from imucalib.plan import write_plan

    try:
        result = _optimize(procedure, target_default, target, target_from_spec, k, time_budget,
                           criterion, grade, min_repetitions, min_static, min_dof, coarse,
                           noise_characterization)
        write_plan(result.plan, out)
    except CalibrationError as exc:
        raise fail(exc) from exc
    except OSError as exc:
        raise fail(ConfigurationError(f"cannot write {out}: {exc.strerror or exc}")) from exc
    _print_optimized(result, out)


def _optimize(procedure: str, target_default: bool, target: str | None,
              target_from_spec: bool, k: float, time_budget_h: float | None, criterion: str,
              grade: str, min_repetitions: int, min_static_s: float, min_dof: int,
              coarse: bool, noise_characterization: Path | None = None) -> Any:
    """Build the request of ``plan optimize`` and ask the procedure's optimiser."""
    from imucalib.procedures import registry
    from imucalib.procedures.common.prediction import OptimizeRequest, optimize_plan

    if sum([target_default, target is not None, target_from_spec]) > 1:
        raise ConfigurationError("give one of --target-default, --target, --target-from-spec")
    request = OptimizeRequest(
        targets="given" if target is not None else "spec" if target_from_spec else "default",
        target_text=target or "", spec_k=k,
        time_budget_s=None if time_budget_h is None else time_budget_h * 3600.0,
        criterion=criterion, grade=grade, min_repetitions=min_repetitions,
        min_static_s=min_static_s, min_lack_of_fit_dof=min_dof, coarse=coarse,
        noise_characterization=str(noise_characterization or ""))
    return optimize_plan(registry.get(procedure), request)


def _print_optimized(result: Any, out: Path) -> None:
    """Print the comparison table of ``plan optimize`` (an OptimizedPlan)."""
    from rich.table import Table

    from imucalib.report.console import display_unit

    ref, best = result.reference, result.prediction
    t_ref, t_best = ref.station_time_s, best.station_time_s
    table = Table("parameter", "unit", "default σ", "optimised σ", "target", "ratio",
                  title=f"{result.plan.procedure}: default plan ({t_ref / 3600:.2f} h) vs "
                        f"optimised ({t_best / 3600:.2f} h)")
    ref_std, best_std = ref.std(), best.std()
    for p in best.parameters:
        unit, scale = display_unit(p.name, p.unit)

        def show(v: float | None, scale: float = scale) -> str:
            return "—" if v is None else f"{v / scale:.3g}"

        ratio = result.ratios.get(p.name)
        table.add_row(p.name, unit, show(ref_std.get(p.name)), show(best_std.get(p.name)),
                      show(result.targets.get(p.name)),
                      "" if ratio is None else f"{ratio:.3f}")
    console.print(table)
    console.print(f"optimised: {result.design}", highlight=False)
    console.print(f"station time: default {t_ref:,.0f} s ({t_ref / 3600:.2f} h), optimised "
                  f"{t_best:,.0f} s ({t_best / 3600:.2f} h, {t_best / t_ref:.0%})",
                  highlight=False)
    console.print(f"worst σ/target: default {result.reference_worst_ratio:.3f}, optimised "
                  f"{result.worst_ratio:.3f}; criterion {result.criterion}",
                  highlight=False)
    for note in result.notes:
        console.print(f"note: {note}", highlight=False, soft_wrap=True)
    console.print(f"wrote {out}: plan {result.plan.name!r}, {len(result.plan.steps)} steps",
                  highlight=False)
