"""The demo's calibration report, read as a user reads it (issue: "the demo's report").

`python -m imucalib.demo --quick` (what `make demo` runs, with one repetition and a ten-minute
static record: about 7 s) ends by printing the PDF's path; the test opens that PDF, extracts its
text (pypdf) and finds every section, the report id and "page n of N" on every page, and every
parameter of the demo's report JSON printed as its value and U = 2u, rounded by the rule of
docs/reporting.md (the strings computed here, independently of imucalib.report).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from pypdf import PdfReader

from imucalib import demo
from imucalib.report.document import SECTION_TITLES

from ._gum import expected_cells, shown_p1


def test_the_demo_ends_with_a_report_that_prints_its_json_numbers(tmp_path: Path, capsys):
    code = demo.main(["--quick", "--out", str(tmp_path), "--no-record"])
    printed = " ".join(capsys.readouterr().out.split())
    assert code == 0, printed
    match = re.search(r"Calibration report \(PDF\): (\S+\.pdf)", printed)
    assert match, printed
    pdf = Path(match.group(1))
    assert pdf.parent == tmp_path.resolve()
    pages = [p.extract_text() for p in PdfReader(str(pdf)).pages]
    text = "\n".join(pages)
    rid = re.search(r"IMUCAL-P1-IMU-0001-[0-9a-f]{12}", pages[0])
    assert rid, pages[0][:300]
    for n, page in enumerate(pages, start=1):
        assert rid.group(0) in page and f"page {n} of {len(pages)}" in page
    for title in SECTION_TITLES:
        assert title in text
    report = json.loads((tmp_path / "p1-run.IMU-0001.p1.report.json").read_text(
        encoding="utf-8"))
    std = report["std_scaled"]
    assert len(report["result"]["parameters"]) == 33
    for row in report["result"]["parameters"]:
        shown, u, unit = shown_p1(row["name"], row["value"], std[row["name"]])
        v_text, u_text = expected_cells(shown, 2.0 * u)
        assert f"{row['name']}\n{v_text}\n{u_text}\n{unit}" in text, row["name"]
    verdict = "PASS" if report["decision"]["passed"] else "FAIL"
    assert f"Decision: {verdict}" in " ".join(text.split())
    # the truth table of step 4 holds every term the data may choose (K2 forced in here)
    from imucalib.calibration import calibrate
    from imucalib.io.opening import open_recording
    from imucalib.models.result import CalibrationResult

    rec_path = tmp_path / "p1-run.h5"
    done = calibrate(rec_path, procedure="p1", options={"terms": "+k2"},
                     out=tmp_path / "k2", record=False)
    saved = CalibrationResult.load(next(p for p in done.written
                                        if p.name.endswith(".result.json")))
    assert "accel_K2_z" in saved.param_names
    with open_recording(rec_path) as rec:
        table = demo._truth_table(saved, rec.truth)
    assert table.columns[0]._cells == [str(len(saved.param_names))]
