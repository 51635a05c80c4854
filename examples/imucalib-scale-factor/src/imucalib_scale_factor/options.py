"""The scale-factor procedure's options, as imucalib's option dataclasses.

:class:`ScaleFactorPlanOptions` holds the keywords of :func:`~.plan.generate_scale_factor_plan`
and :class:`ScaleFactorAnalysisOptions` the keys :func:`~.analysis.analyze_scale_factor` takes as
``options``. Each field is made by imucalib's ``option()`` (help, unit, range, help section), so
``imucalib plan new scale-factor`` builds its flags and its ``--help`` from the first, and
``imucalib calibrate`` reads the second.
"""

from __future__ import annotations

from dataclasses import dataclass

from imucalib.plan.bounds import (
    MAX_REVOLUTIONS,
    MAX_TABLE_RATE_DPS,
)
from imucalib.procedures.common.option_fields import (
    Grade,
    grade_field,
    max_gap_field,
    max_lost_fraction_field,
    noise_block_field,
    plan_name_field,
    sample_rate_field,
    seed_field,
    settle_field,
)
from imucalib.procedures.common.options import option

__all__ = ["DEFAULT_RATES_DPS", "ScaleFactorAnalysisOptions", "ScaleFactorPlanOptions"]

#: The rate magnitudes turned both ways when none are given. [°/s]
DEFAULT_RATES_DPS: tuple[float, ...] = (10.0, 30.0, 60.0, 90.0)


@dataclass(frozen=True)
class ScaleFactorPlanOptions:
    """Keywords of :func:`~imucalib_scale_factor.plan.generate_scale_factor_plan`."""

    rates_dps: tuple[float, ...] = option(
        DEFAULT_RATES_DPS, help="Rate magnitudes about the unit's z axis, each turned +ω and −ω.",
        unit="°/s", min=0.0, max=MAX_TABLE_RATE_DPS, flag="rates")
    revolutions: int = option(2, help="Whole revolutions per turn (≥ 2: one may be lost at the "
                                      "window edges).", min=2, max=MAX_REVOLUTIONS)
    settle_s: float = settle_field(
        5.0, help="Settling before each record (the table reaching its rate).")
    grade: Grade = grade_field("tactical")
    sample_rate_hz: float = sample_rate_field(100.0)
    seed: int = seed_field(0)
    name: str = plan_name_field("scale-factor")


@dataclass(frozen=True)
class ScaleFactorAnalysisOptions:
    """The keys :func:`~imucalib_scale_factor.analysis.analyze_scale_factor` takes as ``options``.

    They are those of imucalib's turn reduction
    (:class:`~imucalib.procedures.common.rate_windows.RateProcessing`), with its defaults.
    """

    max_lost_fraction: float = max_lost_fraction_field(0.01)
    max_gap_s: float = max_gap_field(0.5)
    noise_block_s: float = noise_block_field(
        1.0, help="The length of the blocks whose means' scatter gives the white-noise density.")
