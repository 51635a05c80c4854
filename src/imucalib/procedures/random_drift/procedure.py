"""The random-drift test as a registered procedure.

A :class:`~imucalib.procedures.common.procedure.Procedure` named ``"random-drift"``
(docs/random-drift.md).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from imucalib.procedures.common.defaults import ProcedureDefaults
from imucalib.procedures.common.options import option_names
from imucalib.procedures.common.procedure import accepted_options
from imucalib.procedures.random_drift.options import (
    RandomDriftAnalysisOptions,
    RandomDriftPlanOptions,
)
from imucalib.procedures.random_drift.roles import ROLES

if TYPE_CHECKING:
    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.random_drift.analysis import RandomDriftResult

__all__ = ["PROCEDURE", "RandomDriftProcedure"]


class RandomDriftProcedure(ProcedureDefaults):
    """Gyro random drift and accelerometer zero stability from repeated positions."""

    name = "random-drift"
    description = ("gyro random drift 2.7·√(σ_D0² + σ_D1² + σ_D2² + σ_D3²) and accelerometer "
                   "zero stability from multi-position runs repeated over hours")
    roles = ROLES
    plan_options_type = RandomDriftPlanOptions
    plan_options = option_names(RandomDriftPlanOptions)
    analysis_options_type = RandomDriftAnalysisOptions
    analysis_options = option_names(RandomDriftAnalysisOptions)
    outputs = ("result-json", "report-json", "parameters-csv")

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.random_drift.plan.generate_random_drift_plan`."""
        from imucalib.procedures.random_drift.plan import generate_random_drift_plan

        return generate_random_drift_plan(**options)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> RandomDriftResult:
        """Run :func:`~imucalib.procedures.random_drift.analysis.analyze_random_drift`.

        Raises
        ------
        InvalidInputError
            An unknown option.
        """
        from imucalib.procedures.common.drift_model import GSensitivityOptions
        from imucalib.procedures.random_drift.analysis import analyze_random_drift

        opts = accepted_options(self.name, options, self.analysis_options)
        result = analyze_random_drift(recording, unit=unit, options=GSensitivityOptions(**opts))
        if progress is not None:
            progress(1.0)
        return result


#: The registered random-drift procedure.
PROCEDURE = RandomDriftProcedure()
