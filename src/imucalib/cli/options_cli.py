"""Command-line flags built from a procedure's options dataclass, with a grouped ``--help``.

A procedure declares its options as dataclass fields
(:mod:`imucalib.procedures.common.options`); this module turns them into the parameters of a
Typer command built at run time (a function signature: Typer's public way to declare options),
one per field the command line can give: ``--name VALUE`` parsed by the field's type
(:func:`~imucalib.procedures.common.options.parse_text`), ``--name/--no-name`` for a yes/no
option. ``--help`` (:class:`GroupedHelpCommand`) shows them in sections (procedure, durations,
the unit, the twin, the plan file), each with its unit and default, and lists the Python-only
options with the reason the command line cannot give them. Nothing here names a procedure.

Contents
--------
:func:`spec_parameters`, :func:`given_values`, :class:`GroupedHelpCommand`, :func:`flags_of`
"""

from __future__ import annotations

import inspect
from collections.abc import Sequence
from typing import Annotated, Any, ClassVar

import typer
from typer.core import TyperCommand

from imucalib.procedures.common.options import (
    GROUP_TITLES,
    GROUPS,
    OptionSpec,
    parse_text,
)

__all__ = ["GroupedHelpCommand", "flags_of", "given_values", "spec_parameters"]


def _is_flag(spec: OptionSpec) -> bool:
    return spec.kind is bool and spec.shape == "scalar" and not spec.optional


def spec_parameters(specs: Sequence[OptionSpec]) -> list[inspect.Parameter]:
    """Return keyword parameters (Typer options) for the specs the command line can give.

    A value option is text, parsed later by :func:`given_values` (so that a bad value gets
    one line naming what the option expects); its default is None (not given).
    """
    out = []
    for spec in specs:
        if not spec.cli:
            continue
        panel = GROUP_TITLES[spec.info.group]
        if _is_flag(spec):
            opt = typer.Option(f"{spec.flag}/--no-{spec.flag[2:]}", help=spec.help_with_default(),
                               show_default=False, rich_help_panel=panel)
            annotation: Any = Annotated[bool, opt]
            default: Any = spec.default
        else:
            opt = typer.Option(spec.flag, help=spec.help_with_default(), metavar=spec.metavar(),
                               show_default=False, rich_help_panel=panel)
            annotation, default = Annotated[str | None, opt], None
        out.append(inspect.Parameter(spec.name, inspect.Parameter.KEYWORD_ONLY,
                                     default=default, annotation=annotation))
    return out


def flags_of(specs: Sequence[OptionSpec]) -> set[str]:
    """Return every flag the specs give on the command line (``--x`` and ``--no-x``)."""
    flags = set()
    for spec in specs:
        if spec.cli:
            flags.add(spec.flag)
            if _is_flag(spec):
                flags.add(f"--no-{spec.flag[2:]}")
    return flags


def given_values(ctx: typer.Context, specs: Sequence[OptionSpec]) -> dict[str, Any]:
    """Return {keyword: value} of the options given on the command line, parsed by type.

    Options left at their default are omitted, so that the procedure keeps its own defaults
    (the dataclass states them; a test checks they agree).

    Raises
    ------
    ConfigurationError
        A value that is not what the option takes (one line naming the flag).
    """
    out: dict[str, Any] = {}
    for spec in specs:
        if not spec.cli:
            continue
        source = ctx.get_parameter_source(spec.name)
        if source is None or source.name == "DEFAULT":
            continue
        value = ctx.params[spec.name]
        out[spec.name] = value if isinstance(value, bool) else parse_text(spec, str(value))
    return out


class GroupedHelpCommand(TyperCommand):
    """A Typer command whose ``--help`` shows its options in the specs' sections.

    A subclass sets :attr:`specs` (the procedure's options; the Python-only ones are listed by
    name and reason). The command's own options (``--out``) come first, under "Options".
    """

    specs: ClassVar[tuple[OptionSpec, ...]] = ()

    def format_options(self, ctx: Any, formatter: Any) -> None:
        """Write the command's own options, then one section per option group."""
        by_panel: dict[str | None, list[tuple[str, str]]] = {}
        for param in self.get_params(ctx):
            record = param.get_help_record(ctx)
            if record is not None:
                by_panel.setdefault(getattr(param, "rich_help_panel", None), []).append(record)
        with formatter.section("Options"):
            formatter.write_dl(by_panel.pop(None, []))
        for group in GROUPS:
            rows = by_panel.pop(GROUP_TITLES[group], [])
            if rows:
                with formatter.section(GROUP_TITLES[group]):
                    formatter.write_dl(rows)
        python_only = [(s.name, s.info.python_only) for s in self.specs if not s.cli]
        if python_only:
            with formatter.section("Python only (keywords with no flag)"):
                formatter.write_dl(python_only)
