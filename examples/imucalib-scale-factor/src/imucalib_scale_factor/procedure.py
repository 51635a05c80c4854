"""The scale-factor test as an imucalib procedure: the object the entry point names.

:data:`PROCEDURE` satisfies imucalib's ``Procedure`` protocol
(:class:`imucalib.procedures.common.procedure.Procedure`); the distribution declares it as

.. code-block:: toml

    [project.entry-points."imucalib.procedures"]
    scale-factor = "imucalib_scale_factor.procedure:PROCEDURE"

Importing this module imports neither the plan nor the analysis nor imucalib's report modules:
each is imported when first used, so that listing the procedures stays cheap. The result is
presented by imucalib's generic report content and terminal table (its ``parameter_rows()``):
the three presentation hooks delegate to them.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imucalib.procedures.common.options import option_names
from imucalib.procedures.common.procedure import accepted_options
from imucalib_scale_factor.options import (
    ScaleFactorAnalysisOptions,
    ScaleFactorPlanOptions,
)
from imucalib_scale_factor.roles import ROLES

if TYPE_CHECKING:
    from rich.console import Console

    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.report.document import ReportContent, ReportDocument
    from imucalib_scale_factor.analysis import ScaleFactorResult

__all__ = ["PROCEDURE", "ScaleFactorProcedure"]


class ScaleFactorProcedure:
    """One-axis gyro scale factor: turns about z at ±ω, y = K1·ω + b by weighted least squares."""

    name = "scale-factor"
    description = ("one-axis gyro scale factor (plug-in example): turns about the unit's z axis "
                   "at ±ω on a single-axis table; K1 and bias by weighted least squares")
    roles = ROLES
    plan_options_type = ScaleFactorPlanOptions
    plan_options = option_names(ScaleFactorPlanOptions)
    analysis_options_type = ScaleFactorAnalysisOptions
    analysis_options = option_names(ScaleFactorAnalysisOptions)
    outputs = ("result-json", "report-json", "parameters-csv", "report-pdf")

    def output_writers(self) -> Mapping[str, Callable[[Any, Path, str], list[Path]]]:
        """Return no output format of its own: the shared ones serve."""
        return {}

    def batch_outputs(self, batch: Any, folder: Path, stem: str) -> list[Path]:
        """Write nothing: this procedure makes no batch."""
        return []

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib_scale_factor.plan.generate_scale_factor_plan` of `options`."""
        from imucalib_scale_factor.plan import generate_scale_factor_plan

        return generate_scale_factor_plan(**options)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> ScaleFactorResult:
        """Run :func:`~imucalib_scale_factor.analysis.analyze_scale_factor`.

        `options` are those of the turn reduction (:attr:`analysis_options`).

        Raises
        ------
        InvalidInputError
            An option the analysis does not take.
        """
        from imucalib.procedures.common.rate_windows import RateProcessing
        from imucalib_scale_factor.analysis import analyze_scale_factor

        opts = accepted_options(self.name, options, self.analysis_options)
        result = analyze_scale_factor(recording, unit=unit, processing=RateProcessing(**opts))
        if progress is not None:
            progress(1.0)
        return result

    def analyze_many(self, recordings: Sequence[Recording | str | os.PathLike[str]], *,
                     units: Sequence[str] | None = None,
                     options: Mapping[str, Any] | None = None,
                     progress: Callable[[float], None] | None = None) -> ScaleFactorResult:
        """Refuse: one recording is one unit's test (no lot is calibrated together).

        Raises
        ------
        InvalidInputError
            Always.
        """
        from imucalib.errors import InvalidInputError

        raise InvalidInputError("the scale-factor test analyses one recording at a time")

    def report_content(self, result: Any, meta: Mapping[str, Any]) -> ReportContent:
        """Return the report's sections 1–5: imucalib's generic content of `result`.

        Its ``parameter_rows()`` with U = 2u, this procedure's description, the fit's χ²/ν.
        """
        from imucalib.report.content_generic import content

        return content(result, meta, description=self.description)

    def render_console(self, console: Console, result: Any, written: Sequence[Path]) -> None:
        """Print `result` with imucalib's generic table: its parameter rows and decision."""
        from imucalib.report.console import render_generic

        render_generic(console, result, written)

    def summary_report(self, batch: Any, *, recordings: Sequence[Any] | None = None,
                       report_ids: Mapping[str, str] | None = None) -> ReportDocument:
        """Refuse: the analysis returns one unit's result, never a batch.

        Raises
        ------
        InvalidInputError
            Always.
        """
        from imucalib.report.document import no_summary_report

        no_summary_report(self.name)


#: The procedure the entry point ``scale-factor`` names.
PROCEDURE = ScaleFactorProcedure()
