"""The calibration report of a procedure result, found through its procedure: :func:`build_report`.

The report framework (:mod:`imucalib.report.document`: the document model, the shared sections,
the PDF and HTML writers) names no procedure; each procedure makes its part in its own folder
through the hooks of :class:`~imucalib.procedures.common.procedure.Procedure`. This module joins
the two: it finds a result's procedure in the registry by the result's ``procedure`` name and
hands its hook to the framework — ``report_content`` for one unit's report (sections 1–5;
:func:`~imucalib.report.document.assemble_report` adds the conclusion and the appendix),
``summary_report`` for a batch's summary (P2: an array or a lot). A result of a procedure not
installed here gets the generic content (:mod:`imucalib.report.content_generic`); a result
read back from its file (:class:`~imucalib.models.result_document.StoredResult`: the contract
without the analysis behind it) goes to its procedure like any other, whose content falls back
to the generic one with the procedure's own description and traceability.

Contents
--------
:func:`build_report`, :func:`build_summary_report`
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from imucalib.models.procedure_result import ProcedureResult
from imucalib.report.document import ContentBuilder, ReportDocument, assemble_report

__all__ = ["build_report", "build_summary_report"]


def _content_of(procedure: str) -> ContentBuilder:
    """Return the ``report_content`` hook of procedure `procedure`, or the generic content."""
    from imucalib.errors import ConfigurationError
    from imucalib.procedures import registry

    try:
        return registry.get(procedure).report_content
    except ConfigurationError:  # not installed here, or broken: its parameters, generically
        from imucalib.report.content_generic import content

        return content


def build_report(result: ProcedureResult, *, recording: Any = None, review: Any = None,
                 result_id: int | None = None) -> ReportDocument:
    """Build the report of one unit's procedure result (module docstring).

    `result` is one unit's result (a batch: :func:`build_summary_report` and one report per
    unit); `recording`, `review` and `result_id` are those of
    :func:`~imucalib.report.document.assemble_report`, which builds the document from the
    content of `result`'s procedure.

    Raises
    ------
    InvalidInputError
        A result the report cannot describe (no parameters, a unit that failed to calibrate,
        a batch), or a malformed review.
    """
    return assemble_report(result, _content_of(result.procedure), recording=recording,
                           review=review, result_id=result_id)


def build_summary_report(batch: Any, *, recordings: Any = None,
                         report_ids: Mapping[str, str] | None = None) -> ReportDocument:
    """Build the summary report of a batch, an array or a production lot (one line per unit).

    The ``summary_report`` hook of `batch`'s procedure (P2:
    :func:`~imucalib.procedures.p2.summary_report.summary_report`, docs/reporting.md, "The
    summary of an array or a lot"), with the same arguments: the `recordings` analysed (for
    the environment section) and each unit's `report_ids` as issued.

    Raises
    ------
    InvalidInputError
        The procedure makes no batch.
    ConfigurationError
        The batch names an unregistered procedure.
    """
    from imucalib.procedures import registry

    return registry.get(str(batch.procedure)).summary_report(batch, recordings=recordings,
                                                             report_ids=report_ids)
