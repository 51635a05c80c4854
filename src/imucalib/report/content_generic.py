"""The report of any result with parameters: every parameter with its U, the checks, the decision.

The ``report_content`` hook of a procedure without content of its own delegates here, and so
does one with its own for a calibration result read back from its JSON file; the procedure
passes its description, its documentation page and, when its references are its own, its
traceability statement (this module names no procedure). Everything comes from the result
contract (:class:`~imucalib.models.procedure_result.ProcedureResult`): the rows from
``parameter_rows()`` (u as reported: Birge-scaled under a misfit), the decision and its failed
checks, each fit's χ²/ν, the notes, the provenance and, with a calibration, its temperature
models.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from imucalib.errors import InvalidInputError
from imucalib.models.procedure_result import ProcedureResult
from imucalib.report.document import (
    COVERAGE_FACTOR,
    SECTION_TITLES,
    ReportContent,
    ReportTable,
    Section,
)
from imucalib.report.sections import (
    environment_section,
    equipment_section,
    object_section,
    recommendations,
    temperature_model_table,
    u_paragraph,
)

__all__ = ["content"]


def _rows(result: ProcedureResult) -> list[tuple[str, str, str, str]]:
    """(parameter, value, U, unit) rows, each in the display unit of its kind of quantity."""
    from imucalib.report.console import display_parameter

    rows = [r for r in result.parameter_rows() if math.isfinite(r.value)]
    if not rows:
        raise InvalidInputError(f"a {result.procedure} result has no parameter rows: no report "
                                "can be built from it")
    return [(r.name, *display_parameter(r.name, r.value, COVERAGE_FACTOR * r.std, r.unit))
            for r in rows]


def _process(result: ProcedureResult, description: str | None, documentation: str
             ) -> tuple[list[str], bool]:
    """Return the process paragraphs (the procedure, each fit's χ²/ν) and the misfit flag."""
    name = str(result.procedure)
    text = f"Procedure {name}: {description}" if description is not None else f"Procedure {name}"
    paragraphs = [f"{text.rstrip('.')} ({documentation})."]
    quality = tuple(result.fit_quality)
    paragraphs += [q.summary() for q in quality]
    misfit = any(q.misfit for q in quality)
    paragraphs += [f"Note: {n}" for n in result.notes]
    return paragraphs, misfit


def content(result: ProcedureResult, meta: Mapping[str, Any], *, description: str | None = None,
            documentation: str = "its documentation",
            traceability: str | None = None) -> ReportContent:
    """Return sections 1–5 of any result with parameters (module docstring).

    Parameters
    ----------
    result : ProcedureResult
        Of one unit, from an analysis or read back from its file.
    meta : mapping
        The recording's facts (:func:`~imucalib.report.sections.recording_facts`).
    description : str, optional
        The procedure's one-line description, quoted in the process section (None: the
        procedure's name only, e.g. a result of a procedure not installed here).
    documentation : str
        Where its method is described: ``"docs/<name>.md"`` for a built-in.
    traceability : str, optional
        The traceability statement of a procedure whose references are its own (default: the
        station's, :func:`~imucalib.report.sections.traceability`).

    Raises
    ------
    InvalidInputError
        A result without parameter rows.
    """
    cal = result.calibration
    prov = result.provenance
    table = ReportTable(f"{result.procedure} results of {result.unit}",
                        ("parameter", "value", f"U (k = {COVERAGE_FACTOR:g})", "unit"),
                        tuple(_rows(result)))
    verdict = result.decision
    passed = verdict.passed
    decision = (f"No conformity decision was made ({verdict.rule})." if passed is None
                else verdict.summary())
    reasons = list(verdict.failed)
    process, misfit = _process(result, description, documentation)
    details = dict(prov.details) if prov is not None else {}
    tables = [table]
    if verdict.checks:  # the decision's checks, as the result file keeps them
        from imucalib.report.sections import yes_no

        tables.append(ReportTable("checks of the decision", ("check", "verdict", "summary"),
                                  tuple((c.name, yes_no(c.passed), c.summary)
                                        for c in verdict.checks)))
    if cal is not None and cal.temperature_models:
        tables.append(temperature_model_table(cal))
        process.append(f"The parameters hold at T0 = {cal.reference_temperature_degc:g} °C; "
                       "each temperature model (T1) gives them at other temperatures.")
    sections = (
        object_section(details.get("unit", {"serial": result.unit}), str(result.unit)),
        equipment_section(meta, None, (prov.software_version if prov is not None else "") or "—",
                          statement=traceability),
        environment_section(meta, {}),
        Section(SECTION_TITLES[3], tuple(process)),
        Section(SECTION_TITLES[4], (u_paragraph(), *reasons,
                                    *((f"Decision rule: {verdict.rule}.",)
                                      if passed is not None else ())), tuple(tables)),
    )
    recs = recommendations(passed, reasons, verdict.not_assessed, misfit)
    return ReportContent(sections, decision, passed, tuple(recs), prov)
