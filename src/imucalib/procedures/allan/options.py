"""The Allan plan's options (:func:`~imucalib.procedures.allan.plan.generate_allan_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new allan`` builds its
flags from them (docs/plugins.md).

:class:`AllanAnalysisOptions` holds, the same way, the keys
:func:`~imucalib.procedures.allan.analysis.analyze_allan_recording` takes as ``options`` (none);
``imucalib calibrate`` reads them with ``--set NAME=VALUE``.
"""

from __future__ import annotations

from dataclasses import dataclass

from imucalib.io.import_spec import ImportSpec
from imucalib.plan.bounds import (
    MAX_RECORD_S,
    MAX_TEMPERATURE_DEGC,
    MAX_WAIT_S,
    MIN_TEMPERATURE_DEGC,
)
from imucalib.procedures.common.option_fields import (
    Grade,
    grade_field,
    latitude_field,
    plan_name_field,
    sample_rate_field,
    seed_field,
    warm_up_field,
)
from imucalib.procedures.common.options import option

__all__ = ["AllanAnalysisOptions", "AllanPlanOptions"]


@dataclass(frozen=True)
class AllanPlanOptions:
    """Keywords of :func:`~imucalib.procedures.allan.plan.generate_allan_plan`."""

    temperatures_degc: tuple[float, ...] | None = option(
        None, help="Record once at each chamber temperature, after a soak (none: once, at "
                   "ambient).", unit="°C", min=MIN_TEMPERATURE_DEGC, max=MAX_TEMPERATURE_DEGC,
        flag="temperatures")
    record_s: float = option(7200.0, help="Each static record (≥ 10 min; the longest τ "
                                          "resolved is about a tenth of it).", unit="s",
                             min=600.0, max=MAX_RECORD_S, group="timing")
    soak_stable_s: float = option(1800.0, help="How long chamber and IMU temperatures must "
                                               "stay stable before a record.", unit="s",
                                  min=0.0, max=MAX_WAIT_S, group="timing")
    warm_up_s: float | None = warm_up_field(
        help="Warm-up duration (the grade's 15/30/60 min when omitted).")
    grade: Grade = grade_field("tactical")
    sample_rate_hz: float = sample_rate_field(1000.0)
    latitude_deg: float = latitude_field()
    seed: int = seed_field(1)
    name: str = plan_name_field("allan")


@dataclass(frozen=True)
class AllanAnalysisOptions:
    """The keys the Allan analysis takes as ``options``: how to read a log that is not a Recording.

    A Recording is analysed by :func:`~.analysis.analyze_allan_recording` (no options); a CSV
    or text log (``imucalib allan DATA``) as one static record by
    :func:`~.analysis.analyze_allan_arrays`, read with ``import_spec``.
    """

    import_spec: ImportSpec | None = option(
        None, help="How to read a log that is not a Recording (its columns, units, header).",
        python_only="given by the import options of `imucalib allan DATA` (docs/import.md)")
