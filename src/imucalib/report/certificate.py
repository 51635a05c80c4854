"""The certificate's parts beyond a procedure's content: its heading, equipment, budget, release.

Every calibration report is a certificate of one template (ISO/IEC 17025:2017 §7.8.2, §7.8.4;
docs/reporting.md, "The certificate"): :func:`~imucalib.report.document.assemble_report` puts
before a procedure's sections 1–5 the certificate's heading (:func:`certificate_section`) and adds
to them the registered equipment (section 2, :func:`equipment_table`), the laboratory's site and
the run's environment (section 3), the uncertainty budget (section 5, :func:`budget_table`), and
the operator, the authorisation and the statements (section 6, :func:`authorisation_lines`).

What the result does not know comes as plain values, :class:`CertificateFacts`: the laboratory
(the laboratory configuration, :mod:`imucalib.config`), the customer, and what the records
database knows of the run (operator, calibration date, equipment with certificates, overrides)
and of the result's release (:class:`Release`). A fact not given is read from the recording
(the run's metadata: ``run_operator``, ``run_started_utc``, ``station_equipment_json``,
``override_due``, ``customer``) when the report has it, else stated as "not stated".

The report is a **DRAFT** until it is released (a reviewer's authorisation in the records):
the PDF carries "DRAFT" across every page, the HTML a banner. A recording of the digital twin
(its ``station_json`` kind ``digital-twin``) is never traceable (:func:`simulated`); a report
that does not know the station says that traceability is not stated.

Contents
--------
:class:`CertificateFacts`, :class:`EquipmentItem`, :class:`Release`, :func:`release_from_reviews`,
:func:`simulated`, :func:`identity`, :func:`certificate_section`, :func:`equipment_table`,
:func:`budget_table`, :func:`authorisation_lines`, :func:`complete`, :func:`when_text`,
:data:`RELATES_ONLY`, :data:`NOT_STATED`, :data:`CERTIFICATE_TITLE`
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import date, datetime
from typing import Any

from imucalib.models.reported import ReportedParameter
from imucalib.report.document import COVERAGE_FACTOR, ReportTable, ReviewStatus, Section

__all__ = ["CERTIFICATE_TITLE", "NOT_STATED", "RELATES_ONLY", "CertificateFacts",
           "EquipmentItem", "Release", "authorisation_lines", "budget_table",
           "certificate_section", "complete", "equipment_table", "identity",
           "release_from_reviews", "simulated", "when_text"]

#: What a certificate says of a fact it does not know.
NOT_STATED = "not stated"
#: The statement every certificate carries (ISO/IEC 17025:2017 §7.8.2.1 k).
RELATES_ONLY = "The results relate only to the item calibrated."
#: The title of the certificate's heading (before section 1).
CERTIFICATE_TITLE = "Certificate of calibration"


def when_text(value: Any) -> str:
    """Return a date or time as the certificate prints it ("" for None)."""
    if value is None or value == "":
        return ""
    if isinstance(value, datetime):
        return value.strftime("%Y-%m-%d %H:%M UTC")
    if isinstance(value, date):
        return value.isoformat()
    text = str(value)
    try:  # an ISO time as a recording's metadata holds it ("2026-01-02T10:00:00Z")
        parsed = datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        return text
    return parsed.strftime("%Y-%m-%d %H:%M UTC") if "T" in text else text


@dataclass(frozen=True)
class EquipmentItem:
    """One piece of equipment used: kind, model, serial, certificate, due date, a note."""

    kind: str
    model: str = ""
    serial: str = ""
    certificate: str = ""
    due_on: str = ""
    note: str = ""


@dataclass(frozen=True)
class Release:
    """The release of a result: released or not, by whom, the decision, when, and why.

    Made from the records' release status (``Records.release_status(result_id)``: a reviewer's
    authorisation), or from the result's reviews (:func:`release_from_reviews`).
    """

    released: bool
    reviewer: str = ""
    decision: str = ""
    reviewed_utc: str = ""
    comment: str = ""
    reason: str = ""


@dataclass(frozen=True)
class CertificateFacts:
    """What a certificate states beyond the result (module docstring); plain values.

    Attributes
    ----------
    laboratory, address, accreditation : str
        The issuing laboratory (``[laboratory]`` of the laboratory configuration).
    customer, operator, calibration_date : str
        "" : the recording's (``customer``, ``run_operator``, ``run_started_utc``), else
        "not stated".
    equipment : tuple of EquipmentItem, or None
        The equipment the run used, with certificates and due dates; None: the recording's
        ``station_equipment_json`` when it has one, else not stated.
    overrides : tuple of str
        Each override of a check at the run (an overdue certificate) with its reason; empty:
        the recording's ``override_due``.
    release : Release, optional
        None: not released (a DRAFT), unless the reviews given release it.
    records_result_id, run_id : int, optional
        The result's and the run's ids in the records database.
    method : str
        The procedure and where its method is described ("" : the procedure's name).
    site : tuple of (str, str)
        The laboratory's site (``[site]``) as rows.
    environment : tuple of (str, str)
        The run's environment the records hold, as rows.
    show_budget : bool
        Whether section 5 carries the uncertainty budget (``[certificate] show_budget``).
    statements : tuple of str
        Further statements of the laboratory (``[certificate] statements``).
    """

    laboratory: str = NOT_STATED
    address: str = NOT_STATED
    accreditation: str = "not accredited"
    customer: str = ""
    operator: str = ""
    calibration_date: str = ""
    equipment: tuple[EquipmentItem, ...] | None = None
    overrides: tuple[str, ...] = ()
    release: Release | None = None
    records_result_id: int | None = None
    run_id: int | None = None
    method: str = ""
    site: tuple[tuple[str, str], ...] = ()
    environment: tuple[tuple[str, str], ...] = ()
    show_budget: bool = True
    statements: tuple[str, ...] = ()


def release_from_reviews(reviews: Sequence[ReviewStatus]) -> Release | None:
    """Return the release the reviews make: the last review, if it approves (else not released).

    For a report made without the records' release status; None without a review.
    """
    if not reviews:
        return None
    last = reviews[-1]
    return Release(released=last.approved, reviewer=last.reviewer,
                   decision="approve" if last.approved else "reject",
                   reviewed_utc=last.reviewed_utc, comment=last.comment,
                   reason=("approved by " if last.approved else "rejected by ") + last.reviewer)


def _json(meta: Mapping[str, Any], key: str) -> Any:
    value = meta.get(key)
    if isinstance(value, str) and value:
        try:
            return json.loads(value)
        except ValueError:
            return None
    return value


def simulated(meta: Mapping[str, Any]) -> bool | None:
    """Whether the recording was made on the digital twin (None: no recording, not known)."""
    if not meta:
        return None
    station = _json(meta, "station_json")
    if isinstance(station, Mapping) and (station.get("kind") == "digital-twin"
                                         or isinstance(station.get("twin"), Mapping)):
        return True
    return str(meta.get("source", "")).lower() in ("sim", "simulate", "simulation", "twin")


def identity(unit: str, meta: Mapping[str, Any], stated: Mapping[str, Any]) -> dict[str, str]:
    """Return the item's serial, model and maker: the result's (`stated`), else the recording's."""
    ident = _json(meta, "imu_identity_json")
    mine = ident.get(unit) if isinstance(ident, Mapping) else None
    mine = mine if isinstance(mine, Mapping) else {}
    return {k: str(stated.get(k) or mine.get(k) or (unit if k == "serial" else NOT_STATED))
            for k in ("serial", "model", "maker")}


def _recorded_equipment(meta: Mapping[str, Any]) -> tuple[EquipmentItem, ...] | None:
    rows = _json(meta, "station_equipment_json")
    if not isinstance(rows, list):
        return None
    return tuple(EquipmentItem(str(r.get("kind") or "—"), str(r.get("model") or ""),
                               str(r.get("serial") or ""), str(r.get("certificate") or ""),
                               str(r.get("due_on") or ""))
                 for r in rows if isinstance(r, Mapping))


def complete(facts: CertificateFacts, meta: Mapping[str, Any]) -> CertificateFacts:
    """Return `facts` with what it leaves open read from the recording's metadata `meta`."""
    from dataclasses import replace

    env = _json(meta, "environment_json")
    env = env if isinstance(env, Mapping) else {}
    override = str(meta.get("override_due") or "").strip()
    return replace(
        facts,
        customer=facts.customer or str(meta.get("customer") or env.get("customer") or ""),
        operator=facts.operator or str(meta.get("run_operator") or meta.get("operator") or ""),
        calibration_date=facts.calibration_date or when_text(meta.get("run_started_utc")),
        equipment=facts.equipment if facts.equipment is not None else _recorded_equipment(meta),
        overrides=facts.overrides or ((f"equipment overdue for calibration used: {override}",)
                                      if override else ()))


def traceability_line(sim: bool | None, reference: bool) -> str:
    """Return the certificate heading's traceability cell (sim: the twin; None: not known)."""
    if sim:
        return "NOT traceable: simulated station (digital twin); the values are not measurements"
    if sim is None:
        return (f"{NOT_STATED}: the recording, and so the station that made the result, was "
                "not given to this report")
    if not reference:
        return "no reference quantity (a noise characterisation): see section 2"
    return "to the SI through the certificates of the equipment (section 2)"


def certificate_section(*, report_id: str, issued: str, facts: CertificateFacts,
                        item: Mapping[str, str], procedure: str, decision: str,
                        sim: bool | None, reference: bool = True) -> Section:
    """Return the certificate's heading: who, for whom, what, when, how, status, statements.

    `facts` completed (:func:`complete`); `item` from :func:`identity`.
    """
    release = facts.release
    released = release is not None and release.released
    if released:
        assert release is not None
        status = (f"released: authorised by {release.reviewer}"
                  + (f" on {release.reviewed_utc}" if release.reviewed_utc else ""))
    else:
        status = "DRAFT: not released (" + (
            release.reason or f"{release.decision or 'no decision'} by {release.reviewer}"
            if release is not None else "no authorising review") + ")"
    records = ", ".join(part for part in (
        f"run {facts.run_id}" if facts.run_id is not None else "",
        f"result {facts.records_result_id}" if facts.records_result_id is not None else "")
        if part) or "not recorded (or not consulted)"
    rows = (("certificate (report) id", report_id), ("status", status),
            ("laboratory", facts.laboratory or NOT_STATED),
            ("address", facts.address or NOT_STATED),
            ("accreditation", facts.accreditation or "not accredited"),
            ("customer", facts.customer or NOT_STATED),
            ("item calibrated", f"inertial measurement unit, serial {item['serial']}"),
            ("model", item["model"]), ("maker", item["maker"]),
            ("calibration date", facts.calibration_date or NOT_STATED),
            ("date of issue", issued),
            ("method", facts.method or f"procedure {procedure.upper()}"),
            ("operator", facts.operator or NOT_STATED),
            ("authorised by", f"{release.reviewer} ({release.decision or 'approve'}, "
                              f"{release.reviewed_utc or 'date not stated'})"
             if released and release is not None else "not authorised (DRAFT)"),
            ("decision", decision),
            ("traceability", traceability_line(sim, reference)),
            ("records", records))
    paragraphs = [RELATES_ONLY, *facts.statements]
    if not released:
        paragraphs.insert(0, "DRAFT: this report is not a certificate until a reviewer has "
                             "released it (imucalib records review; docs/records.md).")
    return Section(CERTIFICATE_TITLE, tuple(paragraphs),
                   (ReportTable("certificate", ("item", "value"), rows),))


def equipment_table(facts: CertificateFacts) -> tuple[ReportTable | None, tuple[str, ...]]:
    """Section 2's equipment used with certificates and due dates, and the override lines."""
    lines = tuple(f"Override: {o}" for o in facts.overrides)
    if facts.equipment is None:
        return None, ("Registered equipment used: not stated (the run is not in the records "
                      "database, or the report was made without it).", *lines)
    if not facts.equipment:
        return None, ("Registered equipment used: none registered for the run's station.",
                      *lines)
    rows = tuple((e.kind, e.model or "—", e.serial or "—", e.certificate or NOT_STATED,
                  e.due_on or NOT_STATED, e.note or "") for e in facts.equipment)
    return (ReportTable("equipment used (records)", ("equipment", "model", "serial",
                                                     "certificate", "due on", "note"), rows),
            lines)


def _u_text(u: float, scale: float) -> str:
    from imucalib.report.numbers import round_pair

    if not math.isfinite(u):
        return "—"
    if u == 0.0:
        return "0"
    return round_pair(0.0, u / scale).uncertainty_text


def budget_table(rows: Sequence[ReportedParameter], type_b: Mapping[str, float] | None
                 ) -> ReportTable:
    """Return the uncertainty budget of each parameter (standard uncertainties, display units).

    Type A (noise) u_A, Type B (station) u_B, the model misfit (Birge) u_M, the combined
    u = √(u_A² + u_B² + u_M²) as reported, and U = k·u: ``std_noise`` holds u_A and u_B
    (u_A = √(std_noise² − u_B²)), ``std`` the Birge-scaled u (u_M = √(std² − std_noise²)).
    `type_b` the Type B standard uncertainty per parameter [SI] the procedure added (absent: 0);
    None: the procedure does not itemise it (a dash; the Type A column then holds all of
    std_noise).
    """
    from imucalib.report.console import display_unit

    out = []
    for r in rows:
        if not (math.isfinite(r.value) and math.isfinite(r.std)):
            continue
        unit, scale = display_unit(r.name, r.unit)
        noise = r.std_noise if math.isfinite(r.std_noise) else r.std
        u_b = None if type_b is None else float(type_b.get(r.name, 0.0))
        u_a = math.sqrt(max(noise**2 - (u_b or 0.0) ** 2, 0.0))
        u_m = math.sqrt(max(r.std**2 - noise**2, 0.0))
        out.append((r.name, _u_text(u_a, scale), "—" if u_b is None else _u_text(u_b, scale),
                    _u_text(u_m, scale), _u_text(r.std, scale),
                    _u_text(COVERAGE_FACTOR * r.std, scale), unit))
    return ReportTable("uncertainty budget (standard uncertainties u, k = 1; the last column "
                       f"U = {COVERAGE_FACTOR:g}u)",
                       ("parameter", "Type A (noise)", "Type B (station)",
                        "model misfit (Birge)", "combined u", f"U = {COVERAGE_FACTOR:g}u",
                        "unit"), tuple(out))


def authorisation_lines(facts: CertificateFacts) -> tuple[str, ...]:
    """Section 6's operator, authorisation (or DRAFT) and statements."""
    release = facts.release
    lines = [f"Operator: {facts.operator or NOT_STATED}."]
    if release is not None and release.released:
        lines.append(f"Authorisation: released — authorised by {release.reviewer}, decision "
                     f"{release.decision or 'approve'}, on "
                     f"{release.reviewed_utc or 'a date not stated'}"
                     + (f": {release.comment}" if release.comment else "") + ".")
    else:
        why = (release.reason or f"{release.decision or 'no decision'} by {release.reviewer}"
               if release is not None else "no authorising review")
        lines.append(f"Authorisation: DRAFT — not released ({why}); this report is not a "
                     "certificate until a reviewer has released it.")
    lines += [RELATES_ONLY, *facts.statements]
    return tuple(lines)
