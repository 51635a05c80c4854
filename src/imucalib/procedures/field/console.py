"""A field calibration on the terminal: the parameters, each fit's χ²/ν, the session, the notes.

The ``render_console`` hook of :class:`~imucalib.procedures.field.procedure.FieldProcedure`, for
``imucalib calibrate field`` (docs/field.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape

from imucalib.report.console import print_written, render_generic

__all__ = ["render_field"]


def render_field(console: Console, result: Any, written: Sequence[Path]) -> None:
    """Print a field calibration: the parameters, each fit's χ²/ν, the session, the notes."""
    render_generic(console, result, [])
    for q in result.quality:
        flag = (f"[yellow]misfit: σ × {q.sigma_scale:.3g} (Birge)[/]" if q.misfit
                else "consistent with the noise")
        console.print(f"  {escape(q.group)}: χ²/ν = {q.reduced_chi2:.3g} (ν = {q.dof}), {flag}",
                      highlight=False)
    turns = sum(1 for r in result.rotations if r["kind"] == "turn")
    console.print(f"  {len(result.poses)} static poses (detector k = {result.threshold_factor:g}),"
                  f" {len(result.rotations)} rotations ({turns} full turns); accelerometer "
                  f"{result.accel_form}, gyro {result.gyro_form}", highlight=False,
                  soft_wrap=True)
    need = {n: k for n, k in result.coverage.get("poses_needed", {}).items() if k > 0}
    if need:
        worst = max(need.values())
        more = f"more than {worst - 1}" if worst > 50 else str(worst)
        console.print(f"  to bring every accelerometer σ under its target: {more} more pose(s) "
                      f"({', '.join(sorted(need))}); the report's coverage says where",
                      highlight=False, soft_wrap=True)
    for note in result.notes:
        console.print(f"  [yellow]note:[/] {escape(note)}", highlight=False, soft_wrap=True)
    print_written(console, written)
