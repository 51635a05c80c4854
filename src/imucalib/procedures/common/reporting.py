"""The generic report and terminal hooks, for a procedure without presentation of its own.

A procedure presents its result through three hooks of
:class:`~imucalib.procedures.common.procedure.Procedure`: ``report_content`` (sections 1–5 of its
report), ``render_console`` (the terminal) and ``summary_report`` (a batch's summary). A built-in
procedure without its own (the classical tests, tumble) inherits :class:`GenericReporting`, which
delegates to the generic ones of :mod:`imucalib.report`:

- ``report_content``: :func:`imucalib.report.content_generic.content` — every parameter of
  ``parameter_rows()`` (or of a ``CalibrationResult``) with its U, the procedure's description and
  its page ``docs/<name>.md``, each fit's χ²/ν, the notes and failed checks;
- ``render_console``: :func:`imucalib.report.console.render_generic`;
- ``summary_report``: refused (:func:`imucalib.report.document.no_summary_report`): its analysis
  returns one unit's result, not a batch.

A procedure with its own content, table or batch overrides the hook and keeps its code in its
folder (``report.py``, ``console.py``, ``figures.py``); a plug-in calls the same generic functions
(docs/plugins.md). The report modules are imported when a hook is called, so that importing a
procedure (listing the registry) imports no report code.

Contents
--------
:class:`GenericReporting`
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rich.console import Console

    from imucalib.report.document import ReportContent, ReportDocument

__all__ = ["GenericReporting"]


class GenericReporting:
    """The generic ``report_content``, ``render_console`` and ``summary_report`` of a built-in.

    Attributes
    ----------
    name : str
        The procedure's registry name (its documentation page is ``docs/<name>.md``).
    description : str
        Its one line, quoted in the report's process section.
    """

    name: str
    description: str

    def report_content(self, result: Any, meta: Mapping[str, Any]) -> ReportContent:
        """Return the generic sections 1–5 of `result` (module docstring).

        Raises
        ------
        InvalidInputError
            A result without parameter rows.
        """
        from imucalib.report.content_generic import content

        return content(result, meta, description=self.description,
                       documentation=f"docs/{self.name}.md")

    def render_console(self, console: Console, result: Any, written: Sequence[Path]) -> None:
        """Print `result`'s parameter rows, its decision and the files written (generic)."""
        from imucalib.report.console import render_generic

        render_generic(console, result, written)

    def summary_report(self, batch: Any, *, recordings: Sequence[Any] | None = None,
                       report_ids: Mapping[str, str] | None = None) -> ReportDocument:
        """Refuse: this procedure's analysis returns no batch.

        Raises
        ------
        InvalidInputError
            Always.
        """
        from imucalib.report.document import no_summary_report

        no_summary_report(self.name)
