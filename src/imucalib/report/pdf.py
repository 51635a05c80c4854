"""The calibration report as PDF: :func:`write_report_pdf` (reportlab platypus).

Every page carries the report's unique id in its header and ``page n of N`` in its footer
(ISO/IEC 17025:2017 §7.8.2.1 b: "a unique identification ... on each page ... and a clear
identification of the end"); N is known only after the whole document is laid out, so the
page furniture is drawn by a canvas that keeps every page until the end (:class:`_NumberedCanvas`).
A report not released (a DRAFT, :attr:`~imucalib.report.document.ReportDocument.watermark`)
carries "DRAFT" across every page and in every header. The certificate's heading
(:mod:`imucalib.report.certificate`) comes first, before section 1.
Text is set in DejaVu Sans (shipped with matplotlib), which has the µ, °, σ, χ and ± the tables
use. reportlab and matplotlib are imported inside the functions.

Contents
--------
:func:`write_report_pdf`
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape

from imucalib.report.document import ReportDocument

__all__ = ["write_report_pdf"]

_FONT = "ImucalibSans"
_FONT_BOLD = "ImucalibSans-Bold"


def _register_fonts() -> None:
    import matplotlib
    from reportlab.lib.fonts import addMapping
    from reportlab.pdfbase import pdfmetrics
    from reportlab.pdfbase.ttfonts import TTFont

    if _FONT in pdfmetrics.getRegisteredFontNames():
        return
    ttf = Path(matplotlib.get_data_path()) / "fonts" / "ttf"
    pdfmetrics.registerFont(TTFont(_FONT, str(ttf / "DejaVuSans.ttf")))
    pdfmetrics.registerFont(TTFont(_FONT_BOLD, str(ttf / "DejaVuSans-Bold.ttf")))
    addMapping(_FONT, 0, 0, _FONT)
    addMapping(_FONT, 1, 0, _FONT_BOLD)
    addMapping(_FONT, 0, 1, _FONT)
    addMapping(_FONT, 1, 1, _FONT_BOLD)


def _numbered_canvas(report_id: str, title: str, watermark: str = "") -> Any:
    from reportlab.lib.units import mm
    from reportlab.pdfgen import canvas

    class _NumberedCanvas(canvas.Canvas):
        """Keeps each page's state, then draws header and footer once N is known."""

        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            self._pages: list[dict[str, Any]] = []

        def showPage(self) -> None:  # reportlab's name
            self._pages.append(dict(self.__dict__))
            self._startPage()

        def save(self) -> None:
            total = len(self._pages)
            for n, state in enumerate(self._pages, start=1):
                self.__dict__.update(state)
                width, height = self._pagesize
                if watermark:
                    self.saveState()
                    self.setFillColorRGB(0.8, 0.1, 0.1)
                    self.setFillAlpha(0.15)
                    self.setFont(_FONT_BOLD, 120)
                    self.translate(width / 2, height / 2)
                    self.rotate(50)
                    self.drawCentredString(0, -40, watermark)
                    self.restoreState()
                self.setFont(_FONT, 8)
                self.drawString(15 * mm, height - 10 * mm, f"Report {report_id}"
                                + (f" — {watermark}" if watermark else ""))
                self.drawRightString(width - 15 * mm, height - 10 * mm, title[:70])
                self.line(15 * mm, height - 11.5 * mm, width - 15 * mm, height - 11.5 * mm)
                self.drawString(15 * mm, 8 * mm, f"{report_id}")
                self.drawRightString(width - 15 * mm, 8 * mm, f"page {n} of {total}")
                super().showPage()
            super().save()

    return _NumberedCanvas


def write_report_pdf(document: ReportDocument, path: str | os.PathLike[str]) -> Path:
    """Write the report as a PDF (module docstring) and return its path.

    Parameters
    ----------
    document : ReportDocument
        From :func:`~imucalib.exports.report.build_report`.
    path : str or Path
        The file to write.

    Returns
    -------
    Path
    """
    from reportlab.lib import colors
    from reportlab.lib.pagesizes import A4
    from reportlab.lib.styles import ParagraphStyle, getSampleStyleSheet
    from reportlab.lib.units import mm
    from reportlab.platypus import (
        Image,
        KeepTogether,
        Paragraph,
        SimpleDocTemplate,
        Spacer,
        Table,
        TableStyle,
    )

    _register_fonts()
    styles = getSampleStyleSheet()
    body = ParagraphStyle("body", parent=styles["BodyText"], fontName=_FONT, fontSize=9,
                          leading=11.5)
    cell = ParagraphStyle("cell", parent=body, fontSize=7.5, leading=9)
    head = ParagraphStyle("head", parent=styles["Heading2"], fontName=_FONT_BOLD, fontSize=12,
                          keepWithNext=1)
    sub = ParagraphStyle("sub", parent=body, fontName=_FONT_BOLD, fontSize=9, keepWithNext=1)
    title = ParagraphStyle("title", parent=styles["Title"], fontName=_FONT_BOLD, fontSize=15)
    out = Path(path)
    doc = SimpleDocTemplate(str(out), pagesize=A4, leftMargin=15 * mm, rightMargin=15 * mm,
                            topMargin=18 * mm, bottomMargin=16 * mm, title=document.title,
                            author="imucalib", subject=document.report_id)
    width = A4[0] - 30 * mm
    #: a figure may fill at most this much of the frame's height (its caption and spacing
    #: need the rest): a tall figure is scaled down to fit one page
    max_height = (A4[1] - 34 * mm) * 0.85
    story: list[Any] = [Paragraph(escape(document.title), title),
                        Paragraph(escape(f"Report id: {document.report_id}. Issued "
                                         f"{document.issued_utc}."), body)]
    if document.watermark:
        story.append(Paragraph(f"<b>{escape(document.watermark)}</b>: "
                               + escape("not released — this report is not a certificate "
                                        "until a reviewer has released it."), body))
    shown = (*((document.certificate,) if document.certificate is not None else ()),
             *document.sections)
    for section in shown:
        story.append(Paragraph(escape(section.title), head))
        story += [Paragraph(escape(p), body) for p in section.paragraphs]
        for table in section.tables:
            data = [[Paragraph(f"<b>{escape(h)}</b>", cell) for h in table.header]]
            data += [[Paragraph(escape(c), cell) for c in row] for row in table.rows]
            t = Table(data, repeatRows=1, hAlign="LEFT",
                      colWidths=[width / len(table.header)] * len(table.header)
                      if len(table.header) > 2 else [width * 0.4, width * 0.6])
            t.setStyle(TableStyle([("GRID", (0, 0), (-1, -1), 0.25, colors.grey),
                                   ("BACKGROUND", (0, 0), (-1, 0), colors.whitesmoke),
                                   ("VALIGN", (0, 0), (-1, -1), "TOP")]))
            story += [Spacer(1, 2 * mm), Paragraph(escape(table.title), sub), t]
        for fig in section.figures:
            img = Image(io.BytesIO(fig.png))
            scale = min(width / img.drawWidth, max_height / img.drawHeight, 1.0)
            img.drawWidth *= scale
            img.drawHeight *= scale
            story.append(KeepTogether([Spacer(1, 2 * mm), img,
                                       Paragraph(escape(fig.caption), cell)]))
        story.append(Spacer(1, 3 * mm))
    story.append(Paragraph(escape(f"End of report {document.report_id}."), body))
    doc.build(story, canvasmaker=_numbered_canvas(document.report_id, document.title,
                                                  document.watermark))
    return out
