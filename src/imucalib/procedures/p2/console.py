"""A P2 batch (an array or a lot) on the terminal: one row per unit, the warnings, the decision.

The ``render_console`` hook of :class:`~imucalib.procedures.p2.procedure.P2Procedure`, for
``imucalib calibrate`` (docs/p2.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Column, Table

from imucalib import units
from imucalib.procedures.p2.result import HELD_OUT_CHECK
from imucalib.report.console import print_written

__all__ = ["render_p2"]


def render_p2(console: Console, batch: Any, written: Sequence[Path]) -> None:
    """Print a P2 batch: a row per unit (decision, errors after compensation, lever arm).

    Then each unit's warning notes: temperature models that do not fit or do not predict; and
    the decision line with, beside the units passed, the number of units whose temperature
    models are NOT consistent at the held-out points (not part of P2's rule, docs/p2.md "The
    decision", so a PASS does not hide them).
    """
    table = Table("unit", "decision", Column("accel error [mg]", justify="right"),
                  Column("gyro error [°/h]", justify="right"),
                  Column("lever arm [cm]", justify="right"), "points", "note",
                  title=f"P2 {batch.unit}: temperature-compensated calibration of "
                        f"{len(batch.results)} unit(s)")
    for r in batch.results:
        if r.error:
            table.add_row(r.unit, "[red]FAIL[/]", "", "", "", "", r.error)
            continue
        arm = r.result.provenance.details.get("lever_arm_m", [0.0, 0.0, 0.0])
        err = r.compensated_error
        table.add_row(
            r.unit, "[green]PASS[/]" if r.passed else "[red]FAIL[/]",
            f"{err['accel_mps2'] / (1e-3 * units.G0_MPS2):.3g}",
            f"{err['gyro_rps'] / units.DEG_PER_H:.3g}",
            ", ".join(f"{100 * a:+.1f}" for a in arm),
            f"{sum(not p.held_out for p in r.points)} + {sum(p.held_out for p in r.points)}"
            " held out", "; ".join([*r.reasons, *_held_out_cell(r)]))
    console.print(table)
    for r in batch.results:  # the warnings: models that do not fit, or do not predict
        notes = [n for n in r.notes if n.startswith("the temperature models of")]
        if r.held_out_inconsistent:  # the decision's note: how many, why not in the verdict
            notes += [n for n in r.decision.notes if n.startswith(HELD_OUT_CHECK)]
        for note in notes:
            console.print(f"note ({escape(r.unit)}): {escape(note)}", highlight=False,
                          soft_wrap=True)
    verdict = "PASS" if batch.passed else "FAIL"
    n_ok = sum(bool(r.passed) for r in batch.results)
    held = [r for r in batch.results if r.held_out_inconsistent]
    also = (f"; {len(held)} of {len(batch.results)} unit(s) with temperature models NOT "
            "consistent at the held-out points, not part of P2's rule: see the notes"
            if held else "")
    console.print(f"decision: {verdict} ({n_ok} of {len(batch.results)} unit(s) passed{also})",
                  highlight=False, soft_wrap=True)
    print_written(console, written)


def _held_out_cell(r: Any) -> list[str]:
    """Return the note cell's count of the models NOT consistent at the held-out points."""
    bad = r.held_out_inconsistent
    if not bad:
        return []
    return [f"{len(bad)} of {len(r.held_out)} models NOT consistent at held-out points"]
