"""A P3 result on the terminal: K2 of the three accelerometers, c and c′, the decision.

The ``render_console`` hook of :class:`~imucalib.procedures.p3.procedure.P3Procedure`, for
``imucalib calibrate`` (docs/p3.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Column, Table

from imucalib import units
from imucalib.report.console import print_written
from imucalib.report.numbers import round_pair

__all__ = ["render_p3"]


def render_p3(console: Console, result: Any, written: Sequence[Path]) -> None:
    """Print a P3 result: K2 of the three accelerometers, c and c′, the naive K2, the decision.

    The decision is the result's :class:`~imucalib.models.decision.Decision` (its verdict).
    """
    est = result.estimate
    g = units.G0_MPS2 * 1e6  # K2 [1/(m/s²)] → µg/g²
    table = Table("quantity", Column("value", justify="right"),
                  Column("std. uncertainty", justify="right"), "unit",
                  title=f"P3 {result.unit}: K2 on the centrifuge, dynamic unbalance compensated")
    rows = [(f"K2 of {result.roles['test']} (test)", est.value("K2_T") * g,
             est.std("K2_T") * g, "µg/g²"),
            (f"K2 of {result.roles['ref-a']} (reference A)", est.value("K2_A") * g,
             est.std("K2_A") * g, "µg/g²"),
            (f"K2 of {result.roles['ref-b']} (reference B)", est.value("K2_B") * g,
             est.std("K2_B") * g, "µg/g²"),
            ("c (unbalance, no test load)", est.value("c") * 1e9, est.std("c") * 1e9,
             "nm/(rad/s)²"),
            ("c′ (with the test load)", est.value("c_loaded") * 1e9,
             est.std("c_loaded") * 1e9, "nm/(rad/s)²"),
            ("K2 of the test, unbalance ignored", est.naive_k2_t * g, est.naive_k2_t_std * g,
             "µg/g²")]
    for name, value, sigma, unit in rows:
        cells = round_pair(value, sigma, sign=True)
        table.add_row(escape(name), cells.value_text, cells.uncertainty_text, unit)
    console.print(table)
    console.print(est.quality.summary(), highlight=False)
    k2_std = est.std("K2_T") * units.G0_MPS2
    decision = result.decision
    colour = {True: "green", False: "red", None: "yellow"}[decision.passed]
    console.print(f"decision: [{colour}]{decision.verdict}[/] (U(K2) = 2σ = {2 * k2_std:.2g} "
                  f"g/g², target {result.k2_target_g_per_g2:.2g} g/g²)")
    print_written(console, written)
