"""P1's result on the terminal: the parameters, the fit quality, the checks, the decision.

The ``render_console`` hook of :class:`~imucalib.procedures.p1.procedure.P1Procedure`, for
``imucalib calibrate`` and the demo: every parameter in its display unit with its standard
uncertainty (and the Birge-scaled one under a misfit, docs/processing-estimation.md), its
repeatability verdict, each fit's χ²/ν, the verification checks, the Kalman cross-check and the
decision (docs/reporting.md); the model terms each triad fit chose with every candidate's
χ², ν and criterion (docs/p1.md, "Model terms"); and the achieved σ against the plan's
predicted σ in one line, with one ``note:`` line when the run is worse than predicted
(docs/test-design.md, "Predicted against achieved").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Column, Table

from imucalib.report.console import display_parameter, print_written

__all__ = ["render_calibration"]


def render_calibration(console: Console, analysis: Any, written: Sequence[Path]) -> None:
    """Print a P1 analysis: the parameters, the checks, the decision and the files written."""
    result = analysis.result
    repeat = {r.name: r for c in analysis.checks if c.name == "repeatability" for r in c.rows}
    misfit = getattr(result, "misfit", False)
    columns: list[str | Column] = ["parameter", Column("value", justify="right"),
                                   Column("std. uncertainty", justify="right"), "unit",
                                   "repeatability"]
    if misfit:  # the Birge-scaled σ beside the noise-only σ (docs/processing-estimation.md)
        columns.insert(3, Column("σ × √(χ²/ν)", justify="right"))
    table = Table(*columns,
                  title=f"{result.sensor_id}: {result.procedure.upper()} {result.model} model")
    std = result.std()
    for name in result.param_names:
        value, sigma, unit = display_parameter(name, result.value(name), std[name],
                                      result.units[name])
        row = repeat.get(name)
        rep = "—" if row is None else ("[green]pass[/]" if row.passed else "[red]FAIL[/]")
        cells = [name, value, sigma, unit, rep]
        if misfit:
            scale = result.sigma_scale(name)
            cells.insert(3, display_parameter(name, result.value(name), std[name] * scale,
                                     result.units[name])[1] if scale != 1.0 else "")
        table.add_row(*cells)
    console.print(table)
    for q in getattr(result, "fit_quality", ()):
        console.print(("[bold red]" if q.misfit else "") + escape(q.summary())
                      + ("[/]" if q.misfit else ""), highlight=False)
    selection = getattr(analysis, "model_selection", ())
    if selection:
        from imucalib.procedures.p1.report import MODEL_SELECTION_COLUMNS, model_selection_rows

        terms = Table(*MODEL_SELECTION_COLUMNS, title="model terms (docs/p1.md)")
        for row in model_selection_rows(selection):
            terms.add_row(*(escape(c) for c in row))
        console.print(terms)
    checks = Table("check", "verdict", "summary", title="verification")
    for c in analysis.checks:
        verdict = ("not assessed" if c.passed is None
                   else "[green]pass[/]" if c.passed else "[red]FAIL[/]")
        checks.add_row(c.name, verdict, c.summary)
    console.print(checks)
    if not math.isnan(analysis.kalman_max_difference_sigma):
        console.print(f"Kalman refinement agrees with least squares to "
                      f"{analysis.kalman_max_difference_sigma:.2g} σ; reported σ / Cramér–Rao "
                      f"bound: {max(analysis.crlb_ratio.values()):.4f}", highlight=False)
    prediction = getattr(analysis, "prediction", None)
    if prediction is not None:
        console.print(prediction.summary(), highlight=False, soft_wrap=True, markup=False)
        warning = prediction.warning()
        if warning:
            console.print(f"note: {warning}", highlight=False, soft_wrap=True, markup=False)
    colour = "green" if analysis.decision.passed else "red"
    console.print(f"[bold {colour}]{analysis.decision.summary()}[/]", highlight=False)
    print_written(console, written)
