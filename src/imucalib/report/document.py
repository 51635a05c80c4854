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

Before section 1 stands the certificate's heading, and the sections carry the certificate's
parts a procedure does not make (the laboratory, the customer, the calibration and issue dates,
the equipment with certificates, the uncertainty budget, the operator and the authorisation or
DRAFT status, "the results relate only to the item calibrated"): :mod:`imucalib.report.certificate`
and its :class:`~imucalib.report.certificate.CertificateFacts`.

The unique id (:func:`report_id`) is ``IMUCAL-<PROCEDURE>-<serial>-<hash>``, ``<hash>`` the first
12 hex digits of the SHA-256 of the result's canonical JSON without the analysis time
(``created_utc``), so the same result — the same recording analysed again by the same software
with the same options — always gets the same id and two results never one: the report written at
calibration time, ``imucalib report RESULT`` and ``imucalib report --run N`` carry the same id
(the records ids are stated in the certificate's heading, not in the id).

Each procedure's sections 1–5 are its :class:`ReportContent`, made by the procedure's
``report_content`` hook (:class:`~imucalib.procedures.common.procedure.Procedure`; a procedure
without content of its own delegates to :mod:`imucalib.report.content_generic`: every parameter
with its U, the checks and decision the result carries); :func:`assemble_report` adds the shared
conclusion and appendix (:mod:`imucalib.report.sections`). This module names no procedure: the
registry lookup that finds a result's procedure is :func:`imucalib.exports.report.build_report`.
A batch of units (an array or a production lot, P2) gets one report per unit and a summary
(its procedure's ``summary_report`` hook).

Contents
--------
:func:`assemble_report`, :func:`report_id`, :func:`issued_now`, :func:`no_summary_report`,
:class:`ReportDocument`, :class:`ReportContent`, :data:`ContentBuilder`, :class:`Section`,
:class:`ReportTable`, :class:`ReportFigure`, :class:`ReviewStatus`, :data:`SECTION_TITLES`,
:data:`COVERAGE_FACTOR`, :func:`write_report`
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, TypeAlias

from imucalib.models.procedure_result import ProcedureResult

if TYPE_CHECKING:
    from imucalib.report.certificate import CertificateFacts

__all__ = ["COVERAGE_FACTOR", "SECTION_TITLES", "ContentBuilder", "ReportContent",
           "ReportDocument", "ReportFigure", "ReportTable", "ReviewStatus", "Section",
           "assemble_report", "issued_now", "no_summary_report", "report_id", "write_report"]

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
    #: The certificate's heading, before section 1 (:mod:`imucalib.report.certificate`).
    certificate: Section | None = None
    #: Across every page ("DRAFT" until released); "" for none.
    watermark: str = ""

    def section(self, title_start: str) -> Section:
        """Return the section whose title starts with `title_start` (KeyError if none)."""
        for s in (*((self.certificate,) if self.certificate is not None else ()),
                  *self.sections):
            if s.title.startswith(title_start):
                return s
        raise KeyError(title_start)


# --- small helpers ---------------------------------------------------------------------------

def _canonical_json(data: Any) -> str:
    return json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=True, default=str)


def _without_analysis_time(data: Any) -> Any:
    """Drop every ``created_utc`` of `data` (when the analysis ran is not what it found)."""
    if isinstance(data, Mapping):
        return {k: _without_analysis_time(v) for k, v in data.items() if k != "created_utc"}
    if isinstance(data, list | tuple):
        return [_without_analysis_time(v) for v in data]
    return data


def report_id(result: ProcedureResult) -> str:
    """Return the report's unique id (module docstring): ``IMUCAL-P1-<serial>-<hash>``.

    The hash is of the result's ``to_dict()`` without analysis times, so a result read back
    from its file (whose ``details`` are that dict) gets the id of the report written with it,
    and the records' ids do not enter it: every path that reports a result gives one id.
    """
    from imucalib.models.result_document import json_data

    body = _without_analysis_time(json_data(result.to_dict()))
    digest = hashlib.sha256(_canonical_json(body).encode("utf-8")).hexdigest()[:12]
    serial = re.sub(r"[^A-Za-z0-9]+", "-", str(result.unit or "unit")).strip("-")
    return f"IMUCAL-{str(result.procedure).upper()}-{serial or 'unit'}-{digest}"


@dataclass(frozen=True)
class ReportContent:
    """A procedure's part of its report: sections 1–5 and what the conclusion needs.

    Attributes
    ----------
    sections : tuple of Section
        Object, equipment, environment, process, results (SECTION_TITLES[0:5]).
    decision : str
        The decision in words ("PASS. …"); the conclusion prefixes the verdict when missing.
    passed : bool or None
        The conformity decision (None: none made).
    recommendations : tuple of str
        The conclusion's recommendations.
    provenance : object
        ``recording``, ``recording_sha256``, ``plan_hash``, ``software_version``,
        ``created_utc`` for the appendix (any of them may be missing).
    plan : Plan, optional
        The plan, for its name in the appendix.
    type_b : mapping of str to float, optional
        The Type B standard uncertainty [SI] the analysis added to each parameter (a parameter
        absent: none), for the uncertainty budget; None: the procedure does not itemise it.
    """

    sections: tuple[Section, ...]
    decision: str
    passed: bool | None
    recommendations: tuple[str, ...]
    provenance: Any
    plan: Any = None
    type_b: Mapping[str, float] | None = None


#: A procedure's ``report_content(result, meta) -> ReportContent`` hook: `meta` the facts of the
#: recording (:func:`~imucalib.report.sections.recording_facts`).
ContentBuilder: TypeAlias = Callable[[Any, Mapping[str, Any]], ReportContent]


def issued_now() -> str:
    """Return the issue time of a report made now: ``"2026-01-02 10:00 UTC"``."""
    return datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")


def assemble_report(result: Any, content: ContentBuilder, *, recording: Any = None,
                    review: Any = None, result_id: int | None = None,
                    facts: CertificateFacts | None = None) -> ReportDocument:
    """Assemble the report of a procedure result from its procedure's content (module docstring).

    Parameters
    ----------
    result : ProcedureResult
        One unit's result: a P1 analysis, a P2 unit, a noise characterisation (Allan), a field
        calibration, any result of the contract
        (:class:`~imucalib.models.procedure_result.ProcedureResult`), one read back from its
        file included. A batch (``members``): its procedure's ``summary_report`` and one
        report per unit.
    content : callable
        Its procedure's ``report_content`` hook (:data:`ContentBuilder`): sections 1–5.
    recording : Recording or path, optional
        The recording analysed: its metadata and temperature column fill the environment
        section, the run's facts (operator, start, equipment) and the station (a twin's result
        is not traceable). Without it the conditions during the run are said to be unstated.
    review : ReviewStatus, records ``ReviewView``, mapping, or a sequence of them, optional
        The result's reviews from the records database; without: "not reviewed".
    result_id : int, optional
        The result's id in the records database (stated in the certificate's heading; the
        report id is the same with or without it).
    facts : CertificateFacts, optional
        What the certificate states beyond the result (the laboratory, the customer, the
        records' run, equipment and release; :mod:`imucalib.report.certificate`); default:
        none (a laboratory "not stated"), the recording's run facts, and a DRAFT unless the
        reviews release it.

    Returns
    -------
    ReportDocument

    Raises
    ------
    InvalidInputError
        A result the report cannot describe (no parameters, a unit that failed to calibrate,
        a batch), or a malformed review.
    """
    from dataclasses import replace

    from imucalib.errors import InvalidInputError
    from imucalib.report import certificate as cert
    from imucalib.report import sections as common

    if result.members:
        raise InvalidInputError("a batch of units gets one report per unit and a summary "
                                "(build_summary_report); build_report takes one unit's result")
    if result.error:
        raise InvalidInputError(f"unit {result.unit} could not be calibrated ({result.error}): "
                                "there is no result to report")
    meta = common.recording_facts(recording)
    made = content(result, meta)
    reviews = common.reviews_of(review)
    given = facts if facts is not None else cert.CertificateFacts()
    if given.records_result_id is None and result_id is not None:
        given = replace(given, records_result_id=int(result_id))
    if given.release is None:
        given = replace(given, release=cert.release_from_reviews(reviews))
    done = cert.complete(given, meta)
    sim = cert.simulated(meta)
    rid = report_id(result)
    issued = issued_now()
    prov = result.provenance
    details = dict(prov.details) if prov is not None else {}
    stated = details.get("unit") if isinstance(details.get("unit"), Mapping) else {}
    item = cert.identity(str(result.unit), meta, stated or {})
    sections = [_completed(s, i, done, item, result, made, sim)
                for i, s in enumerate(made.sections)]
    released = done.release is not None and done.release.released
    sections += [common.conclusion_section(made.decision, made.passed,
                                           list(made.recommendations), reviews,
                                           done.records_result_id,
                                           closing=cert.authorisation_lines(done)),
                 common.appendix(meta, made.plan, made.provenance, ())]
    verdict = {None: "no conformity decision", True: "PASS", False: "FAIL"}[made.passed]
    heading = cert.certificate_section(report_id=rid, issued=issued, facts=done, item=item,
                                       procedure=str(result.procedure), decision=verdict,
                                       sim=sim)
    title = f"Calibration report {rid}: {str(result.procedure).upper()} of {result.unit}"
    return ReportDocument(title=title, report_id=rid, issued_utc=issued,
                          sections=tuple(sections), passed=made.passed, certificate=heading,
                          watermark="" if released else "DRAFT")


def _completed(section: Section, index: int, facts: CertificateFacts, item: Mapping[str, str],
               result: Any, made: ReportContent, sim: bool | None) -> Section:
    """Add the certificate's parts to the procedure's section `index` (0 … 4)."""
    from dataclasses import replace

    from imucalib.report import certificate as cert

    if index == 0:  # the identification: what the result leaves blank, the recording says
        tables = tuple(ReportTable(t.title, t.header, tuple(
            (r[0], item[r[0]]) if len(r) == 2 and r[0] in ("model", "maker")
            and r[1] in ("", "—") and item[r[0]] != cert.NOT_STATED else r for r in t.rows))
            if t.title == "identification" else t for t in section.tables)
        return replace(section, tables=tables)
    if index == 1:  # equipment with certificates; a twin's result is never traceable
        table, lines = cert.equipment_table(facts)
        paragraphs = list(section.paragraphs)
        if sim and not any("NOT traceable" in p for p in paragraphs):
            from imucalib.report.sections import traceability

            paragraphs.insert(0, traceability("digital-twin"))
        return replace(section, paragraphs=(*paragraphs, *lines),
                       tables=section.tables + ((table,) if table is not None else ()))
    if index == 2 and (facts.site or facts.environment):
        rows = (*((f"laboratory site: {k}", v) for k, v in facts.site), *facts.environment)
        return replace(section, tables=(
            *section.tables, ReportTable("laboratory site and the run's environment (records)",
                                         ("quantity", "value"), tuple(rows))))
    if index == 4 and facts.show_budget:
        table = cert.budget_table(result.parameter_rows(), made.type_b)
        if not table.rows:
            return section
        note = ("The uncertainty budget: Type A from the fit of the data (the noise), Type B "
                "the station's contribution the analysis adds, the model misfit the Birge "
                "scaling of an inconsistent fit (√(u² − u₀²), u₀ the uncertainty before the "
                "scaling by √(χ²/ν)); they add in quadrature to the combined u, and U = 2u."
                + ("" if made.type_b is not None else
                   " This procedure does not itemise a Type B term (a dash): its Type A column "
                   "holds the whole uncertainty before the misfit scaling."))
        return replace(section, paragraphs=(*section.paragraphs, note),
                       tables=(*section.tables, table))
    return section


def no_summary_report(procedure: str) -> NoReturn:
    """Refuse a summary report: procedure `procedure`'s analysis returns no batch.

    The ``summary_report`` hook of a procedure whose ``analyze`` returns one unit's result.

    Raises
    ------
    InvalidInputError
        Always.
    """
    from imucalib.errors import InvalidInputError

    raise InvalidInputError(f"procedure {procedure} returns one unit's result, not a batch: "
                            "there is no summary report; build_report makes its report")


def write_report(document: ReportDocument, path: str | os.PathLike[str], fmt: str) -> Path:
    """Write `document` to `path` as ``fmt`` "pdf" (:mod:`imucalib.report.pdf`) or "html"."""
    if fmt == "pdf":
        from imucalib.report.pdf import write_report_pdf

        return write_report_pdf(document, path)
    if fmt == "html":
        from imucalib.report.html import write_report_html

        return write_report_html(document, path)
    from imucalib.errors import InvalidInputError

    raise InvalidInputError(f"a report is written as pdf or html; got {fmt!r}")
