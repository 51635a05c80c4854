"""The calibration report (certificate) of a P1 run on the twin, read back from its PDF and HTML.

What is checked (docs/reporting.md, "The calibration report"; ISO/IEC 17025 §7.8): every section
title; the unique id and "page n of N" on every page; every parameter's value and expanded
uncertainty U = 2u as the rounding rule prints them — the expected strings computed here from the
report JSON with an independent implementation of GUM 7.2.6 — and the decision; the HTML holds
the same numbers; the review status; the recording's SHA-256 in the appendix.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import re
import shutil
import subprocess
from html import escape
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from pypdf import PdfReader

from imucalib.errors import InvalidInputError
from imucalib.exports.outputs import write_outputs
from imucalib.exports.report import build_report
from imucalib.procedures import registry
from imucalib.report.document import SECTION_TITLES
from imucalib.report.html import write_report_html
from imucalib.report.pdf import write_report_pdf

from ._gum import expected_cells as _expected_cells
from ._gum import shown_p1 as _shown
from ._standins import stand_in


@pytest.mark.parametrize(("value", "big_u", "cells"), [
    (1.23456, 0.0567, ("+1.235", "0.057")), (12.345, 9.96, ("+12", "10")),
    (103.5726, 276.1, ("+1.0e2", "2.8e2")), (-0.0004, 0.034, ("0.000", "0.034")),
    (1.234e-7, 5.6e-9, ("+1.234e-7", "0.056e-7"))])
def test_the_independent_rule_agrees_with_the_documented_table(value, big_u, cells):
    assert _expected_cells(value, big_u) == cells


@pytest.fixture(scope="module")
def certificate(consumer_run: Path, tmp_path_factory: pytest.TempPathFactory):
    analysis = registry.get("p1").analyze(consumer_run)
    out = tmp_path_factory.mktemp("certificate")
    report_json = write_outputs(analysis, out, ["report-json"], name="c")[0]
    doc = build_report(analysis, recording=consumer_run)
    pdf = write_report_pdf(doc, out / "c.report.pdf")
    html = write_report_html(doc, out / "c.report.html")
    pages = [p.extract_text() for p in PdfReader(str(pdf)).pages]
    return SimpleNamespace(analysis=analysis, doc=doc, pages=pages, text="\n".join(pages),
                           html=html.read_text(encoding="utf-8"), out=out,
                           report=json.loads(report_json.read_text(encoding="utf-8")))


def test_every_page_carries_the_unique_id_and_page_n_of_n(certificate):
    pages, rid = certificate.pages, certificate.doc.report_id
    assert len(pages) >= 2
    assert re.fullmatch(r"IMUCAL-P1-IMU-0001-[0-9a-f]{12}", rid)
    for n, text in enumerate(pages, start=1):
        assert rid in text
        assert f"page {n} of {len(pages)}" in text


def test_every_section_title_is_present(certificate):
    for title in SECTION_TITLES:
        assert title in certificate.text
        assert escape(title) in certificate.html


def test_every_parameter_is_printed_with_its_expanded_uncertainty(certificate):
    result = certificate.report["result"]
    std = certificate.report["std_scaled"]  # u, Birge-scaled when the fit is a misfit
    text = certificate.text
    assert len(result["parameters"]) == 33  # triad: 2 × (3 biases + 9 M), 9 G
    for row in result["parameters"]:
        name = row["name"]
        shown, u, unit = _shown(name, row["value"], std[name])
        v_text, u_text = _expected_cells(shown, 2.0 * u)
        assert f"{name}\n{v_text}\n{u_text}\n{unit}" in text, name
        assert (f"<td>{name}</td><td>{v_text}</td><td>{u_text}</td><td>{escape(unit)}</td>"
                in certificate.html), name
        digits = u_text.split("e")[0].replace(".", "").lstrip("0")
        assert 1 <= len(digits) <= 2, u_text  # at most two significant digits
        decimals = [len(t.split("e")[0].partition(".")[2]) for t in (v_text, u_text)]
        assert decimals[0] == decimals[1]  # the value ends where U ends
    assert "U = k·u, k = 2" in text


def test_the_decision_its_rule_and_the_review_status_are_stated(certificate):
    decision = certificate.report["decision"]
    verdict = "PASS" if decision["passed"] else "FAIL"
    flat = " ".join(certificate.text.split())
    assert f"Decision: {verdict}" in flat
    assert " ".join(decision["rule"].split()) in flat
    assert "Acceptance (plan's [acceptance]): rule 'simple', guard band k = 2" in flat
    assert "Review status: not reviewed" in flat
    assert "Repeatability was not assessed" in flat  # one repetition: a recommendation


def test_the_appendix_and_environment_come_from_the_recording(certificate, consumer_run):
    flat = " ".join(certificate.text.split())
    sha = hashlib.sha256(consumer_run.read_bytes()).hexdigest()
    assert sha in certificate.text.replace("\n", "")
    assert sha in certificate.html
    assert "p1-dual-axis" in flat  # the plan's name
    assert "IMU temperature during the run" in flat
    assert "NOT traceable to the SI" in flat  # a twin run says so
    assert 'src="data:image/png;base64,' in certificate.html  # the residual figure, embedded


def test_a_review_from_the_records_is_shown(certificate):
    doc = build_report(certificate.analysis, result_id=7,
                       review={"reviewer": "qa-lead", "approved": True, "comment": "ok",
                               "reviewed_utc": "2026-01-02 10:00 UTC"})
    assert doc.report_id == certificate.doc.report_id  # the records id is not in the report id
    assert dict(doc.certificate.tables[0].rows)["records"] == "result 7"
    conclusion = " ".join(doc.section("6.").paragraphs)
    assert "approved by qa-lead on 2026-01-02 10:00 UTC: ok" in conclusion
    assert ("Authorisation: released — authorised by qa-lead, decision approve, on "
            "2026-01-02 10:00 UTC: ok.") in conclusion
    assert "not reviewed" not in conclusion and doc.watermark == ""
    with pytest.raises(InvalidInputError, match="reviewer"):
        build_report(certificate.analysis, review={"approved": True})


def test_the_id_is_the_same_for_the_same_result_and_differs_for_another(certificate,
                                                                        consumer_run):
    again = build_report(certificate.analysis)
    assert again.report_id == certificate.doc.report_id
    # the same result analysed at another time: the same id
    analysis = certificate.analysis
    later = dataclasses.replace(analysis, result=dataclasses.replace(
        analysis.result, provenance=dataclasses.replace(analysis.result.provenance,
                                                        created_utc="2031-01-01T00:00:00Z")))
    assert later.to_dict() != analysis.to_dict()
    assert build_report(later).report_id == again.report_id
    reanalysed = registry.get("p1").analyze(consumer_run)  # the recording analysed again
    assert build_report(reanalysed).report_id == again.report_id
    # another option, another result: another id
    per_axis = registry.get("p1").analyze(consumer_run, options={"model": "per-axis"})
    assert build_report(per_axis).report_id != again.report_id
    other = stand_in("earth-rate-bias", "IMU-0001", [("bias_x", 0.0, 1.0, "rad/s")],
                     to_dict=lambda: {"x": 1})
    assert build_report(other).report_id != again.report_id


def test_a_result_with_parameter_rows_gets_the_same_rule():
    rows = [("gyro_bias_x", 1.23456e-5, 3.21e-7, "rad/s"), ("K2", -12.345, 4.98, "1/g")]
    result = stand_in("earth-rate-bias", "U-1", rows, passed=False, to_dict=lambda: {"rows": rows})
    doc = build_report(result)
    table = doc.section("5.").tables[0]
    # a triad parameter in its display unit (1.23456e-5 rad/s = 2.5465 °/h, U = 0.1324 °/h),
    # any other in SI; U = 2u to two significant digits, the value to the same place
    assert table.rows == (("gyro_bias_x", "+2.55", "0.13", "°/h"),
                          ("K2", "-12", "10", "1/g"))
    assert [s.title for s in doc.sections] == list(SECTION_TITLES)
    assert doc.section("6.").paragraphs[0].startswith("Decision: FAIL")
    with pytest.raises(InvalidInputError, match="no parameter rows"):
        build_report(stand_in("x", "u"))


def test_p1_writes_the_pdf_by_default(certificate):
    assert "report-pdf" in registry.get("p1").outputs
    written = write_outputs(certificate.analysis, certificate.out, ["report-pdf", "report-html"],
                            name="d")
    assert [p.name for p in written] == ["d.IMU-0001.p1.report.pdf",
                                         "d.IMU-0001.p1.report.html"]
    assert written[0].read_bytes().startswith(b"%PDF")


def test_a_noise_characterisation_gets_its_noise_tables_and_allan_figures(tmp_path):
    from imucalib.procedures.allan.analysis import analyze_allan_arrays

    rng = np.random.default_rng(1)
    n, rate_hz, sigma_rps = 20000, 100.0, 1e-3
    columns = {f"gyro_{a}_rps": rng.normal(0.0, sigma_rps, n) for a in "xyz"}
    columns.update({f"accel_{a}_mps2": rng.normal(0.0, 1e-2, n) for a in "xyz"})
    columns["temperature_degc"] = np.full(n, 21.5)
    result = analyze_allan_arrays(np.arange(n) / rate_hz, columns, source="rest.csv",
                                  unit="IMU-A")
    doc = build_report(result)
    assert [s.title for s in doc.sections] == list(SECTION_TITLES)
    results = doc.section("5.")
    assert [t.header[2:] for t in results.tables[:2]] == [("gyro_x", "gyro_y", "gyro_z"),
                                                          ("accel_x", "accel_y", "accel_z")]
    assert results.tables[2].title.startswith("uncertainty budget")  # the certificate's
    assert len(results.figures) == 2 and all(f.png.startswith(b"\x89PNG") for f in results.figures)
    arw = dict((row[0], row[2:]) for row in results.tables[0].rows)["Angle random walk"]
    # white noise σ at rate f: ARW = σ/√f [rad/√s] = σ/√f · (180/π) · 60 [°/√h]
    truth_deg_rth = sigma_rps / np.sqrt(rate_hz) * np.degrees(1.0) * 60.0
    for cell in arw:
        value = float(cell.split("±")[0])
        assert abs(value - truth_deg_rth) < 0.05 * truth_deg_rth
    assert "21.5 °C" in " ".join(c for t in doc.section("3.").tables for r in t.rows for c in r)
    pages = PdfReader(str(write_report_pdf(doc, tmp_path / "a.pdf"))).pages
    assert all(doc.report_id in p.extract_text() for p in pages)


def test_a_guarded_rule_is_stated_with_its_guard_band(consumer_run):
    from imucalib.procedures.p1.analysis import P1Options, analyze_p1

    analysis = analyze_p1(consumer_run, options=P1Options(acceptance="guarded", guard_band_k=3.0,
                                                          hash_recording=False))
    doc = build_report(analysis)
    results = " ".join(doc.section("5.").paragraphs)
    assert "rule 'guarded', guard band k = 3" in results
    assert "|value| + 3·u is within its limit" in results
    appendix = dict(doc.section("Appendix").tables[0].rows)
    assert appendix["recording SHA-256"] == "not hashed"


if shutil.which("pdftoppm") or os.environ.get("IMUCALIB_TEST_PDFTOPPM"):
    # defined where the renderer is (CI installs poppler-utils: .ci/run), never skipped there
    def test_the_pages_render_to_png(certificate):
        """Smoke test: pdftoppm renders every page of the certificate to a non-blank PNG."""
        exe = shutil.which("pdftoppm")
        assert exe, "pdftoppm (poppler-utils) is needed: .ci/run installs it"
        pdf = certificate.out / "c.report.pdf"
        done = subprocess.run([exe, "-png", "-r", "40", str(pdf), str(certificate.out / "pg")],
                              capture_output=True, text=True, check=False)
        assert done.returncode == 0, done.stderr
        pngs = sorted(certificate.out.glob("pg-*.png"))
        assert len(pngs) == len(certificate.pages) >= 3
        import matplotlib.image as mpimg

        for png in pngs:
            img = mpimg.imread(png)
            assert img.shape[0] > 200 and img.std() > 0.01      # something is printed


def test_the_held_out_and_repeatability_checks_are_drawn(certificate):
    results = certificate.doc.section("5")
    captions = [f.caption for f in results.figures]
    assert len(captions) == 3 and captions[1].startswith("Held-out verification")
    assert captions[2].startswith("Allan deviation of the noise model")
    assert all(f.png[:8] == b"\x89PNG\r\n\x1a\n" for f in results.figures)
    assert "Held-out verification and repeatability" in certificate.text
    checks = [c for c in certificate.analysis.checks if c.name.startswith("held-out")
              or c.name == "repeatability"]
    # this run has one repetition: repeatability is not assessed and has no rows to draw
    assert [c.name for c in checks if c.rows] == ["held-out accelerometer accuracy",
                                                  "held-out gyro accuracy"]


def test_every_procedure_the_generic_content_reports_cites_an_existing_page():
    root = Path(__file__).resolve().parents[2]
    rows = [("accel_bias_x", 1e-3, 1e-4, "m/s^2")]
    # the built-ins without report content of their own (procedures/<name>/report.py): the generic
    # content, field's with its own traceability statement
    generic = [n for n in registry.BUILTIN if n not in ("p1", "allan", "p2")]
    assert "field" in generic and "p3" in generic
    for name in generic:
        assert (root / "docs" / f"{name}.md").is_file(), name
        doc = build_report(stand_in(name, "U", rows))
        assert f"(docs/{name}.md)." in doc.section("4.").paragraphs[0]
        assert registry.get(name).description.rstrip(".")[:40] in doc.section("4.").paragraphs[0]


def test_the_noise_model_behind_the_weights_is_stated_and_drawn(certificate):
    """P1's window standard errors come from the static record's noise model (docs/p1.md)."""
    noise = certificate.analysis.observations.noise
    assert set(noise) == {"gyro", "accel"}
    results = certificate.doc.section("5.")
    table = next(t for t in results.tables if t.title.startswith("noise model"))
    rows = {r[0]: r[1:] for r in table.rows}
    assert len(rows) == 6
    for i, axis in enumerate("xyz"):
        gyro, accel = noise["gyro"], noise["accel"]
        # N in °/√h: rad/√s × (180/π) × 60; B in °/h; accelerometer N in µg/√Hz, B in µg
        assert rows[f"gyro {axis}"][0] == f"{gyro.white_density[i] * 180 / math.pi * 60:.3g} °/√h"
        assert rows[f"gyro {axis}"][1] == (
            f"{gyro.bias_instability[i] * 180 / math.pi * 3600:.3g} °/h")
        assert rows[f"accel {axis}"][0] == f"{accel.white_density[i] / 9.80665e-6:.3g} µg/√Hz"
        assert rows[f"accel {axis}"][1] == f"{accel.bias_instability[i] / 9.80665e-6:.3g} µg"
    assert any("noise model fitted to the long static records" in f.caption
               for f in results.figures)
    assert "noise model of the long static records" in certificate.text
