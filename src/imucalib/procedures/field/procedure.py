"""The field calibration as a registered procedure (``"field"``).

The plan is :func:`~imucalib.procedures.field.plan.generate_field_plan` (a guided hand-held
session); the analysis :func:`~imucalib.procedures.field.analysis.analyze_field`, on a
Recording of the session or on a user's own log: a CSV or text file read through the import
options of docs/import.md (:meth:`FieldProcedure.analyze` takes the path and an ``import_spec``
option).
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
from imucalib.procedures.field.options import FieldAnalysisOptions, FieldPlanOptions
from imucalib.procedures.field.roles import ROLES

if TYPE_CHECKING:
    from rich.console import Console

    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.field.result import FieldResult
    from imucalib.report.document import ReportContent

__all__ = ["PROCEDURE", "FieldProcedure"]

#: Suffixes read as a Recording; anything else is a log read through the import options.
_RECORDING_SUFFIXES = (".h5", ".hdf5")


class FieldProcedure(ProcedureDefaults):
    """Field calibration by hand: accelerometer from poses, gyro from rotations."""

    name = "field"
    description = ("calibration without equipment from a hand-held log: the accelerometer "
                   "from static poses of unknown orientation (gravity norm) or a fixture's "
                   "faces, the gyro from the rotations between them")
    roles = ROLES
    plan_options_type = FieldPlanOptions
    plan_options = option_names(FieldPlanOptions)
    analysis_options_type = FieldAnalysisOptions
    analysis_options = option_names(FieldAnalysisOptions)
    outputs = ("result-json", "report-json", "parameters-csv", "report-pdf")

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.field.plan.generate_field_plan` (its keywords)."""
        from imucalib.procedures.field.plan import generate_field_plan

        return generate_field_plan(**options)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> FieldResult:
        """Calibrate from a Recording, or a log file read with ``options["import_spec"]``.

        Raises
        ------
        InvalidInputError
            An unknown option, an unreadable log (naming the column and row).
        """
        from imucalib.io.opening import open_recording
        from imucalib.io.reader import Recording
        from imucalib.procedures.common.static_intervals import (
            log_from_frame,
            log_from_recording,
        )
        from imucalib.procedures.field.analysis import FieldOptions, analyze_field

        opts = accepted_options(self.name, options, self.analysis_options)
        spec = opts.pop("import_spec", None)
        try:
            field_options = FieldOptions(**opts)
        except TypeError as exc:
            raise InvalidInputError(f"procedure field: {exc}") from None
        if isinstance(recording, Recording):
            log = log_from_recording(recording, unit)
        elif Path(recording).suffix.lower() in _RECORDING_SUFFIXES:
            with open_recording(recording) as rec:
                log = log_from_recording(rec, unit)
        else:
            from imucalib.io.import_spec import read_imu_table

            path = Path(recording)
            frame = read_imu_table(path, spec)
            log = log_from_frame(frame, unit or "IMU", str(path))
        return analyze_field(log, field_options, progress=progress)

    def report_content(self, result: Any, meta: Mapping[str, Any]) -> ReportContent:
        """Return the generic sections 1–5 with the field traceability (:mod:`.field.report`)."""
        from imucalib.procedures.field.report import content

        return content(result, meta, description=self.description)

    def render_console(self, console: Console, result: Any, written: Sequence[Path]) -> None:
        """Print the parameters, each fit's χ²/ν, the session, the notes (:mod:`.field.console`)."""
        from imucalib.procedures.field.console import render_field

        render_field(console, result, written)


#: The registered field procedure.
PROCEDURE = FieldProcedure()
