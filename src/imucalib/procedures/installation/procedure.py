"""The installation-error test as a Procedure (registered as ``"installation"``).

It implements :class:`~imucalib.procedures.common.procedure.Procedure`.

The plan is :func:`~imucalib.procedures.installation.plan.generate_installation_plan`; the
analysis :func:`~imucalib.procedures.installation.analysis.analyze_installation`, imported when
first used.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from imucalib.procedures.common.defaults import ProcedureDefaults
from imucalib.procedures.common.options import option_names
from imucalib.procedures.common.procedure import accepted_options
from imucalib.procedures.installation.options import (
    InstallationAnalysisOptions,
    InstallationPlanOptions,
)
from imucalib.procedures.installation.roles import ROLES

if TYPE_CHECKING:
    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.installation.analysis import InstallationResult

__all__ = ["PROCEDURE", "InstallationProcedure"]


class InstallationProcedure(ProcedureDefaults):
    """Installation errors: the gyro triad's misalignment angles from ±ω turns."""

    name = "installation"
    description = ("installation (misalignment) errors of the gyro triad on a single-axis "
                   "table: each axis up in turn, a +ω and a −ω turn over whole revolutions; "
                   "the MIMU chapter's closed form and the least-squares triad model")
    roles = ROLES
    plan_options_type = InstallationPlanOptions
    plan_options = option_names(InstallationPlanOptions)
    analysis_options_type = InstallationAnalysisOptions
    analysis_options = option_names(InstallationAnalysisOptions)
    outputs = ("result-json", "report-json", "parameters-csv")

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.installation.plan.generate_installation_plan`."""
        from imucalib.procedures.installation.plan import generate_installation_plan

        return generate_installation_plan(**options)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> InstallationResult:
        """Run :func:`~imucalib.procedures.installation.analysis.analyze_installation`.

        Raises
        ------
        InvalidInputError
            An unknown option.
        """
        from imucalib.procedures.common.rate_windows import RateProcessing
        from imucalib.procedures.installation.analysis import analyze_installation

        opts = accepted_options(self.name, options, self.analysis_options)
        common = bool(opts.pop("common_bias", False))
        result = analyze_installation(recording, unit=unit, processing=RateProcessing(**opts),
                                      common_bias=common)
        if progress is not None:
            progress(1.0)
        return result


#: The registered installation procedure.
PROCEDURE = InstallationProcedure()
