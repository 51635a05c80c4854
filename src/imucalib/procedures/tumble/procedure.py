"""The tumble as a :class:`~imucalib.procedures.common.procedure.Procedure` (``"tumble"``).

The plan is :func:`~imucalib.procedures.tumble.plan.generate_tumble_plan`; the analysis
:func:`~imucalib.procedures.tumble.analysis.analyze_tumble`, imported when first used.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from imucalib.procedures.common.defaults import ProcedureDefaults
from imucalib.procedures.common.options import option_names
from imucalib.procedures.common.procedure import accepted_options
from imucalib.procedures.tumble.options import TumbleAnalysisOptions, TumblePlanOptions
from imucalib.procedures.tumble.roles import ROLES

if TYPE_CHECKING:
    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.tumble.analysis import TumbleResult

__all__ = ["PROCEDURE", "TumbleProcedure"]


class TumbleProcedure(ProcedureDefaults):
    """The accelerometer multi-position tumble on a dividing head (IEEE Std 1293)."""

    name = "tumble"
    description = ("accelerometer multi-position tumble on a dividing head (IEEE Std 1293): "
                   "K0, K1, misalignment, K2 − Kpp, Kip, K3 and Koq from the Fourier "
                   "coefficients of N equally spaced positions")
    roles = ROLES
    plan_options_type = TumblePlanOptions
    plan_options = option_names(TumblePlanOptions)
    analysis_options_type = TumbleAnalysisOptions
    analysis_options = option_names(TumbleAnalysisOptions)
    outputs = ("result-json", "report-json", "parameters-csv")

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.tumble.plan.generate_tumble_plan` (its keywords)."""
        from imucalib.procedures.tumble.plan import generate_tumble_plan

        return generate_tumble_plan(**options)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> TumbleResult:
        """Run :func:`~imucalib.procedures.tumble.analysis.analyze_tumble` on a recording.

        Raises
        ------
        InvalidInputError
            An unknown option.
        """
        from imucalib.procedures.tumble.analysis import TumbleOptions, analyze_tumble

        opts = accepted_options(self.name, options, self.analysis_options)
        if isinstance(opts.get("coefficients"), str):
            opts["coefficients"] = [c.strip() for c in opts["coefficients"].split(",") if c]
        return analyze_tumble(recording, options=TumbleOptions(unit=unit, **opts),
                              progress=progress)


#: The registered tumble procedure.
PROCEDURE = TumbleProcedure()
