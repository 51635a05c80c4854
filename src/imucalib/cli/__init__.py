"""The ``imucalib`` command line: argument handling and rendering only, no maths.

Each module registers its commands on the one Typer app of :mod:`imucalib.cli._app`.

Commands
--------
``simulate SCENARIO --out FILE``   run a twin scenario (built-in name or TOML file) into a Recording
``scenarios``                      list the built-in scenarios
``inspect FILE``                   summarise a Recording: streams, units, steps, rates, gaps
``recover FILE``                   copy out what a crashed writer left in an open Recording
``export FILE --stream DEV/UNIT``  write a stream (or one step of it) as CSV or MAT
``plan validate|show|schema``      check a plan, print its expanded steps, export its JSON Schema
``run PLAN [--station sim|FILE]``  execute a plan on the twin or on equipment (``--resume FILE``)
``calibrate RECORDING``            estimate, verify and decide; write the result JSON
``apply RESULT DATA --out CSV``    correct a recording's IMU stream or a CSV file
``station check STATION.toml``     connect to real equipment, identify, read status; move nothing
"""

from __future__ import annotations

import logging

from imucalib.cli import calibrate, plan, recording, run, station, twin  # noqa: F401 (register)
from imucalib.cli._app import app

__all__ = ["app", "main"]


def main() -> None:
    """Entry point of the ``imucalib`` console script."""
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    app()
