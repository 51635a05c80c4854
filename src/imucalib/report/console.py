"""The terminal's shared pieces (rich): display units, the generic result table, the files written.

A procedure prints its result through its ``render_console`` hook
(:class:`~imucalib.procedures.common.procedure.Procedure`), called by ``imucalib calibrate`` and
the demo: a procedure with a table of its own keeps it in its folder
(``procedures/<name>/console.py``), built from these pieces; every other delegates to
:func:`render_generic`. This module names no procedure.

Contents
--------
:func:`render_generic`
    A result's ``parameter_rows()`` as a table, its decision and the files written.
:func:`print_written`
    The files written, one a line.
:func:`display_parameter`, :func:`display_unit`
    A triad parameter in its display unit (docs/reporting.md), GUM 7.2.6 rounding.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Column, Table

from imucalib import units
from imucalib.report.numbers import round_pair

__all__ = ["display_parameter", "display_unit", "print_written", "render_generic"]

# display unit of each parameter symbol: (unit text, SI value of one display unit); M's
# off-diagonal (misalignment) elements are in _OFF_DIAGONAL instead (docs/reporting.md)
_DISPLAY = {
    ("accel", "bias"): ("µg", units.UG), ("accel", "b"): ("µg", units.UG),
    ("gyro", "bias"): ("°/h", units.DEG_PER_H), ("gyro", "b"): ("°/h", units.DEG_PER_H),
    ("accel", "K"): ("ppm", units.PPM), ("gyro", "K"): ("ppm", units.PPM),
    ("accel", "M"): ("ppm", units.PPM), ("gyro", "M"): ("ppm", units.PPM),
    ("gyro", "G"): ("(°/h)/g", units.DEG_PER_H / units.G0_MPS2),
}
_OFF_DIAGONAL = ("µrad", units.URAD)


def display_parameter(name: str, value: float, sigma: float, si_unit: str
                      ) -> tuple[str, str, str]:
    """(value, uncertainty, unit) cells of one parameter in its display unit, GUM 7.2.6 rounding.

    `sigma` may be a standard or an expanded uncertainty: it is rounded to two significant
    digits and the value to the same decimal place (docs/reporting.md). A scale factor ``K`` is
    shown as its deviation from 1.
    """
    unit, scale = display_unit(name, si_unit)
    shown = value - 1.0 if name.split("_")[1:2] == ["K"] else value  # K as its deviation from 1
    cells = round_pair(shown / scale, sigma / scale, sign=True)
    return cells.value_text, cells.uncertainty_text, unit


def display_unit(name: str, si_unit: str) -> tuple[str, float]:
    """Return (display unit, SI value of one display unit) of a triad parameter (docs/reporting.md).

    ``accel_bias_x`` → ("µg", 9.80665e-6); an M off-diagonal element → ("µrad", 1e-6); a name
    outside the table keeps its SI unit (scale 1).
    """
    parts = name.split("_")
    if len(parts) < 2:
        return si_unit, 1.0
    triad, symbol = parts[0], parts[1]
    unit, scale = _DISPLAY.get((triad, symbol), (si_unit, 1.0))
    if symbol == "M" and len(parts) == 3 and len(parts[2]) == 2 and parts[2][0] != parts[2][1]:
        unit, scale = _OFF_DIAGONAL  # a misalignment, a small angle
    return unit, scale


def print_written(console: Console, written: Sequence[Path]) -> None:
    """Print the files written (``wrote a`` then one a line); nothing when none."""
    if not written:
        return
    console.print("wrote " + "\n      ".join(str(p) for p in written), highlight=False)


def render_generic(console: Console, result: Any, written: Sequence[Path]) -> None:
    """Print a result's ``parameter_rows()`` (one row per estimate), its decision, the files.

    The ``render_console`` of a procedure without a table of its own (the classical tests, a
    plug-in): without ``parameter_rows()`` only the decision and the files written.
    """
    rows = getattr(result, "parameter_rows", None)
    if callable(rows):
        table = Table("parameter", Column("value", justify="right"),
                      Column("std. uncertainty", justify="right"), "unit (SI)",
                      title=f"{result.procedure} {result.unit}")
        for name, value, sigma, unit in rows():
            cells = round_pair(float(value), float(sigma), sign=True)
            table.add_row(escape(str(name)), cells.value_text, cells.uncertainty_text,
                          escape(str(unit)))
        console.print(table)
    verdict = {None: "no decision", True: "PASS", False: "FAIL"}[result.passed]
    console.print(f"{result.procedure} result for {result.unit}: {verdict}", highlight=False)
    print_written(console, written)
