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

import re
from collections.abc import Sequence
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.table import Column, Table

from imucalib import units
from imucalib.models.fit_quality import FitQuality
from imucalib.models.procedure_result import ProcedureResult
from imucalib.report.numbers import round_pair

__all__ = ["DISPLAY_UNITS", "display_parameter", "display_unit", "print_fit_quality",
           "print_written", "render_generic"]

#: The display unit of each kind of quantity, by its SI unit: (unit text, SI value of one display
#: unit). One table for every console, report and records view (docs/reporting.md, "Display
#: units"); a quantity whose SI unit is not here is shown in SI.
DISPLAY_UNITS: dict[str, tuple[str, float]] = {
    "m/s^2": ("µg", units.UG),                                      # accelerometer bias, K0
    "rad/s": ("°/h", units.DEG_PER_H),                              # gyro bias, drift
    "(rad/s)/(m/s^2)": ("(°/h)/g", units.DEG_PER_H / units.G0_MPS2),  # g-sensitivity G, D1–D3
    "rad/s/(m/s^2)": ("(°/h)/g", units.DEG_PER_H / units.G0_MPS2),    # (the same, as P1 writes)
    "1/(m/s^2)": ("µg/g²", units.UG / units.G0_MPS2**2),            # K2, Kip (output per input²)
    "1/(m/s^2)^2": ("µg/g³", units.UG / units.G0_MPS2**3),          # K3
    "s/rad": ("ppm/(°/s)", units.PPM / units.DEG_PER_S),            # a gyro's quadratic term
    "1": ("ppm", units.PPM),                                        # scale factor, misalignment
    "1/K": ("ppm/K", units.PPM),                                    # a scale factor's temp. coeff.
    "m/s^3": ("µg/s", units.UG),                                    # an accelerometer bias's drift
    "rad/s^2": ("(°/h)/s", units.DEG_PER_H),                        # a gyro bias's drift
    "rad": ("µrad", units.URAD),                                    # small angles
}
#: A dimensionless parameter that is a small angle: an off-diagonal M element (misalignment).
_OFF_DIAGONAL = ("µrad", units.URAD)
#: Names of scale factors (about 1), shown as their deviation from 1 in ppm.
_SCALE_FACTOR = re.compile(r"(^|_)(K|K1|scale_factor|scale_from_earth_rate)(_|$)")


def _is_misalignment(parts: list[str]) -> bool:
    """Whether a name's parts are an off-diagonal element of M (``gyro_M_xy``)."""
    return (len(parts) >= 3 and parts[1] == "M" and len(parts[2]) == 2
            and parts[2][0] != parts[2][1])


#: A unit per kelvin power: a temperature model's coefficient (``m/s^2/K``, ``1/K^2``).
_PER_KELVIN = re.compile(r"^(?P<base>.+)/K(\^(?P<power>[2-9]))?$")


def _per_kelvin(si_unit: str) -> tuple[str, float] | None:
    """Display unit of a temperature coefficient: its base quantity's, per K^j (same scale)."""
    m = _PER_KELVIN.match(si_unit)
    if m is None or m["base"] not in DISPLAY_UNITS:
        return None
    text, scale = DISPLAY_UNITS[m["base"]]
    if "/" in text and not (text.startswith("(") and text.endswith(")")):
        text = f"({text})"
    return f"{text}/K" + (f"^{m['power']}" if m["power"] else ""), scale


def display_parameter(name: str, value: float, sigma: float, si_unit: str
                      ) -> tuple[str, str, str]:
    """(value, uncertainty, unit) cells of one parameter in its display unit, GUM 7.2.6 rounding.

    `sigma` may be a standard or an expanded uncertainty: it is rounded to two significant
    digits and the value to the same decimal place (docs/reporting.md). A scale factor (``K``,
    ``K1``, ``scale_factor`` …, dimensionless) is shown as its deviation from 1.
    """
    unit, scale = display_unit(name, si_unit)
    shown = value - 1.0 if _is_scale_factor(name, si_unit) else value
    cells = round_pair(shown / scale, sigma / scale, sign=True)
    return cells.value_text, cells.uncertainty_text, unit


def _is_scale_factor(name: str, si_unit: str) -> bool:
    return si_unit in ("1", "") and bool(_SCALE_FACTOR.search(name)) and \
        not _is_misalignment(name.split("_"))


def display_unit(name: str, si_unit: str) -> tuple[str, float]:
    """Return (display unit, SI value of one display unit) of a parameter (docs/reporting.md).

    By its SI unit (:data:`DISPLAY_UNITS`): ``accel_bias_x`` in m/s² → ("µg", 9.80665e-6), a
    gyro bias in rad/s → ("°/h", …); an off-diagonal M element → ("µrad", 1e-6); a triad
    parameter of the model (``accel_b_x``, ``gyro_G_xy``) by the kind its name says; any other
    quantity keeps its SI unit (scale 1).
    """
    parts = name.split("_")
    if _is_misalignment(parts) and si_unit in ("", "1"):
        # a dimensionless one (gyro_M_xy_closed too); its temperature coefficient
        # (gyro_M_xy_c1, 1/K) is shown by its own unit
        return _OFF_DIAGONAL
    if len(parts) == 3 or (len(parts) >= 2 and si_unit in ("", "1")):
        # a triad parameter's kind is its name's (whatever unit it was given); a longer name
        # with a unit of its own (accel_bias_rate_x in m/s^3) is another quantity
        si_unit = _P1_SI_UNITS.get((parts[0], parts[1]), si_unit)
    if si_unit in DISPLAY_UNITS:
        return DISPLAY_UNITS[si_unit]
    return _per_kelvin(si_unit) or (si_unit, 1.0)


#: The SI unit of each symbol of the triad model (docs/reporting.md).
_P1_SI_UNITS = {("accel", "bias"): "m/s^2", ("accel", "b"): "m/s^2",
                ("gyro", "bias"): "rad/s", ("gyro", "b"): "rad/s",
                ("accel", "K"): "1", ("gyro", "K"): "1", ("accel", "M"): "1", ("gyro", "M"): "1",
                ("gyro", "G"): "(rad/s)/(m/s^2)"}


def print_written(console: Console, written: Sequence[Path]) -> None:
    """Print the files written (``wrote a`` then one a line); nothing when none."""
    if not written:
        return
    console.print("wrote " + "\n      ".join(str(p) for p in written), highlight=False)


def print_fit_quality(console: Console, quality: Sequence[FitQuality]) -> None:
    """Print each fit's χ²/ν, one a line; a misfit in yellow, saying its σ are Birge-scaled."""
    for q in quality:
        style = "yellow" if q.misfit else None
        console.print(escape(q.summary()), style=style, highlight=False, soft_wrap=True)


def render_generic(console: Console, result: ProcedureResult, written: Sequence[Path]) -> None:
    """Print a result's ``parameter_rows()``, each fit's χ²/ν, its decision and the files.

    The ``render_console`` of a procedure without a table of its own (the classical tests, a
    plug-in); a result without parameter rows prints its decision and the files only.
    """
    rows = result.parameter_rows()
    if rows:
        table = Table("parameter", Column("value", justify="right"),
                      Column("std. uncertainty", justify="right"), "unit",
                      title=f"{result.procedure} {result.unit}")
        for row in rows:
            value_text, sigma_text, shown = display_parameter(row.name, row.value, row.std,
                                                              row.unit)
            table.add_row(escape(row.name), value_text, sigma_text, escape(shown))
        console.print(table)
    print_fit_quality(console, result.fit_quality)
    decision = result.decision  # its notes repeat the misfits printed above
    failed = f"; failed: {', '.join(decision.failed)}" if decision.failed else ""
    console.print(f"{result.procedure} result for {result.unit}: {decision.verdict} "
                  f"({escape(decision.rule)}{escape(failed)})", highlight=False, soft_wrap=True)
    print_written(console, written)
