"""P1 as a :class:`~imucalib.procedures.common.procedure.Procedure` (registered as ``"p1"``).

The plan is :func:`~imucalib.procedures.p1.plan.generate_p1_plan`, its predicted uncertainty
:func:`~imucalib.procedures.p1.predict.predict_p1` (:meth:`P1Procedure.predict`); the analysis
:func:`~imucalib.procedures.p1.analysis.analyze_p1` (observations, fit, verification, decision),
imported when first used. Its result, :class:`~imucalib.procedures.p1.analysis.P1Analysis`,
writes the calibration result JSON and the full report JSON.
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
from imucalib.procedures.p1.options import P1AnalysisOptions, P1PlanOptions
from imucalib.procedures.p1.roles import ROLES

if TYPE_CHECKING:
    from rich.console import Console

    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.common.prediction import (
        OptimizedPlan,
        OptimizeRequest,
        Prediction,
    )
    from imucalib.procedures.p1.analysis import P1Analysis
    from imucalib.report.document import ReportContent

__all__ = ["PROCEDURE", "P1Procedure"]

#: The models ``model`` may name (docs/p1.md).
MODELS = ("triad", "per-axis")


class P1Procedure(ProcedureDefaults):
    """Procedure P1: two-dimensional calibration of an IMU on a dual-axis table."""

    name = "p1"
    description = ("two-dimensional calibration on a dual-axis table: six positions, a static "
                   "record, rate points, held-out checks, repetitions")
    roles = ROLES
    plan_options_type = P1PlanOptions
    plan_options = option_names(P1PlanOptions)
    analysis_options_type = P1AnalysisOptions
    analysis_options = option_names(P1AnalysisOptions)
    outputs = ("result-json", "report-json", "residuals-png", "report-pdf")

    def output_writers(self) -> Mapping[str, Callable[[Any, Path, str], list[Path]]]:
        """Return the residual figure (:data:`~imucalib.procedures.p1.outputs.P1_WRITERS`)."""
        from imucalib.procedures.p1.outputs import P1_WRITERS

        return P1_WRITERS

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.p1.plan.generate_p1_plan` (its keywords)."""
        from imucalib.procedures.p1.plan import generate_p1_plan

        return generate_p1_plan(**options)

    def predict(self, plan: Plan) -> Prediction:
        """Return the predicted σ of `plan`'s result (:func:`~.p1.predict.predict_p1`).

        The optional capability of :class:`~imucalib.procedures.common.prediction.Predicting`
        (``imucalib plan show PLAN --predict``; docs/test-design.md).
        """
        from imucalib.procedures.p1.predict import predict_p1

        return predict_p1(plan)

    def optimize_plan(self, request: OptimizeRequest) -> OptimizedPlan:
        """Return the P1 plan meeting `request` (:func:`~.p1.optimize.optimize_request`).

        The optional capability of :class:`~imucalib.procedures.common.prediction.Optimizing`
        (``imucalib plan optimize p1``; docs/test-design.md, "The optimiser (P1)").
        """
        from imucalib.procedures.p1.optimize import optimize_request

        return optimize_request(request)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> P1Analysis:
        """Run :func:`~imucalib.procedures.p1.analysis.analyze_p1` on a recording.

        `options` may set ``model`` (``"triad"``, the default, or ``"per-axis"``),
        ``workers`` (processes the windows are reduced in) and the model terms: ``terms``
        (``"+k2,-g"``), ``term_criterion``, ``term_level`` (docs/p1.md, "Model terms"). An open
        Recording is analysed through its path (the provenance hashes the file). `progress`,
        when given, is called with the fraction of the steps reduced to observations.

        Raises
        ------
        InvalidInputError
            An unknown option or model.
        """
        from imucalib.procedures.p1.analysis import P1Options, analyze_p1

        opts = accepted_options(self.name, options, self.analysis_options)
        model = opts.get("model", "triad")
        if model not in MODELS:
            raise InvalidInputError(f"--model must be 'triad' or 'per-axis'; got {model!r}")
        path = Path(recording.path if hasattr(recording, "path") else recording)
        workers = int(opts.get("workers", 1))
        if workers < 1:
            raise InvalidInputError(f"--workers must be ≥ 1; got {workers}")
        terms = {k: opts[k] for k in ("terms", "term_criterion", "term_level") if k in opts}
        return analyze_p1(path, unit, P1Options(model=model, workers=workers, **terms),
                          progress=progress)

    def report_content(self, result: Any, meta: Mapping[str, Any]) -> ReportContent:
        """Return P1's sections 1–5 of the report (:mod:`imucalib.procedures.p1.report`).

        A result read back from its JSON file (no observations) gets the generic ones, with
        P1's Type B terms for the uncertainty budget.
        """
        from dataclasses import replace

        from imucalib.procedures.p1.report import content, type_b_terms

        return content(result, meta) or replace(super().report_content(result, meta),
                                                type_b=type_b_terms(result))

    def render_console(self, console: Console, result: Any, written: Sequence[Path]) -> None:
        """Print the parameters, the checks and the decision (:mod:`.p1.console`)."""
        from imucalib.procedures.p1.console import render_calibration

        render_calibration(console, result, written)


#: The registered P1 procedure.
PROCEDURE = P1Procedure()
