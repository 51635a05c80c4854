"""P1's part of the calibration report: process, parameters, checks, residual and checks figures.

The ``report_content`` hook of :class:`~imucalib.procedures.p1.procedure.P1Procedure` (sections
1–5; :func:`~imucalib.report.document.assemble_report` adds the conclusion and the appendix).

The results section holds every parameter with U = k·u (R.1 of :mod:`imucalib.report.document`),
the verification checks, the conformity table against the plan's acceptance limits, the
residual figure (per position and rate), the held-out/repeatability figure, the model terms each
triad's fit chose with every candidate's χ², ν and criterion (:func:`model_selection_rows`,
docs/p1.md "Model terms"), the noise model
of the long static records that gave the window means' standard errors, as a table and as
Allan deviation curves (docs/p1.md, docs/reporting.md), and, when the recording holds its plan,
each parameter's predicted σ (the plan's, with the grade's noise and with the fitted noise)
beside the achieved σ (:func:`prediction_rows`; docs/test-design.md, "Predicted against
achieved").
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

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
    u_paragraph,
    yes_no,
)

__all__ = ["MODEL_SELECTION_COLUMNS", "PREDICTION_COLUMNS", "content", "model_selection_rows",
           "prediction_rows", "type_b_terms"]

#: The columns of :func:`model_selection_rows`.
MODEL_SELECTION_COLUMNS = ("triad fit", "terms", "χ²", "ν", "χ²/ν", "criterion",
                           "chosen")

#: The columns of :func:`prediction_rows`.
PREDICTION_COLUMNS = ("parameter", "predicted σ (plan, grade noise)",
                      "predicted σ (fitted noise)", "achieved σ", "unit", "achieved / predicted")

#: The note of the analysis that states its Type B terms (``analysis._add_type_b``).
_TYPE_B_NOTE = re.compile(r"Type B \(GUM\): table position accuracy ([0-9.eE+-]+)″ and "
                          r"axis perpendicularity ([0-9.eE+-]+)″")


def type_b_terms(result: Any) -> dict[str, float]:
    """Return the Type B standard uncertainty [rad] P1 added to each parameter (uncertainty budget).

    The table's position accuracy a (accelerometer misalignments) and its axes'
    perpendicularity (gyro misalignments), uniform: u = a/√3 (docs/p1.md); read from the
    result's notes, so a result read back from its file gives the same as the analysis. No
    note (Type B off): none.
    """
    from imucalib import units

    found = next((m for n in result.notes if (m := _TYPE_B_NOTE.search(str(n)))), None)
    if found is None:
        return {}
    u_pos, u_perp = (float(found.group(i)) * units.ARCSEC / math.sqrt(3.0) for i in (1, 2))
    out = {}
    for row in result.parameter_rows():
        parts = row.name.split("_")
        if len(parts) == 3 and parts[1] == "M" and parts[2][0] != parts[2][1]:
            out[row.name] = u_pos if parts[0] == "accel" else u_perp
    return out


def model_selection_rows(selection: Sequence[Mapping[str, Any]]) -> list[tuple[str, ...]]:
    """Return one row per candidate of each group's choice (the result's ``model_selection``).

    The criterion column is AICc (TS.1), or BIC (TS.2) when that chose; with the
    likelihood-ratio test (TS.3) AICc is shown beside it, as the notes do. A candidate the
    windows cannot resolve says so.
    """
    rows: list[tuple[str, ...]] = []
    for group in selection:
        label = "BIC" if group.get("criterion") == "bic" else "AICc"
        for c in group.get("candidates", ()):
            terms = "+".join(c["terms"]) or "none"
            if c.get("note"):
                rows.append((group["group"], terms, "—", "—", "—", "not identifiable", ""))
                continue
            chosen = sorted(c["terms"]) == sorted(group.get("chosen", ()))
            score = c.get("score")
            rows.append((group["group"], terms, f"{c['chi2']:.4g}", str(c["dof"]),
                         f"{c['reduced_chi2']:.3g}" if c.get("reduced_chi2") is not None
                         else "—", "∞" if score is None else f"{label} {score:.4g}",
                         "yes" if chosen else ""))
    return rows


def prediction_rows(check: Any) -> list[tuple[str, ...]]:
    """Return one row per parameter of a :class:`~imucalib.procedures.p1.achieved.PredictionCheck`.

    The σ in the parameter's display unit (:func:`~imucalib.report.console.display_parameter`),
    then σ_achieved / σ_predicted (grade noise), Eq. (PA.1) of docs/test-design.md.
    """
    from imucalib.report.console import display_parameter

    def shown(name: str, sigma: float | None, unit: str) -> tuple[str, str]:
        if sigma is None:
            return "—", display_parameter(name, 0.0, 1.0, unit)[2]
        _, text, du = display_parameter(name, 0.0, sigma, unit)
        return text, du

    rows: list[tuple[str, ...]] = []
    for r in check.rows:
        nominal, du = shown(r.name, r.predicted_std, r.unit)
        rows.append((r.name, nominal, shown(r.name, r.predicted_fitted_std, r.unit)[0],
                     shown(r.name, r.achieved_std, r.unit)[0], du, f"{r.ratio:.2f}"))
    return rows


def content(analysis: Any, meta: Mapping[str, Any]) -> ReportContent | None:
    """Return P1's sections 1–5 (None for a result without its observations)."""
    from imucalib.procedures.p1.analysis import P1Analysis

    if not isinstance(analysis, P1Analysis):  # read back from its file: no observations
        return None
    from imucalib.procedures.p1.residual_figure import save_residual_figure

    result, obs = analysis.result, analysis.observations
    prov = result.provenance
    details = dict(prov.details)
    plan = getattr(obs, "plan", None)
    unit = details.get("unit", {"serial": result.sensor_id})
    site = {"latitude": f"{obs.latitude_deg:g}°", "table heading": f"{obs.heading_deg:g}°",
            "local gravity used": f"{obs.gravity_mps2:.6f} m/s²"}
    n_windows = details.get("n_windows", len(obs.windows))
    process = Section(SECTION_TITLES[3], (
        "Procedure P1 (docs/p1.md): two-dimensional calibration on a dual-axis table — static "
        "positions, a static noise record, rate points about each axis, held-out positions and "
        "rates, repetitions — fitted by weighted least squares with a Kalman cross-check.",
        f"Model: {result.model}; repetitions: {', '.join(map(str, obs.repetitions))}; "
        f"{n_windows} windows reduced; sample rate {obs.sample_rate_hz:g} Hz"
        + (f", low-pass cut-off {obs.cutoff_hz:g} Hz" if obs.cutoff_hz else "")
        + f"; outliers removed: {details.get('outliers_removed', 0)}.",
        *(f"Note: {n}" for n in result.notes)))
    params = parameter_table(result, f"calibrated parameters of {result.sensor_id} "
                                     f"({result.model} model)")
    checks = ReportTable("verification", ("check", "verdict", "summary"),
                         tuple((c.name, yes_no(c.passed), c.summary) for c in analysis.checks))
    spec = next((c for c in analysis.checks if c.name == "specification"), None)
    accept = details.get("acceptance", {})
    rule_par = [f"Decision rule: {analysis.decision.rule}."]
    if accept:
        rule_par.append(f"Acceptance (plan's [acceptance]): rule '{accept.get('rule')}', "
                        f"guard band k = {float(accept.get('guard_band_k', 2.0)):g}.")
    tables = [params, checks]
    if spec is not None and spec.rows:
        tables.append(ReportTable(
            "conformity with the specification (acceptance limits)",
            ("quantity", "|value|", "limit", "unit", "verdict"),
            tuple((r.name, f"{abs(r.value):.3g}", f"{r.limit:.3g}", r.unit,
                   "pass" if r.passed else "FAIL") for r in spec.rows)))
    if analysis.model_selection:
        tables.append(ReportTable(
            "model terms chosen by the data (docs/p1.md, \"Model terms\"): every candidate "
            "of each triad fit", MODEL_SELECTION_COLUMNS,
            tuple(model_selection_rows(analysis.model_selection))))
    prediction = getattr(analysis, "prediction", None)
    if prediction is not None:
        tables.append(ReportTable(
            "predicted σ of the plan beside the achieved σ (docs/test-design.md, \"Predicted "
            "against achieved\"): " + prediction.summary(), PREDICTION_COLUMNS,
            tuple(prediction_rows(prediction))))
    fit_text = [q.summary() for q in result.fit_quality]
    fig = figure_of(lambda p: save_residual_figure(analysis, p),
                    "Residual mean of each window and axis with ±2 standard-error bars "
                    "(top: accelerometer [µg]; bottom: gyro [°/h]).")
    from imucalib.report.checks_figure import save_checks_figure

    verified = [c for c in analysis.checks if c.name.startswith("held-out")
                or c.name == "repeatability"]
    checks_fig = figure_of(lambda p: save_checks_figure(verified, p),
                           "Held-out verification and repeatability: each quantity's |value| "
                           "over its limit (the dashed line); green passes, red fails.")
    noise_fig = None
    if obs.noise:
        from imucalib.report.noise_model_figure import noise_model_rows, save_noise_model_figure

        tables.append(ReportTable(
            "noise model of the long static records (the window means' standard errors)",
            ("axis", "white noise N", "bias instability B", "random walk K"),
            noise_model_rows(obs.noise)))
        noise_fig = figure_of(
            lambda p: save_noise_model_figure(
                obs.noise, [w.duration_s for w in obs.windows], p,
                tau_min_s=1.0 / obs.sample_rate_hz,
                tau_max_s=max(10.0 * max(w.duration_s for w in obs.windows), 100.0)),
            "Allan deviation of the noise model fitted to the long static records; each "
            "window mean's standard error is its value at τ = the window's length (dotted).")
    results = Section(SECTION_TITLES[4], (u_paragraph(), *fit_text, *rule_par),
                      tuple(tables), tuple(f for f in (fig, checks_fig, noise_fig)
                                           if f is not None))
    recs = recommendations(analysis.decision.passed, analysis.decision.failed,
                           analysis.decision.not_assessed, bool(result.misfit))
    sections = [object_section(unit, result.sensor_id),
                equipment_section(meta, plan, prov.software_version),
                environment_section(meta, site), process, results]
    return ReportContent(tuple(sections), analysis.decision.summary(), analysis.decision.passed,
                         tuple(recs), prov, plan, type_b=type_b_terms(analysis))

