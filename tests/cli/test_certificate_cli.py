"""The certificate in every path of the command line (docs/reporting.md, "The certificate").

One twin P1 run is calibrated with ``imucalib calibrate`` (the calibration-time report) and
recorded in a records database with its station's equipment, operator, start time and customer;
``imucalib report RESULT --result-id N`` and ``imucalib report --run N`` must then give the same
report id, the result's own decision, the equipment with serials, certificate numbers and due
dates, the operator and the calibration date; a DRAFT on every page until a reviewer releases
it; "not traceable" for the twin in every path, and "not stated" (never "traceable") for a
result file without its recording; the laboratory from ``--config``. Read from the PDFs (pypdf).
"""

from __future__ import annotations

import re
import shutil
from datetime import UTC, date, datetime
from pathlib import Path
from types import SimpleNamespace

import pytest
from pypdf import PdfReader
from typer.testing import CliRunner

from imucalib.cli import app
from imucalib.models.result_document import load_result
from imucalib.records import open_records
from imucalib.report.certificate import RELATES_ONLY

LAB_TOML = """
[laboratory]
name = "Inertial Lab"
address = "1 Example Street, Town"

[certificate]
statements = ["Not to be reproduced except in full without the laboratory's approval."]
"""


def _pages(pdf: Path) -> list[str]:
    return [" ".join(p.extract_text().split()) for p in PdfReader(str(pdf)).pages]


def _ids(pages: list[str]) -> set[str]:
    return set(re.findall(r"IMUCAL-P1-IMU-0001-[0-9a-f]{12}(?:-R\d+)?", " ".join(pages)))


def _every_page(pages: list[str], rid: str, *, draft: bool) -> None:
    for n, text in enumerate(pages, start=1):
        assert rid in text and f"page {n} of {len(pages)}" in text
        assert ("DRAFT" in text) is draft, n


@pytest.fixture(scope="module")
def calibrated(consumer_run: Path, tmp_path_factory: pytest.TempPathFactory) -> SimpleNamespace:
    folder = tmp_path_factory.mktemp("certificate-cli")
    recording = folder / "c.h5"
    shutil.copy(consumer_run, recording)
    config = folder / "lab.toml"
    config.write_text(LAB_TOML, encoding="utf-8")
    done = CliRunner().invoke(app, ["calibrate", str(recording), "--no-record", "--config",
                                    str(config)])
    assert done.exit_code == 0, done.output
    pdf = folder / "c.IMU-0001.p1.report.pdf"
    pages = _pages(pdf)
    (rid,) = _ids(pages)
    return SimpleNamespace(folder=folder, recording=recording, config=config, pages=pages,
                           rid=rid, result=folder / "c.IMU-0001.p1.result.json")


@pytest.fixture
def recorded(calibrated: SimpleNamespace, tmp_path: Path) -> SimpleNamespace:
    """The run and its result in a fresh records database, with the station's equipment."""
    db = f"sqlite:///{tmp_path / 'records.db'}"
    with open_records(db) as records:
        records.add_station("bench-1")
        table = records.add_equipment("bench-1", "rotation table", "AC-2", "T-42",
                                      "CERT-2025-17", calibrated_on=date(2025, 6, 30),
                                      due_on=date(2026, 6, 30))
        run_id = records.record_run(plan_name="p1-dual-axis", procedure="p1",
                                    recording=calibrated.recording, operator="J. Doe",
                                    station="bench-1", equipment=[table],
                                    started_utc=datetime(2026, 1, 5, 9, 0, tzinfo=UTC),
                                    environment={"customer": "ACME GmbH"})
        result_id = records.record_result(run_id, load_result(calibrated.result), passed=True,
                                          serial="IMU-0001")
    return SimpleNamespace(db=db, run_id=run_id, result_id=result_id, out=tmp_path)


def _report(*args: str) -> str:
    done = CliRunner().invoke(app, ["report", *args])
    assert done.exit_code == 0, done.output
    assert "Traceback" not in done.output
    return done.output


def test_calibrate_writes_a_draft_certificate_of_the_laboratory(calibrated):
    pages = calibrated.pages
    _every_page(pages, calibrated.rid, draft=True)
    flat = " ".join(pages)
    assert "laboratory Inertial Lab address 1 Example Street, Town" in flat
    assert "Not to be reproduced except in full without the laboratory's approval." in flat
    assert RELATES_ONLY in flat
    assert "traceability NOT traceable: simulated station (digital twin)" in flat
    assert "NOT traceable to the SI" in flat
    assert "uncertainty budget" in flat and "decision PASS" in flat
    assert "status DRAFT: not released" in flat


def test_calibrate_into_another_folder_still_knows_the_station(calibrated, tmp_path):
    done = CliRunner().invoke(app, ["calibrate", str(calibrated.recording), "--no-record",
                                    "-o", str(tmp_path / "elsewhere")])
    assert done.exit_code == 0, done.output
    pages = _pages(tmp_path / "elsewhere" / "c.IMU-0001.p1.report.pdf")
    assert _ids(pages) == {calibrated.rid}
    flat = " ".join(pages)
    assert "traceability NOT traceable: simulated station" in flat
    assert "laboratory not stated" in flat  # no --config: the session's empty configuration


def test_every_path_gives_the_same_id_the_decision_and_the_records_facts(calibrated, recorded):
    out = recorded.out
    said = _report(str(calibrated.result), "--result-id", str(recorded.result_id), "--db",
                   recorded.db, "-o", str(out / "r.pdf"), "--config", str(calibrated.config),
                   "--customer", "Customer Two")
    assert f"(report {calibrated.rid}, DRAFT: not released)" in said
    _report("--run", str(recorded.run_id), "--db", recorded.db, "-o", str(out / "run"),
            "--config", str(calibrated.config))
    by_result = _pages(out / "r.pdf")
    by_run = _pages(out / "run" / "c.IMU-0001.p1.report.pdf")
    for pages in (by_result, by_run):
        assert _ids(pages) == {calibrated.rid}  # one id in every path
        _every_page(pages, calibrated.rid, draft=True)
        flat = " ".join(pages)
        # the result's own decision, not "no conformity decision"
        assert "decision PASS" in flat and "Decision: PASS" in flat
        assert "no conformity decision" not in flat
        # the records' run: equipment with serial, certificate and due date; operator; date
        assert "rotation table AC-2 T-42 CERT-2025-17 2026-06-30" in flat
        assert "operator J. Doe" in flat and "Operator: J. Doe." in flat
        assert "calibration date 2026-01-05 09:00 UTC" in flat
        assert f"records run {recorded.run_id}, result {recorded.result_id}" in flat
        assert "laboratory Inertial Lab" in flat and RELATES_ONLY in flat
        # the twin: not traceable, in every path
        assert "traceability NOT traceable: simulated station" in flat
        assert "NOT traceable to the SI" in flat and "traceable to the SI through" not in flat
        assert "uncertainty budget" in flat
    assert "customer Customer Two" in " ".join(by_result)  # --customer
    assert "customer ACME GmbH" in " ".join(by_run)  # the run's


def test_a_reviewers_approval_releases_the_certificate(calibrated, recorded):
    with open_records(recorded.db) as records:
        records.add_user("Ada Admin", "AA", role="admin")
        records.add_user("Q. Lead", "QL", role="reviewer", by="Ada Admin")
        records.review(recorded.result_id, "Q. Lead", True, "checked against the plan")
    out = recorded.out
    said = _report("--run", str(recorded.run_id), "--db", recorded.db, "-o", str(out / "rel"))
    assert f"(report {calibrated.rid})" in said and "DRAFT" not in said
    pages = _pages(out / "rel" / "c.IMU-0001.p1.report.pdf")
    _every_page(pages, calibrated.rid, draft=False)
    flat = " ".join(pages)
    assert "status released: authorised by Q. Lead on " in flat
    assert "Authorisation: released — authorised by Q. Lead, decision approve" in flat
    assert "checked against the plan" in flat
    assert "NOT traceable: simulated station" in flat  # released, and still not traceable
    _report(str(calibrated.result), "--result-id", str(recorded.result_id), "--db",
            recorded.db, "-o", str(out / "rel.pdf"))
    again = _pages(out / "rel.pdf")
    _every_page(again, calibrated.rid, draft=False)


def test_a_result_file_without_its_recording_does_not_claim_traceability(calibrated, tmp_path):
    alone = tmp_path / "c.IMU-0001.p1.result.json"
    shutil.copy(calibrated.result, alone)
    _report(str(alone), "-o", str(tmp_path / "alone.pdf"))
    pages = _pages(tmp_path / "alone.pdf")
    assert _ids(pages) == {calibrated.rid}
    flat = " ".join(pages)
    assert "Traceability: not stated." in flat
    assert "traceability not stated: the recording" in flat
    assert "traceable to the SI through" not in flat
    # beside its recording (as calibrate writes it) the twin is named
    _report(str(calibrated.result), "-o", str(tmp_path / "beside.pdf"))
    assert "NOT traceable: simulated station" in " ".join(_pages(tmp_path / "beside.pdf"))


def test_a_bad_configuration_is_refused_in_one_line(calibrated, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[site]\nlatitude_deg = 'north'\n", encoding="utf-8")
    for args in (["report", str(calibrated.result), "-o", str(tmp_path / "x.pdf")],
                 ["calibrate", str(calibrated.recording), "--no-record", "-o",
                  str(tmp_path / "cal")]):
        done = CliRunner().invoke(app, [*args, "--config", str(bad)])
        assert done.exit_code != 0
        assert "Traceback" not in done.output
        text = " ".join(done.output.split())
        assert f"laboratory configuration {bad}: [site] latitude_deg" in text, text
    missing = CliRunner().invoke(app, ["report", str(calibrated.result), "--config",
                                       str(tmp_path / "none.toml")])
    assert missing.exit_code != 0 and "no such file" in missing.output
    assert "Traceback" not in missing.output


def test_both_formats_in_one_call_are_the_same_report(calibrated, recorded):
    """``--format pdf,html`` analyses the run once and writes one report, with one id, twice."""
    out = recorded.out / "both"
    said = _report("--run", str(recorded.run_id), "--db", recorded.db, "-o", str(out),
                   "--format", "pdf,html", "--config", str(calibrated.config))
    pdf, html = out / "c.IMU-0001.p1.report.pdf", out / "c.IMU-0001.p1.report.html"
    assert said.count(f"(report {calibrated.rid}") == 2
    assert _ids(_pages(pdf)) == {calibrated.rid}
    text = html.read_text(encoding="utf-8")
    assert calibrated.rid in text and "<td>decision</td><td>PASS</td>" in text
    bad = CliRunner().invoke(app, ["report", "--run", str(recorded.run_id), "--db",
                                   recorded.db, "--format", "pdf,docx"])
    assert bad.exit_code != 0 and "--format must be pdf, html or pdf,html; got 'pdf,docx'" in (
        " ".join(bad.output.split()))
