"""Report: the framework of the calibration report and of the terminal (matplotlib imported lazily).

This package names no procedure (docs/architecture.md, "Layers"): each procedure's report
content, figures and terminal table are in its folder (``procedures/<name>/report.py``,
``figures.py``, ``console.py``), reached through the hooks of
:class:`~imucalib.procedures.common.procedure.Procedure`; :mod:`imucalib.exports.report` finds a
result's procedure and builds its report.

Contents
--------
:mod:`imucalib.report.document`
    The calibration report (certificate) as data:
    :func:`~imucalib.report.document.assemble_report`, :class:`ReportDocument`,
    :class:`ReportContent` (a procedure's sections 1–5).
:mod:`imucalib.report.sections`
    The shared sections: object, equipment and traceability, environment, conclusion, appendix.
:mod:`imucalib.report.certificate`
    The certificate every report is: its heading, the equipment with certificates, the
    uncertainty budget, the authorisation or DRAFT, from plain facts
    (:class:`~imucalib.report.certificate.CertificateFacts`).
:mod:`imucalib.report.content_generic`
    Sections 1–5 of any result with parameters (a procedure without content of its own).
:mod:`imucalib.report.pdf`, :mod:`imucalib.report.html`
    The report as PDF (:func:`~imucalib.report.pdf.write_report_pdf`) and as one HTML page
    (:func:`~imucalib.report.html.write_report_html`).
:mod:`imucalib.report.numbers`
    A value with its uncertainty as text, GUM 7.2.6 rounding (docs/reporting.md).
:mod:`imucalib.report.console`
    The terminal's shared pieces: display units, the generic result table.
:mod:`imucalib.report.noise_table`
    :func:`~imucalib.report.noise_table.format_noise_table` (the datasheet-style noise table).
:mod:`imucalib.report.checks_figure`, :mod:`imucalib.report.noise_model_figure`,
:mod:`imucalib.report.drift_figure`, :mod:`imucalib.report.segments_figure`
    The shared figures: checks over their limits, a noise model's Allan deviation, drift
    across recalibrations, a log's segments.

Each is imported from its module (this package imports nothing eagerly).
"""
