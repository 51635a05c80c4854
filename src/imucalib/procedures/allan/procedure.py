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

from imucalib.procedures.allan.options import AllanAnalysisOptions, AllanPlanOptions
from imucalib.procedures.allan.roles import ROLES
from imucalib.procedures.common.defaults import ProcedureDefaults
from imucalib.procedures.common.options import option_names
from imucalib.procedures.common.procedure import accepted_options

if TYPE_CHECKING:
    from rich.console import Console

    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.allan.analysis import NoiseCharacterization
    from imucalib.report.document import ReportContent

__all__ = ["PROCEDURE", "AllanProcedure"]


class AllanProcedure(ProcedureDefaults):
    """Noise characterisation (IEEE 952 Annex C) of the static records of a recording."""

    name = "allan"
    description = ("noise characterisation: Allan deviations and noise terms of long static "
                   "records, optionally at several temperatures")
    roles = ROLES
    plan_options_type = AllanPlanOptions
    plan_options = option_names(AllanPlanOptions)
    analysis_options_type = AllanAnalysisOptions
    analysis_options = option_names(AllanAnalysisOptions)
    outputs = ("result-json", "noise-json", "kalibr-yaml", "openvins-yaml", "noise-table",
               "figures")

    def output_writers(self) -> Mapping[str, Callable[[Any, Path, str], list[Path]]]:
        """Return the noise outputs (:data:`~imucalib.procedures.allan.outputs.NOISE_WRITERS`)."""
        from imucalib.procedures.allan.outputs import NOISE_WRITERS

        return NOISE_WRITERS

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.allan.plan.generate_allan_plan` (its keywords)."""
        from imucalib.procedures.allan.plan import generate_allan_plan

        return generate_allan_plan(**options)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> NoiseCharacterization:
        """Run :func:`~imucalib.procedures.allan.analysis.analyze_allan_recording`.

        A log that is not a Recording (a CSV, a ``rostopic echo -p`` export) is read with
        ``options["import_spec"]`` and analysed as one static record
        (:func:`~imucalib.procedures.allan.analysis.analyze_allan_arrays`). `progress`, when
        given, is called with the fraction of the records analysed.

        Raises
        ------
        InvalidInputError
            An option other than ``import_spec``.
        """
        from imucalib.procedures.allan.analysis import (
            analyze_allan_arrays,
            analyze_allan_recording,
        )

        opts = accepted_options(self.name, options, self.analysis_options)
        spec = opts.pop("import_spec", None)
        path = None if hasattr(recording, "path") else Path(recording)
        if path is None or path.suffix.lower() in (".h5", ".hdf5"):
            return analyze_allan_recording(recording, unit=unit, progress=progress)
        import numpy as np

        from imucalib.io.import_spec import read_imu_table

        frame = read_imu_table(path, spec)
        cols = {c: frame[c].to_numpy() for c in frame.columns}
        result = analyze_allan_arrays(np.asarray(frame.index, dtype=np.float64), cols,
                                      source=str(path), unit=unit or "imu")
        if progress is not None:
            progress(1.0)
        return result

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
