"""The report of each P2 unit and the summary of the array, read back as a user reads them.

A small P2 run on the twin (three units, three calibration temperatures and one held out, about
8 s) is analysed once; the tests read the PDFs' text (pypdf) and check what docs/reporting.md
promises: every section, the parameters at T0 with U = 2u rounded as stated (strings computed
here independently), one row per temperature model with its χ²/ν and held-out check, the
parameters-versus-temperature figure, and a summary with one row per unit naming each unit's
own report id; the CLI writes them from a recording and from a records run (with its review).
"""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path
from types import SimpleNamespace

import pytest
from pypdf import PdfReader
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.errors import MissingSegmentError
from imucalib.exports.outputs import write_outputs
from imucalib.exports.report import build_report, build_summary_report
from imucalib.models.result_document import load_result
from imucalib.procedures.p2.analysis import failed_unit
from imucalib.procedures.p2.batch import P2BatchResult, analyze_p2
from imucalib.records.calibrations import record_calibration
from imucalib.report.console import display_unit
from imucalib.report.document import SECTION_TITLES

from ..procedures._p2_twin import run_twin_p2, shared_run, twin_equipment, twin_plan
from ._gum import expected_cells


def _small_run(path: Path) -> Path:
    plan = twin_plan(twin_equipment(3), temperatures_degc=(-10.0, 20.0, 50.0),
                     held_out_degc=(35.0,), hysteresis=False)
    return run_twin_p2(plan, path, truth_streams=False)


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> SimpleNamespace:
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent
    recording = shared_run(base, "p2-report-small", _small_run)
    batch = analyze_p2(recording)
    out = tmp_path_factory.mktemp("p2-report")
    written = write_outputs(batch, out, name="small")
    return SimpleNamespace(recording=recording, batch=batch, out=out, written=written)


def _text(path: Path) -> str:
    return "\n".join(p.extract_text() for p in PdfReader(str(path)).pages)


def test_p2_writes_a_report_per_unit_and_the_summary_by_default(small):
    names = {p.name for p in small.written}
    for unit in ("U0", "U1", "U2"):
        assert f"small.{unit}.p2.report.pdf" in names
    assert "small.array.p2.summary.report.pdf" in names


def test_a_unit_report_holds_every_section_and_its_parameters_at_t0(small):
    unit = small.batch.results[0]
    assert unit.error == "", unit.error
    pdf = small.out / f"small.{unit.unit}.p2.report.pdf"
    text = _text(pdf)
    pages = PdfReader(str(pdf)).pages
    rid = build_report(unit).report_id
    assert re.fullmatch(r"IMUCAL-P2-U0-[0-9a-f]{12}", rid)
    for n, page in enumerate(pages, start=1):
        assert rid in page.extract_text() and f"page {n} of {len(pages)}" in page.extract_text()
    for title in SECTION_TITLES:
        assert title in text
    report = json.loads((small.out / "small.U0.p2.result.json").read_text(encoding="utf-8"))
    std = unit.result.std(scaled=True)
    assert len(report["parameters"]) == 36
    for row in report["parameters"]:
        name = row["name"]
        unit_text, scale = display_unit(name, row["unit"])
        v_text, u_text = expected_cells(row["value"] / scale, 2.0 * std[name] / scale)
        assert f"{name}\n{v_text}\n{u_text}\n{unit_text}" in text, name
    assert "the parameters hold at T0 = 25 °C" in " ".join(text.split())


def test_a_unit_report_states_each_temperature_model_and_draws_them(small):
    unit = small.batch.results[1]
    doc = build_report(unit)
    results = doc.section("5.")
    models = next(t for t in results.tables if t.title.startswith("temperature models"))
    assert [r[0] for r in models.rows] == list(unit.models)  # one row per parameter
    for row in models.rows:
        fit, check = unit.models[row[0]], unit.held_out[row[0]]
        assert row[1] == f"{fit.order} ({fit.criterion.upper()})"
        assert row[3] == f"{fit.quality.reduced_chi2:.3g}"
        assert row[4].startswith("consistent" if check.consistent else "NOT consistent")
        assert f"p = {check.p_value:.2g}" in row[4]
    (figure,) = results.figures
    assert figure.png.startswith(b"\x89PNG") and "internal temperature" in figure.caption
    errors = next(t for t in results.tables if "largest error after compensation" in t.title)
    # the plan's accuracy for the consumer grade (docs/p2.md): 0.01 g and 0.5 °/s
    assert unit.error_limits == pytest.approx({"accel_mps2": 0.01 * 9.80665,
                                               "gyro_rps": math.radians(0.5)})
    assert errors.rows[0][2] == "10 mg" and errors.rows[1][2] == "0.5 °/s"
    for row, key in zip(errors.rows, ("accel_mps2", "gyro_rps"), strict=True):
        ok = unit.compensated_error[key] <= unit.error_limits[key]
        assert row[3] == ("pass" if ok else "FAIL")
    # the unit's result file alone (imucalib report RESULT) states the same models
    bare = build_report(load_result(small.out / "small.U1.p2.result.json"))
    again = next(t for t in bare.section("5.").tables if t.title.startswith("temperature"))
    assert again.rows == models.rows
    assert any("T0 = 25 °C" in p for p in bare.section("4.").paragraphs)
    # the figure is in the PDF too (an image on some page)
    images = sum(len(p.images) for p in
                 PdfReader(str(small.out / "small.U1.p2.report.pdf")).pages)
    assert images >= 1


def test_the_summary_has_one_row_per_unit_with_its_report_id(small):
    failed = failed_unit("U9", MissingSegmentError("temperature point 0 lost to dropouts"))
    batch = P2BatchResult(small.batch.recordings, (*small.batch.results, failed))
    doc = build_summary_report(batch)
    assert re.fullmatch(r"IMUCAL-P2-array-[0-9a-f]{12}", doc.report_id)
    table = next(t for t in doc.section("5.").tables if t.title == "per unit")
    rows = {r[0]: r for r in table.rows}
    assert set(rows) == {"U0", "U1", "U2", "U9"}
    for unit in small.batch.results:
        assert rows[unit.unit][1] == ("pass" if unit.passed else "FAIL")
        assert rows[unit.unit][5] == build_report(unit).report_id
    assert rows["U9"][1] == "not calibrated" and "dropouts" in rows["U9"][5]
    n_pass = sum(1 for u in small.batch.results if u.passed)
    assert f"{n_pass} of 4 unit(s) pass." in doc.section("5.").paragraphs
    conclusion = " ".join(doc.section("6.").paragraphs)
    assert conclusion.startswith("Decision: FAIL") and "U9" in conclusion
    assert "not a certificate of any unit" in conclusion
    assert doc.section("5.").figures  # the lot figure (three calibrated units)
    with pytest.raises(Exception, match="one report per unit"):
        build_report(batch)
    with pytest.raises(Exception, match="could not be calibrated"):
        build_report(failed)
    text = " ".join(_text(small.out / "small.array.p2.summary.report.pdf").split())
    assert "IMUs of an array calibrated together by procedure P2" in text
    assert "1. Object: the units calibrated" in text


def test_the_cli_reports_an_array_and_a_records_run_with_its_review(small, tmp_path):
    runner = CliRunner()
    recording = tmp_path / "arr.h5"
    recording.write_bytes(small.recording.read_bytes())
    db = f"sqlite:///{tmp_path / 'records.db'}"
    # recorded as `imucalib calibrate` records it (the analysis made once, in the fixture)
    assert "recorded run 1, result(s) 1, 2, 3" in record_calibration(small.batch, recording,
                                                                      db=db)
    assert runner.invoke(app, ["records", "review", "2", "--user", "qa-lead", "--decision",
                               "approve", "--db", db]).exit_code == 0
    run = runner.invoke(app, ["report", "--run", "1", "--db", db, "--out",
                              str(tmp_path / "rep"), "--format", "html"])
    assert run.exit_code == 0, run.output
    pages = {p.name: p.read_text(encoding="utf-8") for p in (tmp_path / "rep").iterdir()}
    assert set(pages) == {"arr.U0.p2.report.html", "arr.U1.p2.report.html",
                          "arr.U2.p2.report.html", "arr.array.p2.summary.report.html"}
    u1 = pages["arr.U1.p2.report.html"]
    assert re.search(r"IMUCAL-P2-U1-[0-9a-f]{12}\b", u1)
    assert not re.search(r"IMUCAL-P2-U1-[0-9a-f]{12}-R", u1)  # one id in every path
    assert "<td>records</td><td>run 1, result 2</td>" in u1  # the records ids, not in the id
    assert "approved by qa-lead" in u1
    assert "Review status: not reviewed (records result 1 has no review)" in \
        pages["arr.U0.p2.report.html"]
    assert re.search(r"IMUCAL-P2-U1-[0-9a-f]{12}", pages["arr.array.p2.summary.report.html"])
    # the recording changed since it was recorded: refused, naming both hashes
    with open(recording, "ab") as fh:
        fh.write(b"\0")
    bad = runner.invoke(app, ["report", "--run", "1", "--db", db])
    assert bad.exit_code != 0 and "has changed since it was recorded" in bad.output
    assert "Traceback" not in bad.output
    neither = runner.invoke(app, ["report"])
    assert neither.exit_code != 0 and "got neither" in neither.output


def test_three_calibration_points_allow_only_constant_models_and_the_report_says_so(small):
    """AICc (Eq. (6)) is infinite for a line through 3 points: every model is a constant, most
    do not fit, and the analysis and the report say what to do."""
    unit = small.batch.results[2]
    misfits = [n for n, m in unit.models.items() if m.quality.misfit]
    assert misfits and all(unit.models[n].order == 0 for n in misfits)
    note = next(n for n in unit.notes if "do not fit their points" in n)
    assert f"the temperature models of {len(misfits)} parameter(s)" in note
    assert "with 3 calibration points AICc (Eq. (6)) allows no higher order" in note
    doc = build_report(unit)
    assert f"Note: {note}" in doc.section("4.").paragraphs
    # the terminal says it too (`imucalib calibrate`)
    from rich.console import Console

    from imucalib.procedures.p2.console import render_p2

    console = Console(record=True, width=200)
    render_p2(console, small.batch, [])
    assert f"note (U2): {note}" in " ".join(console.export_text().split())
    assert any("consider a fuller model" in p for p in doc.section("6.").paragraphs)


def test_the_p2_sigma_are_scaled_once(small):
    """The P2 covariance holds its Birge ratios already: no fit quality rescales it (docs/p2.md)."""
    for unit in small.batch.results:
        cal = unit.result
        assert cal.fit_quality == () and cal.std(scaled=True) == cal.std()
        worst = [p for p in build_report(unit).section("4.").paragraphs
                 if p.startswith("worst point fit, ")]
        assert [w.split(", ")[1].split(":")[0] for w in worst] == ["gyro", "accel"]
