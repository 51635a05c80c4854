"""The Typer application and the console helpers shared by every command module.

The app's root group is :class:`~imucalib.cli._commands.CommandsOnDemand`: a command's module
is imported when the command is asked for, so the modules register their commands on this app
as they are imported (docs/architecture.md, "The command line starts light").

Help texts are plain text, not rich markup: units in brackets (``Moving-window length [s].``)
and table names (``the plan's [twin]``) must show as written, so every Typer app of the command
line is made by :func:`typer_app`, which turns rich markup off.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.markup import escape

from imucalib.cli._commands import CommandsOnDemand

__all__ = ["app", "console", "err_console", "fail", "typer_app"]


def typer_app(**options: Any) -> typer.Typer:
    """Return a Typer app (the root or a command group) whose help texts are not markup."""
    return typer.Typer(rich_markup_mode=None, **options)


app = typer_app(
    name="imucalib",
    cls=CommandsOnDemand,
    help="Inertial-sensor calibration station: twin, recordings, analysis.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console()
err_console = Console(stderr=True)
#: The ``sys.excepthook`` the entry point chose (:func:`imucalib.cli.main`): Typer installs its
#: own when the app starts, and the root callback puts this one back (h5py prints, through
#: the hook, the errors HDF5 raises while Python frees an object of a file it failed to write).
EXCEPTHOOK: list[Callable[..., Any]] = []


def _print_version(value: bool) -> None:
    if value:
        from imucalib import __version__

        typer.echo(f"imucalib {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[bool, typer.Option(
        "--version", callback=_print_version, is_eager=True,
        help="Print the version and exit.")] = False,
) -> None:
    """Inertial-sensor calibration station: twin, recordings, analysis."""
    if EXCEPTHOOK:
        sys.excepthook = EXCEPTHOOK[0]


def fail(exc: Exception) -> typer.Exit:
    """Print `exc` as an error line and return the exit (code 2) to raise.

    The message is printed as it is: brackets in it (``time_s [furlong]``) are not markup.
    """
    err_console.print(f"[bold red]error:[/] {escape(str(exc))}", highlight=False,
                      soft_wrap=True)
    return typer.Exit(code=2)
