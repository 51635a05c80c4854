"""The calibration report (certificate) as data: :func:`build_report` → :class:`ReportDocument`.

One document, rendered by :mod:`imucalib.report.pdf` (PDF) and :mod:`imucalib.report.html`
(one self-contained HTML page), holds the items ISO/IEC 17025:2017 §7.8.2 and §7.8.4 ask of a
calibration certificate, in six sections and an appendix (docs/reporting.md, "The calibration
report"):

1. Object: the unit calibrated (serial, model, maker, grade).
2. Equipment: the station, its accuracy, and the traceability statement.
3. Environment: site (latitude, heading, gravity) and the conditions of the recording (its
   temperature column, the environment metadata) when the recording is given.
4. Process: the procedure, the model, the data reduced.
5. Results: each parameter's value with its expanded uncertainty

       U = k·u,  k = 2                                                              (R.1)

   (u the standard uncertainty, Birge-scaled under a misfit; about 95 % coverage for a normal
   distribution, JCGM 100:2008 §6.2-6.3), U rounded to two significant digits and the value to
   the same decimal place (:func:`~imucalib.report.numbers.round_pair`, GUM 7.2.6), the
   checks, and the decision with its rule (ILAC-G8:09/2019).
6. Conclusion and recommendations, with the authorisation and review status.

Appendix: the plan's name and hash, the recording's file name and SHA-256, the software version.

The unique id (:func:`report_id`) is ``IMUCAL-<PROCEDURE>-<serial>-<hash>``, ``<hash>`` the first
12 hex digits of the SHA-256 of the result's canonical JSON (so the same result always gets the
same id, two results never one), followed by ``-R<id>`` when the result is in the records
database.

Contents
--------
:func:`build_report`, :func:`report_id`, :class:`ReportDocument`, :class:`Section`,
:class:`ReportTable`, :class:`ReportFigure`, :class:`ReviewStatus`, :data:`SECTION_TITLES`,
:data:`COVERAGE_FACTOR`
"""

from __future__ import annotations

import hashlib
import json
import re
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from imucalib.errors import InvalidInputError
from imucalib.report.numbers import round_pair

__all__ = ["COVERAGE_FACTOR", "SECTION_TITLES", "ReportDocument", "ReportFigure", "ReportTable",
           "ReviewStatus", "Section", "build_report", "report_id"]

#: k of the expanded uncertainty U = k·u (R.1).
COVERAGE_FACTOR = 2.0

#: The titles of the six sections and the appendix, in order.
SECTION_TITLES = ("1. Object: the unit calibrated", "2. Equipment and traceability",
                  "3. Environmental conditions", "4. Calibration process", "5. Results",
                  "6. Conclusion and recommendations", "Appendix: plan and raw data")


@dataclass(frozen=True)
class ReportTable:
    """A table: a title, a header row and rows of cell texts."""

    title: str
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]


@dataclass(frozen=True)
class ReportFigure:
    """A figure as PNG bytes, with its caption."""

    png: bytes
    caption: str


@dataclass(frozen=True)
class Section:
    """A titled section: paragraphs, then tables, then figures."""

    title: str
    paragraphs: tuple[str, ...] = ()
    tables: tuple[ReportTable, ...] = ()
    figures: tuple[ReportFigure, ...] = ()


@dataclass(frozen=True)
class ReviewStatus:
    """A review of the result in the records database (who, when, approved, why)."""

    reviewer: str
    reviewed_utc: str
    approved: bool
    comment: str = ""

    def text(self) -> str:
        """One line: ``"approved by X on T: comment"``."""
        verdict = "approved" if self.approved else "NOT approved"
        tail = f": {self.comment}" if self.comment else ""
        return f"{verdict} by {self.reviewer} on {self.reviewed_utc}{tail}"


@dataclass(frozen=True)
class ReportDocument:
    """The report: its title, unique id, issue time, the sections (appendix last)."""

    title: str
    report_id: str
    issued_utc: str
    sections: tuple[Section, ...]
    passed: bool | None = None

    def section(self, title_start: str) -> Section:
        """Return the section whose title starts with `title_start` (KeyError if none)."""
        for s in self.sections:
            if s.title.startswith(title_start):
                return s
        raise KeyError(title_start)


# --- small helpers ---------------------------------------------------------------------------

def _canonical_json(data: Any) -> str:
    return json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=True, default=str)


def report_id(result: Any, *, result_id: int | None = None) -> str:
    """Return the report's unique id (module docstring): ``IMUCAL-P1-<serial>-<hash>[-R<id>]``."""
    body = result.to_dict() if callable(getattr(result, "to_dict", None)) else repr(result)
    digest = hashlib.sha256(_canonical_json(body).encode("utf-8")).hexdigest()[:12]
    serial = re.sub(r"[^A-Za-z0-9]+", "-", str(getattr(result, "unit", "") or "unit")).strip("-")
    text = f"IMUCAL-{str(result.procedure).upper()}-{serial or 'unit'}-{digest}"
    return text if result_id is None else f"{text}-R{int(result_id)}"


def _reviews(review: Any) -> tuple[ReviewStatus, ...]:
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


def _expanded_cells(value: float, sigma: float) -> tuple[str, str]:
    """(value, U) cells: U = k·u (R.1) to two significant digits, the value to its place."""
    cells = round_pair(float(value), COVERAGE_FACTOR * float(sigma), sign=True)
    return cells.value_text, cells.uncertainty_text


def _figure(save: Any, caption: str) -> ReportFigure | None:
    """Run ``save(path)`` into a temporary folder and keep the PNG's bytes."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "figure.png"
        save(path)
        return ReportFigure(path.read_bytes(), caption) if path.is_file() else None


def _yes_no(passed: bool | None) -> str:
    return "not assessed" if passed is None else "pass" if passed else "FAIL"


def _recording_facts(recording: Any) -> dict[str, Any]:
    """Metadata and the IMU temperature range of a Recording (open, or a path), else {}."""
    if recording is None:
        return {}
    from imucalib.io.reader import Recording, open_recording

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


def _json_field(meta: Mapping[str, Any], key: str) -> dict[str, Any]:
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


def _plan_name(meta: Mapping[str, Any], plan: Any) -> str:
    name = None if plan is None else getattr(plan, "name", None)
    if name:
        return str(name)
    m = re.search(r'^name\s*=\s*"([^"]*)"', str(meta.get("plan_toml", "")), re.MULTILINE)
    return m.group(1) if m else "—"


# --- the sections ----------------------------------------------------------------------------

def _object_section(unit: Mapping[str, Any], serial: str) -> Section:
    rows = (("serial number", str(unit.get("serial") or serial)),
            ("model", str(unit.get("model") or "—")),
            ("maker", str(unit.get("maker") or "—")),
            ("grade", str(unit.get("grade") or "—")))
    return Section(SECTION_TITLES[0],
                   (f"The item calibrated is the inertial measurement unit {serial}: its "
                    "accelerometer and gyro triads.",),
                   (ReportTable("identification", ("item", "value"), rows),))


def _traceability(station_kind: str, *, reference: bool = True, procedure: str = "") -> str:
    if procedure == "field":
        return ("Traceability: a field calibration by hand uses no rotation table. Its references "
                "are local gravity (normal gravity at the stated latitude and height with a Type "
                "B for the local anomaly, or the value given), the known angle of whole turns "
                "flat on a surface, and the Earth rate as a defined constant (15.041 °/h); the "
                "orientations of the poses are not references (docs/field.md).")
    if not reference:
        return ("Traceability: a noise characterisation uses no reference quantity; its values "
                "come from the unit's own output and the recording's time base, whose accuracy "
                "bounds theirs.")
    if station_kind == "digital-twin":
        return ("Traceability: this calibration was made on the digital twin (a simulated "
                "station). Its references are simulated and are NOT traceable to the SI; the "
                "report documents the method, not a calibration of a physical unit.")
    return ("Traceability: the references are the rotation table's angle and rate (traceable to "
            "the SI through the table's own calibration certificate, to be kept with the "
            "equipment records) and local gravity (normal gravity at the site's latitude and "
            "height, or the value given in the plan); the Earth rate is a defined constant "
            "(15.041 °/h). imucalib does not verify the table's certificate.")


def _equipment_section(meta: Mapping[str, Any], plan: Any, software: str, *,
                       reference: bool = True, procedure: str = "") -> Section:
    station = _json_field(meta, "station_json")
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
    return Section(SECTION_TITLES[1], (_traceability(kind, reference=reference,
                                                     procedure=procedure),),
                   (ReportTable("equipment", ("item", "value"), tuple(rows)),))


def _environment_section(meta: Mapping[str, Any], site: Mapping[str, str]) -> Section:
    rows = list(site.items())
    env = _json_field(meta, "environment_json")
    for key, value in env.items():
        rows.append((str(key).replace("_", " "), str(value)))
    station = _json_field(meta, "station_json")
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


def _recommendations(passed: bool | None, failed: Iterable[str], not_assessed: Iterable[str],
                     misfit: bool) -> list[str]:
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


def _conclusion_section(decision_text: str, passed: bool | None, recs: list[str],
                        reviews: tuple[ReviewStatus, ...], result_id: int | None) -> Section:
    verdict = {None: "no conformity decision", True: "PASS", False: "FAIL"}[passed]
    text = decision_text if decision_text.startswith(verdict) else f"{verdict}. {decision_text}"
    paragraphs = [f"Decision: {text}".strip()]
    paragraphs += [f"Recommendation: {r}" for r in recs]
    if reviews:
        paragraphs += [f"Review: {r.text()}." for r in reviews]
        last = reviews[-1]
        paragraphs.append("Authorisation: " + ("authorised" if last.approved else
                                               "NOT authorised") + f" ({last.reviewer}).")
    else:
        where = ("" if result_id is None else
                 f" (records result {result_id} has no review)")
        paragraphs.append(f"Review status: not reviewed{where}. Authorisation: not authorised "
                          "— this report is not a certificate until it has been reviewed.")
    return Section(SECTION_TITLES[5], tuple(paragraphs))


def _appendix(meta: Mapping[str, Any], plan: Any, prov: Any, extra: Sequence[tuple[str, str]]
              ) -> Section:
    plan_hash = getattr(prov, "plan_hash", "") or str(meta.get("plan_hash", "")) or "—"
    rows = [("plan name", _plan_name(meta, plan)), ("plan hash (SHA-256)", plan_hash),
            ("recording", getattr(prov, "recording", "") or "—"),
            ("recording SHA-256", getattr(prov, "recording_sha256", "") or "not hashed"),
            ("software version", getattr(prov, "software_version", "") or "—"),
            ("result created (UTC)", getattr(prov, "created_utc", "") or "—"), *extra]
    return Section(SECTION_TITLES[6],
                   ("The raw data are identified by their SHA-256: imucalib recomputes it "
                    "from the recording file.",),
                   (ReportTable("plan and raw data", ("item", "value"), tuple(rows)),))


def _u_paragraph() -> str:
    return (f"Each value is given with its expanded uncertainty U = k·u, k = {COVERAGE_FACTOR:g} "
            "(about 95 % coverage for a normal distribution; JCGM 100:2008 §6), u the standard "
            "uncertainty (Type A from the fit, with the equipment's Type B contribution; scaled "
            "by √(χ²/ν) under a model misfit). U is rounded to two significant digits and the "
            "value to the same decimal place (GUM 7.2.6).")


# --- per result kind -------------------------------------------------------------------------

def _p1_sections(analysis: Any, meta: Mapping[str, Any]) -> tuple[list[Section], Any, bool]:
    from imucalib.report.console import display_parameter
    from imucalib.report.residual_figure import save_residual_figure

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
    std = result.std(scaled=True)
    rows = []
    for name in result.param_names:
        value, big_u, shown_unit = display_parameter(name, result.value(name),
                                                     COVERAGE_FACTOR * std[name],
                                                     result.units[name])
        rows.append((name, value, big_u, shown_unit))
    params = ReportTable(f"calibrated parameters of {result.sensor_id} ({result.model} model)",
                         ("parameter", "value", f"U (k = {COVERAGE_FACTOR:g})", "unit"),
                         tuple(rows))
    checks = ReportTable("verification", ("check", "verdict", "summary"),
                         tuple((c.name, _yes_no(c.passed), c.summary) for c in analysis.checks))
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
    fit_text = [q.summary() for q in result.fit_quality]
    fig = _figure(lambda p: save_residual_figure(analysis, p),
                  "Residual mean of each window and axis with ±2 standard-error bars "
                  "(top: accelerometer [µg]; bottom: gyro [°/h]).")
    from imucalib.report.checks_figure import save_checks_figure

    verified = [c for c in analysis.checks if c.name.startswith("held-out")
                or c.name == "repeatability"]
    checks_fig = _figure(lambda p: save_checks_figure(verified, p),
                         "Held-out verification and repeatability: each quantity's |value| "
                         "over its limit (the dashed line); green passes, red fails.")
    results = Section(SECTION_TITLES[4], (_u_paragraph(), *fit_text, *rule_par),
                      tuple(tables), tuple(f for f in (fig, checks_fig) if f is not None))
    recs = _recommendations(analysis.decision.passed, analysis.decision.failed,
                            analysis.decision.not_assessed, bool(result.misfit))
    sections = [_object_section(unit, result.sensor_id),
                _equipment_section(meta, plan, prov.software_version),
                _environment_section(meta, site), process, results]
    return sections, (analysis.decision.summary(), analysis.decision.passed, recs, prov,
                      plan), True


def _generic_sections(result: Any, meta: Mapping[str, Any]
                      ) -> tuple[list[Section], Any, bool]:
    from imucalib.report.console import display_parameter

    rows_of = getattr(result, "parameter_rows", None)
    cal: Any = getattr(result, "result", None)
    prov = getattr(cal, "provenance", None) or getattr(result, "provenance", None)
    rows = []
    if callable(rows_of):
        for name, value, sigma, unit in rows_of():
            v, big_u = _expanded_cells(float(value), float(sigma))
            rows.append((str(name), v, big_u, str(unit)))
    elif callable(getattr(cal, "std", None)) and hasattr(cal, "param_names"):
        std = cal.std(scaled=True)  # a calibration result without a procedure's analysis
        for name in cal.param_names:
            rows.append((name, *display_parameter(name, cal.value(name),
                                                  COVERAGE_FACTOR * std[name],
                                                  cal.units[name])))
    else:
        raise InvalidInputError(f"a {result.procedure} result has no parameter rows: no report "
                                "can be built from it")
    table = ReportTable(f"{result.procedure} results of {result.unit}",
                        ("parameter", "value", f"U (k = {COVERAGE_FACTOR:g})", "unit"),
                        tuple(rows))
    passed = result.passed
    decision = {None: "No conformity decision was made.",
                True: "Every assessed check passed.", False: "A check failed."}[passed]
    reasons = list(getattr(result, "reasons", ()) or ())
    notes = [f"Note: {n}" for n in getattr(result, "notes", ()) or ()]
    details = dict(getattr(prov, "details", {}) or {})
    sections = [
        _object_section(details.get("unit", {"serial": result.unit}), str(result.unit)),
        _equipment_section(meta, None, getattr(prov, "software_version", "") or "—",
                           procedure=str(result.procedure)),
        _environment_section(meta, {}),
        Section(SECTION_TITLES[3], (f"Procedure {result.procedure} (docs/).", *notes)),
        Section(SECTION_TITLES[4], (_u_paragraph(), *reasons), (table,)),
    ]
    recs = _recommendations(passed, reasons, (), False)
    return sections, (decision, passed, recs, prov, None), False


def _allan_sections(result: Any, meta: Mapping[str, Any]) -> tuple[list[Section], Any, bool]:
    from imucalib.report.allan_figure import plot_allan_triad
    from imucalib.report.noise_table import format_noise_table

    tables, figures, convention = [], [], ""
    for i, seg in enumerate(result.segments):
        markdown = format_noise_table(seg.fits(), fmt="markdown")
        for block in markdown.split("\n\n"):
            lines = [ln for ln in block.splitlines()
                     if ln.startswith("|") and not set(ln) <= set("|-: ")]
            cells = [tuple(c.strip() for c in ln.strip("|").split("|")) for ln in lines]
            if cells:
                tables.append(ReportTable(f"record {i}: {seg.label}", cells[0],
                                          tuple(cells[1:])))
            elif block.strip():
                convention = block.strip()
        for sensor in ("gyro", "accel"):
            if any(c.sensor == sensor for c in seg.channels):
                fig = _figure(lambda p, seg=seg, sensor=sensor: plot_allan_triad(seg, sensor,
                                                                                 path=p),
                              f"Allan deviation of the {sensor} axes, record {i} ({seg.label}).")
                if fig is not None:
                    figures.append(fig)
    temps = [s.temperature_degc for s in result.segments if s.temperature_degc is not None]
    site = {"IMU temperature (record means)": ", ".join(f"{t:.1f} °C" for t in temps)} \
        if temps else {}
    sections = [
        _object_section({"serial": result.unit}, str(result.unit)),
        _equipment_section(meta, None, result.software_version, reference=False),
        _environment_section(meta, site),
        Section(SECTION_TITLES[3], ("Noise characterisation (docs/noise.md): overlapping Allan "
                                    "deviation of each static record and a fit of the noise "
                                    "terms; each value with its standard uncertainty.",)),
        Section(SECTION_TITLES[4], ("The noise tables give value ± standard uncertainty "
                                    "(k = 1), GUM 7.2.6 rounding.", *filter(None, [convention])),
                tuple(tables), tuple(figures)),
    ]
    recs = ["Use the noise terms in the navigation filter's process noise."]
    prov = type("Prov", (), {"recording": Path(result.recording).name,
                             "software_version": result.software_version,
                             "created_utc": result.created_utc})()
    return sections, ("A noise characterisation makes no conformity decision.", None, recs,
                      prov, None), False


def build_report(result: Any, *, recording: Any = None, review: Any = None,
                 result_id: int | None = None) -> ReportDocument:
    """Build the report of a procedure result (module docstring).

    Parameters
    ----------
    result : ProcedureResult
        A P1 analysis (:class:`~imucalib.procedures.p1.analysis.P1Analysis`), a noise
        characterisation (Allan), or any result with ``parameter_rows()`` (the classical tests,
        P3, field).
    recording : Recording or path, optional
        The recording analysed: its metadata and temperature column fill the environment
        section. Without it the conditions during the run are said to be unstated.
    review : ReviewStatus, records ``ReviewView``, mapping, or a sequence of them, optional
        The result's reviews from the records database; without: "not reviewed".
    result_id : int, optional
        The result's id in the records database (appended to the report id).

    Returns
    -------
    ReportDocument

    Raises
    ------
    InvalidInputError
        A result the report cannot describe (no parameters), or a malformed review.
    """
    meta = _recording_facts(recording)
    if result.procedure == "p1" and hasattr(result, "observations"):
        sections, tail, _ = _p1_sections(result, meta)
    elif result.procedure == "allan" and hasattr(result, "segments"):
        sections, tail, _ = _allan_sections(result, meta)
    else:
        sections, tail, _ = _generic_sections(result, meta)
    decision_text, passed, recs, prov, plan = tail
    reviews = _reviews(review)
    sections.append(_conclusion_section(decision_text, passed, recs, reviews, result_id))
    sections.append(_appendix(meta, plan, prov, ()))
    rid = report_id(result, result_id=result_id)
    title = f"Calibration report {rid}: {str(result.procedure).upper()} of {result.unit}"
    issued = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    return ReportDocument(title=title, report_id=rid, issued_utc=issued,
                          sections=tuple(sections), passed=passed)

