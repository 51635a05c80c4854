"""Progress bars of the long commands: on a terminal's stderr only, never in pipes or tests.

Library functions report progress through a plain callback (a fraction done, or done and
total); :func:`progress_bar` turns one into a rich progress bar with an ETA, drawn on stderr
when stderr is a terminal and ``--quiet`` was not given. Otherwise the callback does nothing,
so output captured from a pipe, a file or a test holds no escape codes.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Protocol

from imucalib.cli._app import err_console

if TYPE_CHECKING:
    from rich.progress import Progress

__all__ = ["QUIET_HELP", "ProgressUpdate", "make_progress", "progress_bar", "shows_progress"]

#: Help text of the ``--quiet`` option of the commands that draw a progress bar.
QUIET_HELP = "No progress bar (none is drawn anyway when stderr is not a terminal)."


class ProgressUpdate(Protocol):
    """``update(fraction, detail="")``: the fraction done (0 to 1) and a short text."""

    def __call__(self, fraction: float, detail: str = "") -> None:
        """Move the bar to `fraction`; show `detail` beside it."""


def _hidden(fraction: float, detail: str = "") -> None:
    """Do nothing: the update of a bar that is not drawn."""


def shows_progress(quiet: bool = False) -> bool:
    """Whether progress is drawn: stderr is a terminal and ``--quiet`` was not given."""
    return not quiet and err_console.is_terminal


def make_progress() -> Progress:
    """Return a rich Progress on stderr: description, bar, percentage, text, elapsed, ETA."""
    from rich.progress import (
        BarColumn,
        Progress,
        TaskProgressColumn,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    return Progress(TextColumn("[bold]{task.description}"), BarColumn(), TaskProgressColumn(),
                    TextColumn("{task.fields[detail]}"), TimeElapsedColumn(),
                    TimeRemainingColumn(), console=err_console, transient=True)


@contextmanager
def progress_bar(description: str, *, quiet: bool = False
                 ) -> Iterator[ProgressUpdate]:
    """Yield ``update(fraction, detail="")`` drawing a bar with an ETA (a no-op when hidden).

    Parameters
    ----------
    description : str
        Shown before the bar (text, not markup).
    quiet : bool
        ``--quiet``: draw nothing.
    """
    if not shows_progress(quiet):
        yield _hidden
        return
    from rich.markup import escape

    with make_progress() as progress:
        task = progress.add_task(escape(description), total=1.0, detail="")

        def update(fraction: float, detail: str = "") -> None:
            progress.update(task, completed=min(max(fraction, 0.0), 1.0), detail=detail)

        yield update
