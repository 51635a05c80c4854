"""The certificate's template (report/certificate.py; docs/reporting.md, "The certificate").

Every report, whatever the procedure, is a certificate: its heading (laboratory, customer, item,
calibration and issue dates, method, operator, authorisation, decision, traceability), the
registered equipment with certificates and due dates and any override, the uncertainty budget
of the parameters, the statement that the results relate only to the item calibrated; a DRAFT
(watermarked on every PDF page, a banner in HTML) until released; a twin run is never
traceable, and a report that does not know the station says traceability is not stated. Read
back from the PDF (pypdf) and the HTML.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import pytest
from pypdf import PdfReader

from imucalib import units
from imucalib.exports.outputs import write_outputs
from imucalib.exports.report import build_report, laboratory_facts
from imucalib.models.reported import ReportedParameter
from imucalib.models.result_document import load_result
from imucalib.procedures import registry
from imucalib.report.certificate import (
    RELATES_ONLY,
    CertificateFacts,
    EquipmentItem,
    Release,
    budget_table,
)
from imucalib.report.html import render_report_html
from imucalib.report.pdf import write_report_pdf

from ._standins import stand_in

LAB = {"laboratory": "Inertial Lab", "address": "1 Example Street", "customer": "ACME GmbH",
       "accreditation": "not accredited"}


def _pages(pdf: Path) -> list[str]:
    return [" ".join(p.extract_text().split()) for p in PdfReader(str(pdf)).pages]


@pytest.fixture(scope="module")
def p1(consumer_run: Path, tmp_path_factory: pytest.TempPathFactory) -> SimpleNamespace:
    analysis = registry.get("p1").analyze(consumer_run)
    out = tmp_path_factory.mktemp("template")
    result_file = write_outputs(analysis, out, ["result-json"], name="c")[0]
    return SimpleNamespace(analysis=analysis, out=out, stored=load_result(result_file),
                           run=consumer_run)


def test_a_draft_carries_draft_on_every_page_a_released_report_does_not(p1, tmp_path):
    draft = build_report(p1.analysis, recording=p1.run, facts=laboratory_facts(**LAB))
    assert draft.watermark == "DRAFT"
    pages = _pages(write_report_pdf(draft, tmp_path / "draft.pdf"))
    assert len(pages) >= 3
    for n, text in enumerate(pages, start=1):
        assert "DRAFT" in text and draft.report_id in text
        assert f"page {n} of {len(pages)}" in text
    html = render_report_html(draft)
    assert '<div class="draft-banner">DRAFT: not released' in html
    assert f'<header>Report <span class="report-id">{draft.report_id}</span> — DRAFT' in html
    released = build_report(p1.analysis, recording=p1.run, facts=laboratory_facts(
        **LAB, release=Release(True, "Q. Lead", "approve", "2026-01-05 09:00 UTC", "checked",
                               "approved by Q. Lead")))
    assert released.watermark == "" and released.report_id == draft.report_id
    pages = _pages(write_report_pdf(released, tmp_path / "released.pdf"))
    for n, text in enumerate(pages, start=1):
        assert "DRAFT" not in text and released.report_id in text
        assert f"page {n} of {len(pages)}" in text
    flat = " ".join(pages)
    assert "authorised by Q. Lead (approve, 2026-01-05 09:00 UTC)" in flat
    assert ("Authorisation: released — authorised by Q. Lead, decision approve, on "
            "2026-01-05 09:00 UTC: checked.") in flat
    assert "<div class=\"draft-banner\">" not in render_report_html(released)
    # a rejection is no release: still a DRAFT, saying why
    rejected = build_report(p1.analysis, facts=CertificateFacts(release=Release(
        False, "Q. Lead", "reject", "2026-01-05", "noisy", "rejected by Q. Lead")))
    assert rejected.watermark == "DRAFT"
    assert dict(rejected.certificate.tables[0].rows)["status"] == (
        "DRAFT: not released (rejected by Q. Lead)")


def test_the_heading_states_who_for_whom_what_when_how(p1, tmp_path):
    doc = build_report(p1.analysis, recording=p1.run, facts=laboratory_facts(
        **LAB, operator="J. Doe"))
    rows = dict(doc.certificate.tables[0].rows)
    assert rows["certificate (report) id"] == doc.report_id
    assert (rows["laboratory"], rows["address"], rows["accreditation"]) == (
        "Inertial Lab", "1 Example Street", "not accredited")
    assert rows["customer"] == "ACME GmbH"
    assert rows["item calibrated"] == "inertial measurement unit, serial IMU-0001"
    assert (rows["model"], rows["maker"]) == ("twin-consumer", "imucalib digital twin")
    # the calibration date is the run's (the recording's start), the issue date the report's
    from imucalib.io.opening import open_recording

    with open_recording(p1.run) as rec:
        started = str(rec.metadata["run_started_utc"])
    assert rows["calibration date"] == f"{started[:10]} {started[11:16]} UTC"
    assert rows["date of issue"] == doc.issued_utc
    assert rows["method"].startswith("procedure P1: ") and rows["method"].endswith(
        "(docs/p1.md)")
    assert rows["operator"] == "J. Doe" and rows["decision"] == "PASS"
    assert rows["traceability"].startswith("NOT traceable: simulated station")
    flat = " ".join(_pages(write_report_pdf(doc, tmp_path / "c.pdf")))
    assert RELATES_ONLY in flat and "Certificate of calibration" in flat
    assert "Operator: J. Doe." in flat
    # section 1 completes the unit's identity from the recording
    ident = dict(doc.section("1.").tables[0].rows)
    assert (ident["model"], ident["maker"]) == ("twin-consumer", "imucalib digital twin")


def test_without_facts_the_certificate_says_not_stated(p1):
    doc = build_report(p1.stored)  # a result file alone: no recording, no records, no config
    rows = dict(doc.certificate.tables[0].rows)
    for key in ("laboratory", "address", "customer", "calibration date", "operator"):
        assert rows[key] == "not stated", key
    assert rows["accreditation"] == "not accredited"
    assert rows["authorised by"] == "not authorised (DRAFT)"
    # the station is not known: traceability is not stated, never claimed
    assert rows["traceability"].startswith("not stated")
    section2 = " ".join(doc.section("2.").paragraphs)
    assert section2.startswith("Traceability: not stated.")
    assert "traceable to the SI through" not in section2
    assert "Registered equipment used: not stated" in section2


def test_a_twin_run_is_not_traceable_whatever_the_procedure_says(p1):
    stored = build_report(p1.stored, recording=p1.run)  # the result file with its recording
    assert "NOT traceable to the SI" in stored.section("2.").paragraphs[0]
    assert dict(stored.certificate.tables[0].rows)["traceability"].startswith("NOT traceable")
    # a procedure with a traceability statement of its own (the field calibration's) on the twin
    from imucalib.report.sections import equipment_section, recording_facts

    meta = recording_facts(p1.run)
    section = equipment_section(meta, None, "x", statement="Traceability: by hand, gravity.")
    assert "NOT traceable to the SI" in section.paragraphs[0]


def test_the_equipment_with_certificates_due_dates_and_an_override(p1):
    facts = laboratory_facts(equipment=(
        EquipmentItem("rotation table", "AC-2", "T-42", "CERT-2025-17", "2026-06-30"),
        EquipmentItem("thermal chamber", "TC-1", "C-7", "CERT-2024-3", "2025-01-01",
                      "overdue at the run")),
        overrides=("equipment overdue for calibration used: chamber off, not used",))
    doc = build_report(p1.analysis, recording=p1.run, facts=facts)
    section = doc.section("2.")
    table = next(t for t in section.tables if t.title == "equipment used (records)")
    assert table.header == ("equipment", "model", "serial", "certificate", "due on", "note")
    assert table.rows == (("rotation table", "AC-2", "T-42", "CERT-2025-17", "2026-06-30", ""),
                          ("thermal chamber", "TC-1", "C-7", "CERT-2024-3", "2025-01-01",
                           "overdue at the run"))
    assert ("Override: equipment overdue for calibration used: chamber off, not used"
            in section.paragraphs)
    none = build_report(p1.analysis, recording=p1.run, facts=laboratory_facts(equipment=()))
    assert ("Registered equipment used: none registered for the run's station."
            in none.section("2.").paragraphs)


def test_the_budget_splits_u_into_type_a_type_b_and_the_misfit(p1):
    doc = build_report(p1.analysis, recording=p1.run)
    budget = next(t for t in doc.section("5.").tables if t.title.startswith("uncertainty budget"))
    assert budget.header == ("parameter", "Type A (noise)", "Type B (station)",
                             "model misfit (Birge)", "combined u", "U = 2u", "unit")
    rows = {r[0]: r[1:] for r in budget.rows}
    assert len(rows) == 33
    # P1's Type B: the table's position accuracy (10″) on the accelerometer misalignments and
    # its perpendicularity (5″) on the gyro's, uniform: u = a/√3, in µrad
    assert rows["accel_M_xy"][1] == f"{10 * units.ARCSEC / math.sqrt(3) / units.URAD:.2g}"
    assert rows["gyro_M_yz"][1] == f"{5 * units.ARCSEC / math.sqrt(3) / units.URAD:.2g}"
    assert rows["accel_bias_x"][1] == "0" and rows["gyro_M_xx"][1] == "0"
    # the parts add up to the combined u the results table uses
    by_name = {r.name: r for r in p1.analysis.parameter_rows()}
    r = by_name["accel_M_xy"]
    u_b = 10 * units.ARCSEC / math.sqrt(3)
    u_a = math.sqrt(r.std_noise**2 - u_b**2)
    assert rows["accel_M_xy"][0] == f"{u_a / units.URAD:.2g}"
    assert rows["accel_M_xy"][3] == f"{r.std / units.URAD:.2g}"
    # the result read back from its file gives the same budget (P1's Type B from its notes)
    again = build_report(p1.stored, recording=p1.run)
    assert next(t for t in again.section("5.").tables
                if t.title.startswith("uncertainty budget")).rows == budget.rows
    # [certificate] show_budget = false leaves it out
    off = build_report(p1.analysis, facts=CertificateFacts(show_budget=False))
    assert not any(t.title.startswith("uncertainty budget") for t in off.section("5.").tables)


def test_a_misfit_and_a_type_b_add_up_in_quadrature():
    rows = [ReportedParameter("K2", 0.5, 2.0, "1/g", 1.0)]  # u = 2, before Birge scaling 1
    table = budget_table(rows, {"K2": 0.6})
    # Type A √(1 − 0.36) = 0.8, Type B 0.6, misfit √(4 − 1) = 1.7, u = 2, U = 4
    assert table.rows == (("K2", "0.80", "0.60", "1.7", "2.0", "4.0", "1/g"),)
    # a procedure that itemises no Type B: a dash, and Type A holds std_noise
    assert budget_table(rows, None).rows == (("K2", "1.0", "—", "1.7", "2.0", "4.0", "1/g"),)


def test_every_procedure_gets_the_template(tmp_path):
    """The generic content (a classical test, a plug-in) is a certificate too."""
    result = stand_in("tumble", "U-9", [("accel_bias_x", 1e-3, 1e-4, "m/s^2")], passed=True)
    doc = build_report(result, facts=laboratory_facts(**LAB))
    assert doc.certificate is not None and doc.watermark == "DRAFT"
    rows = dict(doc.certificate.tables[0].rows)
    assert rows["customer"] == "ACME GmbH" and rows["decision"] == "PASS"
    assert rows["method"].endswith("(docs/tumble.md)")
    assert any(t.title.startswith("uncertainty budget") for t in doc.section("5.").tables)
    assert doc.section("6.").paragraphs[0] == "Decision: PASS (a stand-in rule)"
    flat = " ".join(_pages(write_report_pdf(doc, tmp_path / "t.pdf")))
    assert RELATES_ONLY in flat and "DRAFT" in flat


def test_a_stored_result_states_its_own_decision(p1):
    """A result file's decision (version 4) is the report's, with its checks."""
    doc = build_report(p1.stored)
    decision = p1.stored.decision
    assert decision.passed is True
    conclusion = doc.section("6.").paragraphs[0]
    assert conclusion == f"Decision: {decision.summary()}"
    checks = next(t for t in doc.section("5.").tables if t.title == "checks of the decision")
    assert [r[0] for r in checks.rows] == [c.name for c in decision.checks]
    assert dict(doc.certificate.tables[0].rows)["decision"] == "PASS"
    assert build_report(replace(p1.stored)).report_id == build_report(p1.analysis).report_id
