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

Every report is a certificate (:mod:`imucalib.report.certificate`): the laboratory comes from
the laboratory configuration (:mod:`imucalib.config`, ``imucalib.toml``) through
:func:`laboratory_facts`, the method from the procedure (its description and documentation
page), and the records' run, equipment and release from the caller (``imucalib report``).

Contents
--------
:func:`build_report`, :func:`build_summary_report`, :func:`laboratory_facts`
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from imucalib.models.procedure_result import ProcedureResult
from imucalib.report.certificate import CertificateFacts
from imucalib.report.document import ContentBuilder, ReportDocument, assemble_report

if TYPE_CHECKING:
    from imucalib.config import LabConfig

__all__ = ["build_report", "build_summary_report", "laboratory_facts"]


def laboratory_facts(config: LabConfig | None = None, **given: Any) -> CertificateFacts:
    """Return the certificate's facts of the laboratory configuration, with `given` fields.

    Parameters
    ----------
    config : LabConfig, optional
        Default: :func:`imucalib.config.load_config` (the file ``--config`` named,
        ``$IMUCALIB_CONFIG``, ``./imucalib.toml`` or the user's; none: "not stated").
    **given
        Fields of :class:`~imucalib.report.certificate.CertificateFacts` (the customer, the
        records' operator, equipment, release …).

    Raises
    ------
    ConfigurationError
        A configuration file that cannot be read or has a bad field.
    """
    from imucalib.config import load_config

    lab = config if config is not None else load_config()
    site = lab.site
    rows = tuple((label, text) for label, text in (
        ("latitude", None if site.latitude_deg is None else f"{site.latitude_deg:g}°"),
        ("height", None if site.height_m is None else f"{site.height_m:g} m"),
        ("local gravity", None if site.gravity_mps2 is None else f"{site.gravity_mps2:.6f} m/s²"))
        if text is not None)
    return CertificateFacts(**{
        "laboratory": lab.laboratory.name, "address": lab.laboratory.address,
        "accreditation": lab.laboratory.accreditation, "site": rows,
        "show_budget": lab.certificate.show_budget,
        "statements": tuple(lab.certificate.statements), **given})


def _method(procedure: str) -> str:
    """Return the certificate's method: the procedure, its description and documentation."""
    from imucalib.errors import ConfigurationError
    from imucalib.procedures import registry

    try:
        proc = registry.get(procedure)
    except ConfigurationError:
        return f"procedure {procedure} (not installed here)"
    page = f"docs/{procedure}.md" if procedure in registry.BUILTIN else "its documentation"
    return f"procedure {procedure.upper()}: {proc.description.rstrip('.')} ({page})"


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
                 result_id: int | None = None, facts: CertificateFacts | None = None
                 ) -> ReportDocument:
    """Build the report of one unit's procedure result (module docstring).

    `result` is one unit's result (a batch: :func:`build_summary_report` and one report per
    unit); `recording`, `review`, `result_id` and `facts` are those of
    :func:`~imucalib.report.document.assemble_report`, which builds the document from the
    content of `result`'s procedure; `facts` default: :func:`laboratory_facts` (the
    laboratory configuration), the method the procedure's.

    Raises
    ------
    InvalidInputError
        A result the report cannot describe (no parameters, a unit that failed to calibrate,
        a batch), or a malformed review.
    ConfigurationError
        A laboratory configuration that cannot be read.
    """
    given = facts if facts is not None else laboratory_facts()
    if not given.method:
        given = replace(given, method=_method(str(result.procedure)))
    return assemble_report(result, _content_of(result.procedure), recording=recording,
                           review=review, result_id=result_id, facts=given)


def build_summary_report(batch: Any, *, recordings: Any = None,
                         report_ids: Mapping[str, str] | None = None) -> ReportDocument:
    """Build the summary report of a batch, an array or a production lot (one line per unit).

    The ``summary_report`` hook of `batch`'s procedure (docs/reporting.md, "The summary of an
    array or a lot"), with the same arguments: the `recordings` analysed (for
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
