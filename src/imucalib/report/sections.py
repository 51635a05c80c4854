"""The sections every calibration report shares, and the helpers of the per-procedure contents.

:mod:`imucalib.report.document` assembles a report from a procedure's sections 1–5 (its content
module, ``report/content_<procedure>.py``) and the pieces here: the object, equipment and
traceability, environment sections, the recommendations, the conclusion with the review status,
and the appendix (docs/reporting.md, "The calibration report").

Contents
--------
:func:`object_section`, :func:`equipment_section`, :func:`environment_section`,
:func:`recommendations`, :func:`conclusion_section`, :func:`appendix`, :func:`u_paragraph`,
:func:`traceability`, :func:`reviews_of`, :func:`expanded_cells`, :func:`parameter_table`,
:func:`figure_of`, :func:`yes_no`, :func:`recording_facts`, :func:`json_field`,
:func:`plan_name`, :func:`temperature_model_table`, :data:`TRACEABILITY_NOT_STATED`
"""

from __future__ import annotations

import json
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np

from imucalib.errors import InvalidInputError
from imucalib.models.result import Provenance
from imucalib.report.document import (
    COVERAGE_FACTOR,
    SECTION_TITLES,
    ReportFigure,
    ReportTable,
    ReviewStatus,
    Section,
)
from imucalib.report.numbers import round_pair

__all__ = ["TRACEABILITY_NOT_STATED", "appendix", "conclusion_section", "environment_section",
           "equipment_section", "expanded_cells", "figure_of", "json_field", "object_section",
           "parameter_table", "plan_name", "recommendations", "recording_facts", "reviews_of",
           "temperature_model_table", "traceability", "u_paragraph", "yes_no"]


def reviews_of(review: Any) -> tuple[ReviewStatus, ...]:
    """Reviews from ReviewStatus, records ``ReviewView``-like objects or mappings."""
    if review is None:
        return ()
    items = [review] if not isinstance(review, Sequence) else list(review)
    out = []
    for r in items:
        get = r.get if isinstance(r, Mapping) else (lambda k, r=r: getattr(r, k, None))
        when = get("reviewed_utc")
        when_text = (when.strftime("%Y-%m-%d %H:%M UTC") if isinstance(when, datetime)
                     else str(when or ""))
        if get("reviewer") is None or get("approved") is None:
            raise InvalidInputError(f"a review needs `reviewer` and `approved`; got {r!r}")
        out.append(ReviewStatus(str(get("reviewer")), when_text, bool(get("approved")),
                                str(get("comment") or "")))
    return tuple(out)


def expanded_cells(value: float, sigma: float) -> tuple[str, str]:
    """(value, U) cells: U = k·u (R.1) to two significant digits, the value to its place."""
    cells = round_pair(float(value), COVERAGE_FACTOR * float(sigma), sign=True)
    return cells.value_text, cells.uncertainty_text


def figure_of(save: Any, caption: str) -> ReportFigure | None:
    """Run ``save(path)`` into a temporary folder and keep the PNG's bytes."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "figure.png"
        save(path)
        return ReportFigure(path.read_bytes(), caption) if path.is_file() else None


def yes_no(passed: bool | None) -> str:
    """Return the verdict cell of a check: pass, FAIL or not assessed."""
    return "not assessed" if passed is None else "pass" if passed else "FAIL"


def recording_facts(recording: Any) -> dict[str, Any]:
    """Metadata and the IMU temperature range of a Recording (open, or a path), else {}."""
    if recording is None:
        return {}
    from imucalib.io.opening import open_recording
    from imucalib.io.reader import Recording

    if isinstance(recording, Recording):
        return _read_facts(recording)
    with open_recording(Path(recording)) as rec:
        return _read_facts(rec)


def _read_facts(rec: Any) -> dict[str, Any]:
    meta = dict(rec.metadata)
    temps: list[float] = []
    for info in rec.streams:
        if "temperature_degc" in getattr(info, "columns", ()):
            data = rec.read_stream(info.device, info.unit, ["temperature_degc"])
            t = np.asarray(data.columns["temperature_degc"], dtype=float)
            t = t[np.isfinite(t)]
            if t.size:
                temps += [float(t.min()), float(t.mean()), float(t.max())]
                meta.setdefault("_temperature_unit", info.unit)
    if temps:
        meta["_temperature_degc"] = (min(temps[0::3]), float(np.mean(temps[1::3])),
                                     max(temps[2::3]))
    return meta


def json_field(meta: Mapping[str, Any], key: str) -> dict[str, Any]:
    """Return a JSON (or Python-literal) dict stored in a recording's metadata `key`; {} if none."""
    text = meta.get(key)
    if not text:
        return {}
    try:
        value = json.loads(str(text))
    except ValueError:
        try:  # some writers store a Python repr
            import ast

            value = ast.literal_eval(str(text))
        except (ValueError, SyntaxError):
            return {}
    return value if isinstance(value, dict) else {}


def plan_name(meta: Mapping[str, Any], plan: Any) -> str:
    """Return the plan's name: from the Plan, else the recording's stored plan TOML, else a dash."""
    name = None if plan is None else getattr(plan, "name", None)
    if name:
        return str(name)
    from imucalib.io.context import RecordingContext

    return RecordingContext.of(meta).plan_name or "—"


# --- the sections ----------------------------------------------------------------------------

def object_section(unit: Mapping[str, Any], serial: str) -> Section:
    """Section 1: the unit calibrated (serial, model, maker, grade)."""
    rows = (("serial number", str(unit.get("serial") or serial)),
            ("model", str(unit.get("model") or "—")),
            ("maker", str(unit.get("maker") or "—")),
            ("grade", str(unit.get("grade") or "—")))
    return Section(SECTION_TITLES[0],
                   (f"The item calibrated is the inertial measurement unit {serial}: its "
                    "accelerometer and gyro triads.",),
                   (ReportTable("identification", ("item", "value"), rows),))


#: The traceability statement of a report that does not know the station (no recording given).
TRACEABILITY_NOT_STATED = (
    "Traceability: not stated. The recording was not given to this report, so the station "
    "that made the result is not known here (a result of the digital twin is not traceable to "
    "the SI); report the recording (imucalib report RECORDING, or --run N) for the statement.")


def traceability(station_kind: str, *, reference: bool = True) -> str:
    """Return the traceability statement of a station kind (an honest line for the twin)."""
    if station_kind == "digital-twin":
        return ("Traceability: this calibration was made on the digital twin (a simulated "
                "station). Its references are simulated and are NOT traceable to the SI; the "
                "report documents the method, not a calibration of a physical unit.")
    if not reference:
        return ("Traceability: a noise characterisation uses no reference quantity; its values "
                "come from the unit's own output and the recording's time base, whose accuracy "
                "bounds theirs.")
    return ("Traceability: the references are the rotation table's angle and rate (traceable to "
            "the SI through the table's own calibration certificate, to be kept with the "
            "equipment records) and local gravity (normal gravity at the site's latitude and "
            "height, or the value given in the plan); the Earth rate is a defined constant "
            "(15.041 °/h). imucalib does not verify the table's certificate.")


def equipment_section(meta: Mapping[str, Any], plan: Any, software: str, *,
                      reference: bool = True, statement: str | None = None) -> Section:
    """Section 2: station, table, the plan's equipment, software, traceability.

    The traceability statement is that of the station kind (:func:`traceability`; `reference`
    false: a measurement without a reference quantity), or `statement` when the procedure's
    references are its own (a field calibration by hand: gravity and whole turns); a recording
    of the digital twin is never traceable, whatever the procedure; without the recording
    (`meta` empty) and without a statement of its own, traceability is not stated.
    """
    station = json_field(meta, "station_json")
    kind = str(station.get("kind") or meta.get("source") or "—")
    rows: list[tuple[str, str]] = [("station", kind)]
    twin = station.get("twin") if isinstance(station.get("twin"), dict) else None
    table = twin.get("table") if twin else station.get("table")
    if isinstance(table, dict):
        rows.append(("rotation table", ", ".join(f"{k} {table[k]}" for k in ("kind", "grade")
                                                 if k in table) or "—"))
    eq = getattr(plan, "equipment", None)
    if eq is not None:
        for key, value in eq.model_dump().items():
            rows.append((key.replace("_", " "), f"{value:g}" if isinstance(value, float)
                         else str(value)))
    rows.append(("software", f"imucalib {software}"))
    if kind == "digital-twin":
        text = traceability(kind)
    elif statement is not None:
        text = statement
    elif not meta:
        text = TRACEABILITY_NOT_STATED
    else:
        text = traceability(kind, reference=reference)
    return Section(SECTION_TITLES[1], (text,),
                   (ReportTable("equipment", ("item", "value"), tuple(rows)),))


def environment_section(meta: Mapping[str, Any], site: Mapping[str, str]) -> Section:
    """Section 3: the site, the environment metadata and the IMU temperature range."""
    rows = list(site.items())
    env = json_field(meta, "environment_json")
    for key, value in env.items():
        rows.append((str(key).replace("_", " "), str(value)))
    station = json_field(meta, "station_json")
    twin_site = (station.get("twin") or {}).get("site") if isinstance(station.get("twin"),
                                                                      dict) else None
    if isinstance(twin_site, dict) and twin_site.get("ambient_temperature_degc") is not None:
        rows.append(("ambient temperature (station)",
                     f"{float(twin_site['ambient_temperature_degc']):.1f} °C"))
    temp = meta.get("_temperature_degc")
    paragraphs = []
    if temp is not None:
        lo, mean, hi = temp
        rows.append(("IMU temperature during the run (min / mean / max)",
                     f"{lo:.1f} / {mean:.1f} / {hi:.1f} °C"))
    if "run_started_utc" in meta:
        rows.append(("run started", str(meta["run_started_utc"])))
    if not meta:
        paragraphs.append("The recording was not given to the report: the conditions during "
                          "the run (temperature) are not stated here.")
    elif temp is None and not env:
        paragraphs.append("The recording holds no temperature column and no environment "
                          "metadata: the conditions during the run are not stated.")
    return Section(SECTION_TITLES[2], tuple(paragraphs),
                   (ReportTable("conditions", ("quantity", "value"), tuple(rows)),)
                   if rows else ())


def recommendations(passed: bool | None, failed: Iterable[str], not_assessed: Iterable[str],
                    misfit: bool) -> list[str]:
    """Return the conclusion's recommendations from the decision and the checks not assessed."""
    out = []
    failed, not_assessed = list(failed), list(not_assessed)
    if passed:
        out.append("The calibration may be applied (imucalib apply with the result file).")
    elif passed is False:
        out.append("Do not apply this calibration: investigate the failed check(s) ("
                   + ", ".join(failed or ["see section 5"]) + ") and repeat the run.")
    if "repeatability" in not_assessed:
        out.append("Repeatability was not assessed: run the plan with three repetitions "
                   "(docs/p1.md, rule 6).")
    for name in (n for n in not_assessed if n != "repeatability"):
        out.append(f"The check '{name}' was not assessed: provide what it needs.")
    if misfit:
        out.append("The model does not describe the data within its noise (χ²/ν high): the "
                   "uncertainties were scaled (Birge); consider a fuller model or check the "
                   "station.")
    out.append("Recalibrate at the interval set by the laboratory's quality system, and after "
               "any shock, repair or change of mounting.")
    return out


def conclusion_section(decision_text: str, passed: bool | None, recs: list[str],
                       reviews: tuple[ReviewStatus, ...], result_id: int | None,
                       closing: Sequence[str] | None = None) -> Section:
    """Section 6: the decision, recommendations, the reviews and the authorisation.

    `closing`: the certificate's operator, authorisation (or DRAFT) and statements
    (:func:`imucalib.report.certificate.authorisation_lines`), which replace the one-line
    authorisation status of a report without them.
    """
    verdict = {None: "no conformity decision", True: "PASS", False: "FAIL"}[passed]
    text = decision_text if decision_text.startswith(verdict) else f"{verdict}. {decision_text}"
    paragraphs = [f"Decision: {text}".strip()]
    paragraphs += [f"Recommendation: {r}" for r in recs]
    if reviews:
        paragraphs += [f"Review: {r.text()}." for r in reviews]
        last = reviews[-1]
        if closing is None:
            paragraphs.append("Authorisation: " + ("authorised" if last.approved else
                                                   "NOT authorised") + f" ({last.reviewer}).")
    else:
        where = ("" if result_id is None else
                 f" (records result {result_id} has no review)")
        paragraphs.append(f"Review status: not reviewed{where}."
                          + (" Authorisation: not authorised — this report is not a "
                             "certificate until it has been reviewed." if closing is None
                             else ""))
    paragraphs += list(closing or ())
    return Section(SECTION_TITLES[5], tuple(paragraphs))


def appendix(meta: Mapping[str, Any], plan: Any, prov: Provenance | None,
             extra: Sequence[tuple[str, str]]) -> Section:
    """Build the appendix: plan name and hash, recording and its SHA-256, software, extras."""
    p = prov or Provenance()
    plan_hash = p.plan_hash or str(meta.get("plan_hash", "")) or "—"
    rows = [("plan name", plan_name(meta, plan)), ("plan hash (SHA-256)", plan_hash),
            ("recording", p.recording or "—"),
            ("recording SHA-256", p.recording_sha256 or "not hashed"),
            ("software version", p.software_version or "—"),
            ("result created (UTC)", p.created_utc or "—"), *extra]
    return Section(SECTION_TITLES[6],
                   ("The raw data are identified by their SHA-256: imucalib recomputes it "
                    "from the recording file.",),
                   (ReportTable("plan and raw data", ("item", "value"), tuple(rows)),))


def u_paragraph() -> str:
    """Return the paragraph that states U = k·u (R.1) and the rounding rule."""
    return (f"Each value is given with its expanded uncertainty U = k·u, k = {COVERAGE_FACTOR:g} "
            "(about 95 % coverage for a normal distribution; JCGM 100:2008 §6), u the standard "
            "uncertainty (Type A from the fit, with the equipment's Type B contribution; scaled "
            "by √(χ²/ν) under a model misfit). U is rounded to two significant digits and the "
            "value to the same decimal place (GUM 7.2.6).")


def parameter_table(cal: Any, title: str) -> ReportTable:
    """Every parameter of a CalibrationResult: value, U = k·u (R.1, Birge-scaled u), unit."""
    from imucalib.report.console import display_parameter

    std = cal.std(scaled=True)
    rows = tuple((name, *display_parameter(name, cal.value(name), COVERAGE_FACTOR * std[name],
                                           cal.units[name]))
                 for name in cal.param_names)
    return ReportTable(title, ("parameter", "value", f"U (k = {COVERAGE_FACTOR:g})", "unit"),
                       rows)


def temperature_model_table(cal: Any) -> ReportTable:
    """One row per temperature model (T1) of a CalibrationResult (docs/reporting.md).

    Order and how it was chosen, the linear coefficient c₁ with U = k·u per °C in the
    parameter's display unit, χ²/ν of the model's fit, and the held-out check (max|z|, p, ν).
    """
    from imucalib.report.console import display_unit

    rows = []
    for tm in cal.temperature_models:
        unit, scale = display_unit(tm.name, cal.units.get(tm.name, ""))
        order = len(tm.coefficients) - 1
        if order >= 1:
            cells = round_pair(tm.coefficients[1] / scale,
                               COVERAGE_FACTOR * float(np.sqrt(tm.covariance[1, 1])) / scale,
                               sign=True)
            slope = f"{cells.value_text} ± {cells.uncertainty_text} {unit}/°C"
        else:
            slope = "— (constant)"
        check = tm.held_out
        held = ("not checked (no held-out point)" if check is None else
                f"{'consistent' if check.consistent else 'NOT consistent'}: max|z| "
                f"{check.max_abs_z:.2g}, p = {check.p_value:.2g} (ν = {check.dof})")
        reduced = tm.chi2 / tm.dof if tm.dof > 0 else float("nan")
        rows.append((tm.name, f"{order} ({tm.order_criterion.upper()})", slope,
                     f"{reduced:.3g}", held))
    return ReportTable("temperature models (T1)",
                       ("parameter", "order (criterion)", f"c₁ ± U (k = {COVERAGE_FACTOR:g})",
                        "χ²/ν", "held-out check"), tuple(rows))
