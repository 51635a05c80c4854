"""``imucalib procedures [NAME]``: which procedures exist, what each one's plan takes, its roles."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.table import Table

from imucalib.cli._app import app, console, err_console, fail
from imucalib.errors import CalibrationError

__all__ = ["procedures"]


@app.command()
def procedures(
    name: Annotated[str | None, typer.Argument(
        help="A procedure: list its plan options (flag, default, unit), analysis options and "
             "step roles.")]
    = None,
) -> None:
    """List every registered procedure (built-in or installed) with its one-line description.

    A plug-in that is refused (it shadows a built-in name, or fails to load) is named on
    stderr with the reason.

    With a NAME, list that procedure's plan options as `imucalib plan new NAME` takes them,
    grouped, with defaults and units, the options its analysis takes, and its step roles (what
    a step file's `role` may say, docs/import.md).
    """
    from imucalib.procedures import registry
    from imucalib.procedures.common.options import GROUP_TITLES, GROUPS, option_specs

    try:
        if name is None:
            table = Table("procedure", "description", "from", title="imucalib procedures")
            broken = []
            for n in registry.names():
                try:
                    proc = registry.get(n)
                except CalibrationError as exc:
                    broken.append(str(exc))
                    continue
                where = registry.origin(n)
                table.add_row(n, proc.description,
                              "built-in" if where == "built-in" else where.split(" of ")[-1])
            console.print(table)
            for line in (*registry.problems(), *broken):
                err_console.print(f"refused: {line}", highlight=False, soft_wrap=True)
            console.print("`imucalib procedures NAME` lists a procedure's options; "
                          "`imucalib plan new NAME --help` the same as flags.", highlight=False)
            return
        proc = registry.get(name)
        specs = option_specs(proc.plan_options_type)
    except CalibrationError as exc:
        raise fail(exc) from exc
    console.print(f"{proc.name}: {proc.description}", highlight=False, soft_wrap=True)
    table = Table("flag", "default", "unit", "what", title=f"plan new {proc.name}")
    for group in GROUPS:
        rows = [s for s in specs if s.cli and s.info.group == group]
        if rows:
            table.add_section()
            table.add_row(f"[bold]{GROUP_TITLES[group]}[/]", "", "", "")
            for s in rows:
                table.add_row(s.flag, s.default_text(), s.info.unit, s.info.help)
    console.print(table)
    python_only = [s for s in specs if not s.cli]
    for s in python_only:
        console.print(f"Python only: {s.name} ({s.info.python_only})", highlight=False,
                      soft_wrap=True)
    analysis = ", ".join(sorted(proc.analysis_options)) or "none"
    console.print(f"analysis options (imucalib calibrate): {analysis}", highlight=False,
                  soft_wrap=True)
    roles = Table("role", "what the step is for", title=f"step roles of {proc.name}")
    for role, meaning in proc.roles.items():
        roles.add_row(role, meaning)
    console.print(roles)
