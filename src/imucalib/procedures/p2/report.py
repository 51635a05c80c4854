"""P2's part of the calibration report of one unit: the parameters at T0, their temperature models.

One unit of an array full-temperature calibration (docs/p2.md) gets its own report: the
parameters at the reference temperature T0 with U = k·u (R.1 of :mod:`imucalib.report.document`),
each parameter's temperature model (order and how it was chosen, the linear coefficient c₁ of
(T1) with its U, χ²/ν of the fit, the held-out check of the model at temperatures it was not
fitted to), the errors left after compensation that the decision judges, and the figure of every
parameter against the unit's internal temperature with its model and 2σ band
(:func:`~imucalib.procedures.p2.figures.save_temperature_figure`). The ``report_content`` hook of
:class:`~imucalib.procedures.p2.procedure.P2Procedure`; the summary of the whole array or lot is
:mod:`imucalib.procedures.p2.summary_report`.

(T1): p(T, Ṫ, ℓ) = Σ c_j (T − T0)^j + d·Ṫ + h·ℓ (docs/processing-estimation.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from imucalib import units
from imucalib.report.document import (
    SECTION_TITLES,
    ReportContent,
    ReportTable,
    Section,
)
from imucalib.report.sections import (
    environment_section,
    equipment_section,
    figure_of,
    object_section,
    parameter_table,
    recommendations,
    temperature_model_table,
    u_paragraph,
)

__all__ = ["content"]


def _worst_point_fits(points: Any) -> list[Any]:
    """Return the largest-χ²/ν fit quality of each triad over the calibration points."""
    fits = [q for p in points if not p.held_out for q in p.least_squares.fit_quality]
    return [max((q for q in fits if q.group == g), key=lambda q: q.reduced_chi2)
            for g in ("gyro", "accel") if any(q.group == g for q in fits)]


def _error_rows(unit_result: Any) -> tuple[tuple[str, ...], ...]:
    """(triad, error, limit, verdict): the errors left after compensation against the plan's."""
    err, limits = unit_result.compensated_error, unit_result.error_limits
    rows = []
    for key, triad, scale, unit in (("accel_mps2", "accelerometer", units.G0_MPS2 * 1e-3, "mg"),
                                    ("gyro_rps", "gyro", units.DEG, "°/s")):
        if err.get(key) is None:
            continue
        limit = limits.get(key)
        rows.append((triad, f"{err[key] / scale:.3g} {unit}",
                     "—" if limit is None else f"{limit / scale:.3g} {unit}",
                     "—" if limit is None else "pass" if err[key] <= limit else "FAIL"))
    return tuple(rows)


def _held_out_note(unit_result: Any) -> str:
    """Return the decision's note on the held-out consistency (empty when every model holds)."""
    from imucalib.procedures.p2.result import HELD_OUT_CHECK

    return next((n for n in unit_result.decision.notes if n.startswith(HELD_OUT_CHECK)), "")


def content(unit_result: Any, meta: Mapping[str, Any]) -> ReportContent | None:
    """Return a P2 unit's sections 1–5 (None for anything but a calibrated P2 unit)."""
    from imucalib.procedures.p2.result import P2UnitResult

    if not isinstance(unit_result, P2UnitResult) or unit_result.result is None:
        return None
    from imucalib.procedures.p2.figures import save_temperature_figure

    cal = unit_result.result
    prov = cal.provenance
    points = unit_result.points
    temps = [p.temperature_degc for p in points]
    held = sum(p.held_out for p in points)
    legs = sorted({p.leg for p in points})
    t0 = cal.reference_temperature_degc
    site = {"temperature points (internal, min / max)":
            f"{min(temps):+.1f} / {max(temps):+.1f} °C" if temps else "—",
            "temperature legs": ", ".join(legs) or "—"}
    process = Section(SECTION_TITLES[3], (
        "Procedure P2 (docs/p2.md): array full-temperature calibration — the IMUs on a cube in "
        "a thermal chamber on a rotation table; at each temperature point static positions and "
        "±ω turns give every parameter (least squares, with the closed form as a cross-check); "
        "each parameter's temperature dependence is fitted as a polynomial (T1) whose order is "
        "chosen by AICc or cross-validation; held-out temperature points check the models.",
        f"{len(points) - held} calibration and {held} held-out temperature point(s); the "
        f"parameters hold at T0 = {t0:g} °C.",
        *(f"worst point fit, {q.summary()}" for q in _worst_point_fits(points)),
        *(f"Note: {n}" for n in unit_result.notes)))
    tables = [parameter_table(cal, f"parameters of {unit_result.unit} at T0 = {t0:g} °C"),
              temperature_model_table(cal)]
    errors = _error_rows(unit_result)
    if errors:
        tables.append(ReportTable("largest error after compensation (held-out points when there "
                                  "are any)", ("triad", "error", "limit (plan)", "verdict"),
                                  errors))
    fig = figure_of(lambda p: save_temperature_figure(unit_result, p),
                    "Every parameter against the unit's internal temperature: the estimate at "
                    "each point with 2σ bars (open: held out), the model with its 2σ band, per "
                    "leg.")
    reasons = list(unit_result.reasons)
    held_note = _held_out_note(unit_result)
    results = Section(SECTION_TITLES[4],
                      (u_paragraph(), "Decision rule: the largest accelerometer and gyro error "
                       "left after compensation, at the held-out temperature points, within the "
                       "plan's accuracy limits; the closed form agrees with least squares. The "
                       "held-out consistency of the temperature models (each model's max|z| ≤ 3 "
                       "and p ≥ 0.01 at the held-out points, the table above) is reported with "
                       "the decision but is not part of this rule (docs/p2.md, \"The "
                       "decision\").",
                       *(f"Failed: {r}." for r in reasons),
                       *((f"Not part of the rule: {held_note}.",) if held_note else ())),
                      tuple(tables), (fig,) if fig is not None else ())
    passed = unit_result.passed
    bad = unit_result.held_out_inconsistent
    beside = (f" {len(bad)} of {len(unit_result.held_out)} temperature models are NOT "
              "consistent at the held-out points, which P2's rule does not judge (section 5)."
              if bad else "")
    decision = ("Every check of P2's rule passed." + beside if passed else
                "FAIL: " + "; ".join(reasons) + "." + beside if passed is False else
                "No conformity decision was made.")
    misfit = (any(q.misfit for q in _worst_point_fits(points))
              or any(m.quality.misfit for m in unit_result.models.values()))
    recs = recommendations(passed, reasons, (), misfit)
    if bad:  # "may be applied" says what it does not judge
        recs = [f"{r.rstrip('.')}; but {len(bad)} temperature model(s) do not predict the "
                "held-out points within their uncertainty: their U between the calibration "
                "temperatures may be understated (add temperature points, or raise "
                "--max-order, and recalibrate if that matters for the use)."
                if "may be applied" in r else r for r in recs]
    details = dict(prov.details)
    sections = (object_section(details.get("unit", {"serial": unit_result.unit}),
                               str(unit_result.unit)),
                equipment_section(meta, None, prov.software_version),
                environment_section(meta, site), process, results)
    return ReportContent(sections, decision, passed, tuple(recs), prov)
