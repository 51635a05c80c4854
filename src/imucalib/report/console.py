"""A procedure result on the terminal (rich tables), for ``imucalib calibrate`` and the demo.

Contents
--------
:func:`render_result`
    Dispatch on the result's procedure: :func:`render_calibration` (P1: the parameters, the
    checks, the decision) or :func:`render_noise_characterization` (Allan: each record's noise
    terms); a procedure without a renderer gets its decision and the files written.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Column, Table

from imucalib import units
from imucalib.report.numbers import round_pair

__all__ = ["display_parameter", "display_unit", "render_calibration",
           "render_noise_characterization", "render_p3",
           "render_result"]

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


def _wrote(console: Console, written: Sequence[Path]) -> None:
    if not written:
        return
    console.print("wrote " + "\n      ".join(str(p) for p in written), highlight=False)


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
    colour = "green" if analysis.decision.passed else "red"
    console.print(f"[bold {colour}]{analysis.decision.summary()}[/]", highlight=False)
    _wrote(console, written)


def render_noise_characterization(console: Console, result: Any, written: Sequence[Path]
                                  ) -> None:
    """Print each record's noise-term table and the files written."""
    from imucalib.report.noise_table import format_noise_table

    for seg in result.segments:
        temp = "" if seg.temperature_degc is None else f", {seg.temperature_degc:.1f} °C"
        console.print(f"[bold]{seg.label}[/]: {seg.n_samples:,} samples at "
                      f"{seg.sample_rate_hz:g} Hz{temp}", highlight=False)
        console.print(format_noise_table(seg.fits(), fmt="text"), highlight=False,
                      soft_wrap=True)
    _wrote(console, written)


def _render_other(console: Console, result: Any, written: Sequence[Path]) -> None:
    """Print a result with ``parameter_rows()`` (the classical tests): one row per estimate."""
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
    _wrote(console, written)


def render_p2(console: Console, batch: Any, written: Sequence[Path]) -> None:
    """Print a P2 batch: a row per unit (decision, errors after compensation, lever arm).

    Then each unit's warning notes: temperature models that do not fit or do not predict.
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
            " held out", "; ".join(r.reasons))
    console.print(table)
    for r in batch.results:  # the warnings among the analysis notes: models that do not fit
        for note in r.notes:
            if note.startswith(("the temperature models of", "held-out check:")):
                console.print(f"note ({escape(r.unit)}): {escape(note)}", highlight=False,
                              soft_wrap=True)
    verdict = "PASS" if batch.passed else "FAIL"
    n_ok = sum(bool(r.passed) for r in batch.results)
    console.print(f"decision: {verdict} ({n_ok} of {len(batch.results)} unit(s) passed)",
                  highlight=False)
    _wrote(console, written)


def render_p3(console: Console, result: Any, written: Sequence[Path]) -> None:
    """Print a P3 result: K2 of the three accelerometers, c and c′, the naive K2, the decision."""
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
    verdict = "[green]PASS[/]" if result.passed else "[red]FAIL[/]"
    console.print(f"decision: {verdict} (U(K2) = 2σ = {2 * k2_std:.2g} g/g², target "
                  f"{result.k2_target_g_per_g2:.2g} g/g²)")
    _wrote(console, written)


def render_field(console: Console, result: Any, written: Sequence[Path]) -> None:
    """Print a field calibration: the parameters, each fit's χ²/ν, the session, the notes."""
    _render_other(console, result, [])
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
    _wrote(console, written)


_RENDERERS: dict[str, Callable[[Console, Any, Sequence[Path]], None]] = {
    "field": render_field,
    "p1": render_calibration,
    "p2": render_p2,
    "p3": render_p3,
    "allan": render_noise_characterization,
}


def render_result(console: Console, result: Any, written: Sequence[Path]) -> None:
    """Print a procedure result (module docstring)."""
    _RENDERERS.get(result.procedure, _render_other)(console, result, written)
