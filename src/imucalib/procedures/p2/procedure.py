"""P2 as a :class:`~imucalib.procedures.common.procedure.Procedure` (registered as ``"p2"``).

The plan is :func:`~imucalib.procedures.p2.plan.generate_p2_plan`, its predicted uncertainty
:func:`~imucalib.procedures.p2.predict.predict_p2` (:meth:`P2Procedure.predict`) and its
optimiser :func:`~imucalib.procedures.p2.optimize.optimize_request`
(:meth:`P2Procedure.optimize_plan`, docs/test-design.md, "P2: temperature points"); the analysis
:func:`~imucalib.procedures.p2.batch.analyze_p2` (every unit of the array, each through
:func:`~imucalib.procedures.p2.analysis.analyze_unit`), imported when first used. With `unit`
given, only that unit is analysed; the result is a
:class:`~imucalib.procedures.p2.batch.P2BatchResult` either way.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imucalib.errors import InvalidInputError
from imucalib.procedures.common.defaults import ProcedureDefaults
from imucalib.procedures.common.options import option_names
from imucalib.procedures.common.procedure import accepted_options
from imucalib.procedures.p2.options import P2AnalysisOptions, P2PlanOptions
from imucalib.procedures.p2.roles import ROLES

if TYPE_CHECKING:
    from rich.console import Console

    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.common.prediction import (
        OptimizedPlan,
        OptimizeRequest,
        Prediction,
    )
    from imucalib.procedures.p2.batch import P2BatchResult
    from imucalib.report.document import ReportContent, ReportDocument

__all__ = ["PROCEDURE", "P2Procedure"]


class P2Procedure(ProcedureDefaults):
    """Procedure P2: array full-temperature calibration on a cube in a chamber."""

    name = "p2"
    description = ("array full-temperature calibration: IMUs on a cube in a thermal chamber on "
                   "a single-axis table, six orientations × static and ±ω at every "
                   "temperature, temperature models of every parameter")
    roles = ROLES
    plan_options_type = P2PlanOptions
    plan_options = option_names(P2PlanOptions)
    analysis_options_type = P2AnalysisOptions
    analysis_options = option_names(P2AnalysisOptions)
    outputs = ("result-json", "report-json", "temperature-png", "report-pdf")

    def output_writers(self) -> Mapping[str, Callable[[Any, Path, str], list[Path]]]:
        """Return the temperature figure (:data:`~imucalib.procedures.p2.outputs.P2_WRITERS`)."""
        from imucalib.procedures.p2.outputs import P2_WRITERS

        return P2_WRITERS

    def batch_outputs(self, batch: Any, folder: Path, stem: str) -> list[Path]:
        """Write the lot's summary (:func:`~imucalib.procedures.p2.outputs.write_batch_summary`)."""
        from imucalib.procedures.p2.outputs import write_batch_summary

        return write_batch_summary(batch, folder, stem)

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.p2.plan.generate_p2_plan` (its keywords)."""
        from imucalib.procedures.p2.plan import generate_p2_plan

        return generate_p2_plan(**options)

    def predict(self, plan: Plan) -> Prediction:
        """Return the predicted σ of `plan`'s temperature models (:func:`~.p2.predict.predict_p2`).

        The optional capability of :class:`~imucalib.procedures.common.prediction.Predicting`
        (``imucalib plan show PLAN --predict``; docs/test-design.md, "P2: temperature points").
        """
        from imucalib.procedures.p2.predict import predict_p2

        return predict_p2(plan)

    def optimize_plan(self, request: OptimizeRequest) -> OptimizedPlan:
        """Return the P2 plan meeting `request` (:func:`~.p2.optimize.optimize_request`).

        The optional capability of :class:`~imucalib.procedures.common.prediction.Optimizing`
        (``imucalib plan optimize p2``; docs/test-design.md, "P2: temperature points").
        """
        from imucalib.procedures.p2.optimize import optimize_request

        return optimize_request(request)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> P2BatchResult:
        """Run :func:`~imucalib.procedures.p2.batch.analyze_p2` on a recording.

        Raises
        ------
        InvalidInputError
            An unknown option.
        """
        path = Path(recording.path if hasattr(recording, "path") else recording)
        return self.analyze_many([path], units=[unit] if unit else None, options=options,
                                 progress=progress)

    def analyze_many(self, recordings: Sequence[Recording | str | os.PathLike[str]], *,
                     units: Sequence[str] | None = None,
                     options: Mapping[str, Any] | None = None,
                     progress: Callable[[float], None] | None = None) -> P2BatchResult:
        """Run :func:`~imucalib.procedures.p2.batch.analyze_p2` on a lot (one cube each).

        `options` ``workers`` and ``scheduler`` run the units in parallel (local processes or a
        Dask scheduler); the others are :class:`~imucalib.procedures.p2.analysis.P2Options`.

        Raises
        ------
        InvalidInputError
            An unknown option.
        """
        from imucalib.procedures.p2.analysis import P2Options
        from imucalib.procedures.p2.batch import analyze_p2

        opts = accepted_options(self.name, options, self.analysis_options)
        workers = int(opts.pop("workers", 1))
        scheduler = opts.pop("scheduler", None)
        try:
            p2_options = P2Options(**opts)
        except TypeError as exc:
            raise InvalidInputError(f"procedure p2: {exc}") from None
        paths = [Path(r.path if hasattr(r, "path") else r) for r in recordings]
        return analyze_p2(paths[0] if len(paths) == 1 else paths,
                          units=list(units) if units else None, options=p2_options,
                          workers=workers, scheduler=scheduler, progress=progress)

    def report_content(self, result: Any, meta: Mapping[str, Any]) -> ReportContent:
        """Return a P2 unit's sections 1–5 of the report (:mod:`imucalib.procedures.p2.report`).

        A result read back from its JSON file (no temperature points) gets the generic ones.
        """
        from imucalib.procedures.p2.report import content

        return content(result, meta) or super().report_content(result, meta)

    def render_console(self, console: Console, result: Any, written: Sequence[Path]) -> None:
        """Print the batch: a row per unit, the warnings, the decision (:mod:`.p2.console`)."""
        from imucalib.procedures.p2.console import render_p2

        render_p2(console, result, written)

    def summary_report(self, batch: Any, *, recordings: Sequence[Any] | None = None,
                       report_ids: Mapping[str, str] | None = None) -> ReportDocument:
        """Return the summary report of an array or a lot (:mod:`.p2.summary_report`)."""
        from imucalib.procedures.p2.summary_report import summary_report

        return summary_report(batch, recordings=recordings, report_ids=report_ids)


#: The registered P2 procedure.
PROCEDURE = P2Procedure()
