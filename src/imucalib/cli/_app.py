"""The Typer application and the console helpers shared by every command module."""

from __future__ import annotations

import typer
from rich.console import Console
from rich.markup import escape

__all__ = ["app", "console", "err_console", "fail"]

app = typer.Typer(
    name="imucalib",
    help="Inertial-sensor calibration station: twin, recordings, analysis.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console()
err_console = Console(stderr=True)


def fail(exc: Exception) -> typer.Exit:
    """Print `exc` as an error line and return the exit (code 2) to raise.

    The message is printed as it is: brackets in it (``time_s [furlong]``) are not markup.
    """
    err_console.print(f"[bold red]error:[/] {escape(str(exc))}", highlight=False,
                      soft_wrap=True)
    return typer.Exit(code=2)
