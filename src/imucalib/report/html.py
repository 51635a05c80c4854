"""The calibration report as one self-contained HTML page: :func:`write_report_html`.

The same :class:`~imucalib.report.document.ReportDocument` as the PDF
(:mod:`imucalib.report.pdf`): the unique id in the page's header and footer, the certificate's
heading, the six sections and the appendix, tables as ``<table>``, figures embedded as base64
PNG (``data:`` URIs), so the file needs nothing beside it. A report not released carries a
DRAFT banner under its header and "DRAFT" across the page.

Contents
--------
:func:`render_report_html`, :func:`write_report_html`
"""

from __future__ import annotations

import base64
import os
from html import escape
from pathlib import Path

from imucalib.report.document import ReportDocument

__all__ = ["render_report_html", "write_report_html"]

_STYLE = """
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; font-size: 14px;
       max-width: 60em; margin: 2em auto; color: #111; }
header, footer { font-size: 12px; color: #555; border-bottom: 1px solid #999; }
footer { border-top: 1px solid #999; border-bottom: none; margin-top: 2em; }
table { border-collapse: collapse; margin: 0.5em 0 1em 0; font-size: 12px; }
th, td { border: 1px solid #aaa; padding: 2px 6px; text-align: left; vertical-align: top; }
th { background: #f2f2f2; }
figure img { max-width: 100%; }
figcaption { font-size: 12px; }
.draft-banner { background: #b71c1c; color: #fff; font-weight: bold; padding: 0.4em 0.8em;
                margin: 0.5em 0; }
.watermark { position: fixed; top: 35%; left: 15%; font-size: 140px; font-weight: bold;
             color: rgba(183, 28, 28, 0.10); transform: rotate(-30deg); pointer-events: none; }
"""


def render_report_html(document: ReportDocument) -> str:
    """Return the report as an HTML document (module docstring)."""
    rid = escape(document.report_id)
    mark = escape(document.watermark)
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             f"<title>{escape(document.title)}</title><style>{_STYLE}</style></head>"
             + "<body>",
             f'<header>Report <span class="report-id">{rid}</span>'
             + (f" — {mark}" if mark else "") + "</header>"]
    if mark:
        parts.append(f'<div class="watermark" aria-hidden="true">{mark}</div>')
        parts.append(f'<div class="draft-banner">{mark}: not released — this report is not a '
                     "certificate until a reviewer has released it.</div>")
    parts += [f"<h1>{escape(document.title)}</h1>",
              f"<p>Report id: {rid}. Issued {escape(document.issued_utc)}.</p>"]
    shown = (*((document.certificate,) if document.certificate is not None else ()),
             *document.sections)
    for section in shown:
        parts.append(f"<section><h2>{escape(section.title)}</h2>")
        parts += [f"<p>{escape(p)}</p>" for p in section.paragraphs]
        for table in section.tables:
            parts.append(f"<h3>{escape(table.title)}</h3><table><thead><tr>"
                         + "".join(f"<th>{escape(h)}</th>" for h in table.header)
                         + "</tr></thead><tbody>")
            parts += ["<tr>" + "".join(f"<td>{escape(c)}</td>" for c in row) + "</tr>"
                      for row in table.rows]
            parts.append("</tbody></table>")
        for fig in section.figures:
            data = base64.b64encode(fig.png).decode("ascii")
            parts.append(f'<figure><img alt="{escape(fig.caption)}" '
                         f'src="data:image/png;base64,{data}">'
                         f"<figcaption>{escape(fig.caption)}</figcaption></figure>")
        parts.append("</section>")
    parts.append(f"<footer>End of report {rid}.</footer></body></html>")
    return "\n".join(parts) + "\n"


def write_report_html(document: ReportDocument, path: str | os.PathLike[str]) -> Path:
    """Write :func:`render_report_html` to `path` (UTF-8) and return the path."""
    out = Path(path)
    out.write_text(render_report_html(document), encoding="utf-8")
    return out
