"""The summary report of an array or a production lot: one line per unit, the lot's spread.

A batch (P2: every unit of one recording, an "array", or of several, a "lot";
:class:`~imucalib.procedures.p2.batch.P2BatchResult`) gets one report per calibrated unit
(:mod:`imucalib.procedures.p2.report`) and this summary, the ``summary_report`` hook of
:class:`~imucalib.procedures.p2.procedure.P2Procedure`: the units, the equipment and
conditions of the recordings, the process, a table with each unit's decision, the errors left
after compensation, the parameters furthest from the lot (in robust standard deviations,
1.4826·MAD), each unit's own report id, and the figure of every parameter across the units.
The summary is not a certificate of any unit: each unit's own report is (docs/reporting.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from imucalib import units
from imucalib.report.document import (
    SECTION_TITLES,
    ReportDocument,
    ReportTable,
    Section,
    issued_now,
    report_id,
)
from imucalib.report.sections import (
    appendix,
    environment_section,
    equipment_section,
    figure_of,
    recording_facts,
)

__all__ = ["summary_report"]


def _first_recording(batch: Any, recordings: Sequence[Any] | None) -> Any:
    if recordings:
        return recordings[0]
    for name in batch.recordings:
        if Path(name).is_file():
            return Path(name)
    return None


def _cell(value: float | None, scale: float, unit: str) -> str:
    return "—" if value is None else f"{value / scale:.3g} {unit}"


def summary_report(batch: Any, *, recordings: Sequence[Any] | None = None,
                   report_ids: Mapping[str, str] | None = None) -> ReportDocument:
    """Build the summary report of an array or a production lot (module docstring).

    Parameters
    ----------
    batch : P2BatchResult
        Every unit's result (``results``), with ``recordings`` and ``unit`` ("array"/"lot").
    recordings : sequence of Recording or path, optional
        The recordings analysed, for the environment section (the first one's conditions).
    report_ids : mapping of str to str, optional
        Each unit's report id as issued (with its records id); default:
        :func:`~imucalib.report.document.report_id` of the unit's result.

    Returns
    -------
    ReportDocument
        Sections: the units, equipment, environment, process, the per-unit table with each
        unit's report id, the lot figure, and the conclusion (docs/reporting.md).
    """
    from imucalib.procedures.p2.batch import held_out_units, summary_rows
    from imucalib.procedures.p2.figures import save_lot_figure

    issued = issued_now()
    meta = recording_facts(_first_recording(batch, recordings))
    rows = summary_rows(batch)
    by_unit = {r.unit: r for r in batch.results}
    done = [r for r in batch.results if r.result is not None]
    table_rows = []
    for row in rows:
        unit_result = by_unit[row["unit"]]
        verdict = ("not calibrated" if row["error"] else
                   "pass" if row["passed"] else "FAIL")
        table_rows.append((
            str(row["unit"]), verdict,
            _cell(row["accel_error_mps2"], units.G0_MPS2 * 1e-3, "mg"),
            _cell(row["gyro_error_rps"], units.DEG, "°/s"),
            "; ".join(row["worst_parameters"]) or "—",
            (report_ids or {}).get(str(row["unit"])) or report_id(unit_result)
            if unit_result.result is not None else row["error"]))
    n_pass = sum(1 for r in batch.results if r.passed)
    held = held_out_units(batch)
    held_text = ((f"{len(held)} of {len(batch.results)} unit(s) have temperature models NOT "
                  f"consistent at the held-out points ({', '.join(held)}): each unit's report "
                  "names them; P2's rule does not judge them (docs/p2.md, \"The decision\").",)
                 if held else ())
    failed = [r.unit for r in batch.results if not r.passed]
    kind, article = ("production lot", "a") if batch.unit == "lot" else ("array", "an")
    units_table = ReportTable("units", ("unit", "recording"),
                              tuple((r.unit, _recording_of(r)) for r in batch.results))
    prov = done[0].result.provenance if done else None
    sections = [
        Section("1. Object: the units calibrated",
                (f"The items are the {len(batch.results)} IMUs of {article} {kind} calibrated "
                 f"together by procedure {batch.procedure.upper()}; each has its own report.",),
                (units_table,)),
        equipment_section(meta, None, getattr(prov, "software_version", "") or "—"),
        environment_section(meta, {}),
        Section(SECTION_TITLES[3], (
            f"Procedure {batch.procedure.upper()} (docs/p2.md), every unit analysed on its own "
            f"from {len(batch.recordings)} recording(s). The parameters furthest from the lot "
            "are those whose value at T0 lies furthest from the lot's median, in robust "
            "standard deviations (1.4826·MAD), the three largest (three or more units).",)),
        Section(SECTION_TITLES[4],
                (f"{n_pass} of {len(batch.results)} unit(s) pass.", *held_text),
                (ReportTable("per unit", ("unit", "decision", "accel error after compensation",
                                          "gyro error after compensation",
                                          "furthest from the lot", "unit report id"),
                             tuple(table_rows)),),
                tuple(f for f in ([figure_of(lambda p: save_lot_figure(batch, p),
                                             "Every parameter at T0 across the units (green "
                                             "pass, red fail; 2σ bars; grey: the median).")]
                                  if len(done) >= 2 else []) if f is not None)),
    ]
    verdict = "PASS" if batch.passed else "FAIL"
    conclusion = [f"Decision: {verdict}: {n_pass} of {len(batch.results)} unit(s) pass"
                  + (f"; failed or not calibrated: {', '.join(failed)}" if failed else "")
                  + (f"; {len(held)} unit(s) with temperature models NOT consistent at the "
                     "held-out points (not part of P2's rule)" if held else "") + "."]
    conclusion.append("This summary is not a certificate of any unit: each unit's own report "
                      "(its id in the table) is, once reviewed.")
    if failed:
        conclusion.append("Recommendation: do not apply the calibration of a failed unit; "
                          "read its report for the failed check and repeat its run.")
    sections.append(Section(SECTION_TITLES[5], tuple(conclusion)))
    extra = tuple((f"recording {i + 1}", str(name)) for i, name in enumerate(batch.recordings))
    sections.append(appendix(meta, None, prov, extra))
    rid = report_id(batch)
    return ReportDocument(
        title=f"Summary report {rid}: {batch.procedure.upper()} {kind} of "
              f"{len(batch.results)} unit(s)",
        report_id=rid, issued_utc=issued, sections=tuple(sections), passed=batch.passed)


def _recording_of(unit_result: Any) -> str:
    cal = unit_result.result
    name = getattr(getattr(cal, "provenance", None), "recording", "") if cal else ""
    return str(name) or "—"
