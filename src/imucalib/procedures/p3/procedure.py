"""P3 as a :class:`~imucalib.procedures.common.procedure.Procedure` (registered as ``"p3"``).

The plan is :func:`~imucalib.procedures.p3.plan.generate_p3_plan`; the analysis
:func:`~imucalib.procedures.p3.analysis.analyze_p3`, imported when first used. The result is
about the test accelerometer; `unit`, when given, must be it.
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
from imucalib.procedures.p3.options import P3AnalysisOptions, P3PlanOptions
from imucalib.procedures.p3.roles import ROLES

if TYPE_CHECKING:
    from rich.console import Console

    from imucalib.io.reader import Recording
    from imucalib.plan.schema import Plan
    from imucalib.procedures.p3.analysis import P3Result

__all__ = ["PROCEDURE", "P3Procedure"]


class P3Procedure(ProcedureDefaults):
    """Procedure P3: accelerometer K2 on a centrifuge with dynamic-unbalance compensation."""

    name = "p3"
    description = ("accelerometer K2 on a precision centrifuge: two reference accelerometers "
                   "in a round-robin measure the rotor's dynamic unbalance, which is removed "
                   "from the test accelerometer's ω⁴ term")
    roles = ROLES
    plan_options_type = P3PlanOptions
    plan_options = option_names(P3PlanOptions)
    analysis_options_type = P3AnalysisOptions
    analysis_options = option_names(P3AnalysisOptions)
    outputs = ("result-json", "report-json", "parameters-csv")

    def generate_plan(self, **options: Any) -> Plan:
        """Return :func:`~imucalib.procedures.p3.plan.generate_p3_plan` (its keywords)."""
        from imucalib.procedures.p3.plan import generate_p3_plan

        return generate_p3_plan(**options)

    def analyze(self, recording: Recording | str | os.PathLike[str], *,
                unit: str | None = None, options: Mapping[str, Any] | None = None,
                progress: Callable[[float], None] | None = None) -> P3Result:
        """Run :func:`~imucalib.procedures.p3.analysis.analyze_p3` on a recording.

        Raises
        ------
        InvalidInputError
            An unknown option, or `unit` that is not the test accelerometer.
        """
        from imucalib.procedures.p3.analysis import P3Options, analyze_p3
        from imucalib.procedures.p3.observations import P3Processing

        opts = accepted_options(self.name, options, self.analysis_options)
        axis = opts.pop("input_axis", None)
        if unit is not None and opts.get("test") not in (None, unit):
            raise InvalidInputError(f"unit {unit!r} and test {opts['test']!r} disagree")
        if unit is not None:
            opts["test"] = unit
        if axis:
            opts["processing"] = P3Processing(input_axis=axis)
        try:
            p3_options = P3Options(**opts)
        except TypeError as exc:
            raise InvalidInputError(f"procedure p3: {exc}") from None
        return analyze_p3(recording, options=p3_options, progress=progress)

    def render_console(self, console: Console, result: Any, written: Sequence[Path]) -> None:
        """Print K2 of the three accelerometers, c and c′, the decision (:mod:`.p3.console`)."""
        from imucalib.procedures.p3.console import render_p3

        render_p3(console, result, written)


#: The registered P3 procedure.
PROCEDURE = P3Procedure()
