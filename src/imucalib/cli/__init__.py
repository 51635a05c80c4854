"""The ``imucalib`` command line: argument handling and rendering only, no maths.

Each module registers its commands on the one Typer app of :mod:`imucalib.cli._app`.

Commands
--------
``simulate SCENARIO --out FILE``   run a twin scenario (built-in name or TOML file) into a Recording
``scenarios``                      list the built-in scenarios
``inspect FILE``                   summarise a Recording: streams, units, steps, rates, gaps
``recover FILE``                   copy out what a crashed writer left in an open Recording
``export FILE --stream DEV/UNIT``  write a stream (or one step of it) as CSV or MAT
"""

from __future__ import annotations

import logging

from imucalib.cli import recording, station, twin  # noqa: F401  (they register their commands)
from imucalib.cli._app import app

__all__ = ["app", "main"]


def main() -> None:
    """Entry point of the ``imucalib`` console script."""
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    app()
