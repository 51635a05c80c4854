"""The g-sensitivity test as a registered procedure.

A :class:`~imucalib.procedures.common.procedure.Procedure` named ``"g-sensitivity"``
(docs/g-sensitivity.md).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from imucalib.procedures.common.defaults import ProcedureDefaults
from imucalib.procedures.common.options import option_names
from imucalib.procedures.common.procedure import accepted_options
from imucalib.procedures.g_sensitivity.options import (
    GSensitivityAnalysisOptions,
    GSensitivityPlanOptions,
)
from imucalib.procedures.g_sensitivity.roles import ROLES

if TYPE_CHECKING:
    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.g_sensitivity.analysis import GSensitivityResult

__all__ = ["PROCEDURE", "GSensitivityProcedure"]


class GSensitivityProcedure(ProcedureDefaults):
    """Gyro g-sensitivity (D0 + D1·a_x + D2·a_y + D3·a_z per axis) on a dual-axis table."""

    name = "g-sensitivity"
    description = ("gyro g-sensitivity: drift D0 + D1·a_x + D2·a_y + D3·a_z of each gyro axis "
                   "from static positions on a dual-axis table, Earth rate subtracted")
    roles = ROLES
    plan_options_type = GSensitivityPlanOptions
    plan_options = option_names(GSensitivityPlanOptions)
    analysis_options_type = GSensitivityAnalysisOptions
    analysis_options = option_names(GSensitivityAnalysisOptions)
    outputs = ("result-json", "report-json", "parameters-csv")

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.g_sensitivity.plan.generate_g_sensitivity_plan`."""
        from imucalib.procedures.g_sensitivity.plan import generate_g_sensitivity_plan

        return generate_g_sensitivity_plan(**options)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> GSensitivityResult:
        """Run :func:`~imucalib.procedures.g_sensitivity.analysis.analyze_g_sensitivity`.

        Raises
        ------
        InvalidInputError
            An unknown option.
        """
        from imucalib.procedures.g_sensitivity.analysis import (
            GSensitivityOptions,
            analyze_g_sensitivity,
        )

        opts = accepted_options(self.name, options, self.analysis_options)
        result = analyze_g_sensitivity(recording, unit=unit, options=GSensitivityOptions(**opts))
        if progress is not None:
            progress(1.0)
        return result


#: The registered g-sensitivity procedure.
PROCEDURE = GSensitivityProcedure()
