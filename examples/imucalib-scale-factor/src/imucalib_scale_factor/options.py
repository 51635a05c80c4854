"""The scale-factor procedure's options, as imucalib's option dataclasses.

:class:`ScaleFactorPlanOptions` holds the keywords of :func:`~.plan.generate_scale_factor_plan`
and :class:`ScaleFactorAnalysisOptions` the keys :func:`~.analysis.analyze_scale_factor` takes as
``options``. Each field is made by imucalib's ``option()`` (help, unit, range, help section), so
``imucalib plan new scale-factor`` builds its flags and its ``--help`` from the first, and
``imucalib calibrate`` reads the second.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from imucalib.plan.bounds import (
    MAX_REVOLUTIONS,
    MAX_SAMPLE_RATE_HZ,
    MAX_SETTLE_S,
    MAX_TABLE_RATE_DPS,
    MIN_SAMPLE_RATE_HZ,
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
    settle_s: float = option(5.0, help="Settling before each record (the table reaching its "
                                       "rate).", unit="s", min=0.0, max=MAX_SETTLE_S,
                             group="timing")
    grade: Literal["consumer", "tactical", "navigation"] = option(
        "tactical", help="The twin unit's grade (its gyro range bounds the rates).", group="twin")
    sample_rate_hz: float = option(100.0, help="The twin unit's output rate.", unit="Hz",
                                   min=MIN_SAMPLE_RATE_HZ, max=MAX_SAMPLE_RATE_HZ, group="twin")
    seed: int = option(0, help="Seed of the twin.", min=0, max=2**63 - 1, group="twin")
    name: str = option("scale-factor", help="The plan's name (the recording's file name starts "
                                            "with it).", group="plan")


@dataclass(frozen=True)
class ScaleFactorAnalysisOptions:
    """The keys :func:`~imucalib_scale_factor.analysis.analyze_scale_factor` takes as ``options``.

    They are those of imucalib's turn reduction
    (:class:`~imucalib.procedures.common.rate_windows.RateProcessing`), with its defaults.
    """

    max_lost_fraction: float = option(
        0.01, help="The fraction of a window's expected samples that dropouts may take.",
        min=0.0, max=1.0)
    max_gap_s: float = option(0.5, help="The longest single dropout in a window.", unit="s",
                              min=0.0, group="timing")
    noise_block_s: float = option(
        1.0, help="The length of the blocks whose means' scatter gives the white-noise density.",
        unit="s", min=0.0, group="timing")
