"""The Earth-rate gyro bias test as a registered procedure.

A :class:`~imucalib.procedures.common.procedure.Procedure` named ``"earth-rate-bias"``
(docs/earth-rate-bias.md).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from imucalib.procedures.common.defaults import ProcedureDefaults
from imucalib.procedures.common.options import option_names
from imucalib.procedures.common.procedure import accepted_options
from imucalib.procedures.earth_rate_bias.options import (
    EarthRateBiasAnalysisOptions,
    EarthRateBiasPlanOptions,
)
from imucalib.procedures.earth_rate_bias.roles import ROLES

if TYPE_CHECKING:
    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.earth_rate_bias.analysis import EarthRateBiasResult

__all__ = ["PROCEDURE", "EarthRateBiasProcedure"]


class EarthRateBiasProcedure(ProcedureDefaults):
    """Navigation-grade gyro bias against Earth rate: 4-position and up/down methods."""

    name = "earth-rate-bias"
    description = ("gyro bias against Earth rate (navigation grade): 4-position (N, E, S, W) and "
                   "up/down methods on a single-axis table with remounts, compared")
    roles = ROLES
    plan_options_type = EarthRateBiasPlanOptions
    plan_options = option_names(EarthRateBiasPlanOptions)
    analysis_options_type = EarthRateBiasAnalysisOptions
    analysis_options = option_names(EarthRateBiasAnalysisOptions)
    outputs = ("result-json", "report-json", "parameters-csv")

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~.plan.generate_earth_rate_bias_plan` (its keywords)."""
        from imucalib.procedures.earth_rate_bias.plan import generate_earth_rate_bias_plan

        return generate_earth_rate_bias_plan(**options)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> EarthRateBiasResult:
        """Run :func:`~.analysis.analyze_earth_rate_bias`.

        Raises
        ------
        InvalidInputError
            An unknown option.
        """
        from imucalib.procedures.earth_rate_bias.analysis import analyze_earth_rate_bias

        opts = accepted_options(self.name, options, self.analysis_options)
        result = analyze_earth_rate_bias(recording, unit=unit, **opts)
        if progress is not None:
            progress(1.0)
        return result


#: The registered Earth-rate bias procedure.
PROCEDURE = EarthRateBiasProcedure()
