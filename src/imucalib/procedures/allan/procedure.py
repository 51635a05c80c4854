"""The Allan procedure as a :class:`~imucalib.procedures.common.procedure.Procedure` (``"allan"``).

The plan is :func:`~imucalib.procedures.allan.plan.generate_allan_plan`; the analysis
:func:`~imucalib.procedures.allan.analysis.analyze_allan_recording`, imported when first used.
Its result, :class:`~imucalib.procedures.allan.analysis.NoiseCharacterization`, writes the
versioned noise JSON, Kalibr and OpenVINS YAML, a datasheet table per record, and figures.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imucalib.errors import InvalidInputError
from imucalib.procedures.allan.options import AllanAnalysisOptions, AllanPlanOptions
from imucalib.procedures.common.options import option_names
from imucalib.procedures.common.reporting import GenericReporting

if TYPE_CHECKING:
    from rich.console import Console

    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.allan.analysis import NoiseCharacterization
    from imucalib.report.document import ReportContent

__all__ = ["PROCEDURE", "AllanProcedure"]


class AllanProcedure(GenericReporting):
    """Noise characterisation (IEEE 952 Annex C) of the static records of a recording."""

    name = "allan"
    description = ("noise characterisation: Allan deviations and noise terms of long static "
                   "records, optionally at several temperatures")
    plan_options_type = AllanPlanOptions
    plan_options = option_names(AllanPlanOptions)
    analysis_options_type = AllanAnalysisOptions
    analysis_options = option_names(AllanAnalysisOptions)
    outputs = ("noise-json", "kalibr-yaml", "openvins-yaml", "noise-table", "figures")

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.allan.plan.generate_allan_plan` (its keywords)."""
        from imucalib.procedures.allan.plan import generate_allan_plan

        return generate_allan_plan(**options)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> NoiseCharacterization:
        """Run :func:`~imucalib.procedures.allan.analysis.analyze_allan_recording`.

        `progress`, when given, is called with the fraction of the records analysed.

        Raises
        ------
        InvalidInputError
            Any option (this procedure takes none).
        """
        from imucalib.procedures.allan.analysis import analyze_allan_recording

        if options:
            raise InvalidInputError(f"procedure allan takes no options; got {sorted(options)}")
        return analyze_allan_recording(recording, unit=unit, progress=progress)

    def report_content(self, result: Any, meta: Mapping[str, Any]) -> ReportContent:
        """Return the noise tables and Allan figures of the report (:mod:`.allan.report`).

        A result without its records gets the generic sections.
        """
        from imucalib.procedures.allan.report import content

        return content(result, meta) or super().report_content(result, meta)

    def render_console(self, console: Console, result: Any, written: Sequence[Path]) -> None:
        """Print each record's noise-term table (:mod:`.allan.console`)."""
        from imucalib.procedures.allan.console import render_noise_characterization

        render_noise_characterization(console, result, written)


#: The registered Allan procedure.
PROCEDURE = AllanProcedure()
