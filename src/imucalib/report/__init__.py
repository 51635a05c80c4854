"""Report: figures and tables for the calibration report (matplotlib imported lazily).

Each block below is one feature's public API; see the module docstrings.

Contents
--------
:mod:`imucalib.report.allan_figure`
    :func:`plot_allan_triad`, :func:`save_allan_figures`.
:mod:`imucalib.report.noise_table`
    :func:`~imucalib.report.noise_table.format_noise_table` (the datasheet-style noise table).
:mod:`imucalib.report.console`
    The terminal rendering of procedure results.
:mod:`imucalib.report.numbers`
    A value with its uncertainty as text, GUM 7.2.6 rounding (docs/reporting.md).
:mod:`imucalib.report.document`
    The calibration report (certificate) as data: :func:`~imucalib.report.document.build_report`.
:mod:`imucalib.report.pdf`, :mod:`imucalib.report.html`
    The report as PDF (:func:`~imucalib.report.pdf.write_report_pdf`) and as one HTML page
    (:func:`~imucalib.report.html.write_report_html`).
"""

from __future__ import annotations

# --- allan ---
from imucalib.report.allan_figure import plot_allan_triad, save_allan_figures

# --- end allan ---

__all__ = [
    # --- allan ---
    "plot_allan_triad",
    "save_allan_figures",
    # --- end allan ---
]
