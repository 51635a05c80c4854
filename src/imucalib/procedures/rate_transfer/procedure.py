"""The gyro rate transfer as a Procedure (registered as ``"rate-transfer"``).

It implements :class:`~imucalib.procedures.common.procedure.Procedure`.

The plan is :func:`~imucalib.procedures.rate_transfer.plan.generate_rate_transfer_plan`; its
prediction :func:`~imucalib.procedures.rate_transfer.predict.predict_rate_transfer` and its
optimiser :func:`~imucalib.procedures.rate_transfer.optimize.optimize_request`
(``imucalib plan optimize rate-transfer``, docs/test-design.md); the analysis
:func:`~imucalib.procedures.rate_transfer.analysis.analyze_rate_transfer`, imported when first
used.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from imucalib.procedures.common.defaults import ProcedureDefaults
from imucalib.procedures.common.options import option_names
from imucalib.procedures.common.procedure import accepted_options
from imucalib.procedures.rate_transfer.options import (
    RateTransferAnalysisOptions,
    RateTransferPlanOptions,
)
from imucalib.procedures.rate_transfer.roles import ROLES

if TYPE_CHECKING:
    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.common.prediction import (
        OptimizedPlan,
        OptimizeRequest,
        Prediction,
    )
    from imucalib.procedures.rate_transfer.analysis import RateTransferResult

__all__ = ["PROCEDURE", "RateTransferProcedure"]


class RateTransferProcedure(ProcedureDefaults):
    """Gyro rate transfer: scale factor, bias, nonlinearity and asymmetry per axis."""

    name = "rate-transfer"
    description = ("gyro rate transfer on a single-axis table: each axis up in turn, turns at "
                   "±ω over whole revolutions; scale factor, bias, nonlinearity (ppm of full "
                   "scale), asymmetry and quadratic term per axis")
    roles = ROLES
    plan_options_type = RateTransferPlanOptions
    plan_options = option_names(RateTransferPlanOptions)
    analysis_options_type = RateTransferAnalysisOptions
    analysis_options = option_names(RateTransferAnalysisOptions)
    outputs = ("result-json", "report-json", "parameters-csv")

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.rate_transfer.plan.generate_rate_transfer_plan`."""
        from imucalib.procedures.rate_transfer.plan import generate_rate_transfer_plan

        return generate_rate_transfer_plan(**options)

    def predict(self, plan: Plan) -> Prediction:
        """Return :func:`~imucalib.procedures.rate_transfer.predict.predict_rate_transfer`.

        The Predicting capability (``imucalib plan show PLAN --predict``).
        """
        from imucalib.procedures.rate_transfer.predict import predict_rate_transfer

        return predict_rate_transfer(plan)

    def optimize_plan(self, request: OptimizeRequest) -> OptimizedPlan:
        """Return the rate-transfer plan meeting `request` (:func:`~.optimize.optimize_request`).

        The optional capability of :class:`~imucalib.procedures.common.prediction.Optimizing`
        (``imucalib plan optimize rate-transfer``; docs/test-design.md, "Rate transfer").
        """
        from imucalib.procedures.rate_transfer.optimize import optimize_request

        return optimize_request(request)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> RateTransferResult:
        """Run :func:`~imucalib.procedures.rate_transfer.analysis.analyze_rate_transfer`.

        Raises
        ------
        InvalidInputError
            An unknown option.
        """
        from imucalib.procedures.rate_transfer.analysis import analyze_rate_transfer
        from imucalib.procedures.rate_transfer.observations import RateProcessing

        opts = accepted_options(self.name, options, self.analysis_options)
        result = analyze_rate_transfer(recording, unit=unit,
                                       processing=RateProcessing(**opts))
        if progress is not None:
            progress(1.0)
        return result


#: The registered rate-transfer procedure.
PROCEDURE = RateTransferProcedure()
