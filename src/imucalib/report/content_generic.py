"""The report of any result with parameters: every parameter with its U, the checks, the decision.

The ``report_content`` hook of a procedure without content of its own delegates here, and so
does one with its own for a calibration result read back from its JSON file; the procedure
passes its description, its documentation page and, when its references are its own, its
traceability statement (this module names no procedure). The rows come from the result's
``parameter_rows()`` (name, value, u, unit) or, for a bare
:class:`~imucalib.models.result.CalibrationResult`, from its parameters (u Birge-scaled under a
misfit).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from imucalib.errors import InvalidInputError
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


def _rows(result: Any, cal: Any) -> list[tuple[str, str, str, str]]:
    """(parameter, value, U, unit) rows, each in the display unit of its kind of quantity."""
    from imucalib.report.console import display_parameter

    rows_of = getattr(result, "parameter_rows", None)
    if callable(rows_of):
        items = [(str(n), float(v), float(s), str(u)) for n, v, s, u in rows_of()]
    elif callable(getattr(cal, "std", None)) and hasattr(cal, "param_names"):
        std = cal.std(scaled=True)  # a calibration result without a procedure's analysis
        items = [(n, cal.value(n), std[n], cal.units[n]) for n in cal.param_names]
    else:
        raise InvalidInputError(f"a {result.procedure} result has no parameter rows: no report "
                                "can be built from it")
    return [(name, *display_parameter(name, value, COVERAGE_FACTOR * sigma, unit))
            for name, value, sigma, unit in items]


def _process(result: Any, cal: Any, description: str | None, documentation: str
             ) -> tuple[list[str], bool]:
    """Return the process paragraphs (the procedure, each fit's χ²/ν) and the misfit flag."""
    name = str(result.procedure)
    text = f"Procedure {name}: {description}" if description is not None else f"Procedure {name}"
    paragraphs = [f"{text.rstrip('.')} ({documentation})."]
    quality = tuple(result.fit_quality)  # a procedure's result, or a CalibrationResult read back
    paragraphs += [q.summary() for q in quality]
    misfit = any(q.misfit for q in quality)
    paragraphs += [f"Note: {n}" for n in getattr(result, "notes", ()) or ()]
    return paragraphs, misfit


def content(result: Any, meta: Mapping[str, Any], *, description: str | None = None,
            documentation: str = "its documentation",
            traceability: str | None = None) -> ReportContent:
    """Return sections 1–5 of any result with parameters (module docstring).

    Parameters
    ----------
    result : ProcedureResult
        With ``parameter_rows()``, or a ``CalibrationResult`` as ``result``.
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
    cal: Any = getattr(result, "result", None)
    prov = getattr(cal, "provenance", None) or getattr(result, "provenance", None)
    table = ReportTable(f"{result.procedure} results of {result.unit}",
                        ("parameter", "value", f"U (k = {COVERAGE_FACTOR:g})", "unit"),
                        tuple(_rows(result, cal)))
    passed = result.passed
    decision = {None: "No conformity decision was made.",
                True: "Every assessed check passed.", False: "A check failed."}[passed]
    reasons = list(getattr(result, "reasons", ()) or ())
    process, misfit = _process(result, cal, description, documentation)
    details = dict(getattr(prov, "details", {}) or {})
    tables = [table]
    if getattr(cal, "temperature_models", None):
        tables.append(temperature_model_table(cal))
        process.append(f"The parameters hold at T0 = {cal.reference_temperature_degc:g} °C; "
                       "each temperature model (T1) gives them at other temperatures.")
    sections = (
        object_section(details.get("unit", {"serial": result.unit}), str(result.unit)),
        equipment_section(meta, None, getattr(prov, "software_version", "") or "—",
                          statement=traceability),
        environment_section(meta, {}),
        Section(SECTION_TITLES[3], tuple(process)),
        Section(SECTION_TITLES[4], (u_paragraph(), *reasons), tuple(tables)),
    )
    recs = recommendations(passed, reasons, (), misfit)
    return ReportContent(sections, decision, passed, tuple(recs), prov)
