"""The rate transfer's plan options (:func:`~.plan.generate_rate_transfer_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new rate-transfer`` builds
its flags from them (docs/plugins.md).

:class:`RateTransferAnalysisOptions` holds, the same way, the keys
:func:`~.analysis.analyze_rate_transfer` takes as ``options``; ``imucalib calibrate`` reads them
with ``--set NAME=VALUE``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from imucalib.plan.bounds import (
    MAX_REVOLUTIONS,
    MAX_TABLE_RATE_DPS,
)
from imucalib.plan.equipment import TwinEquipment
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
    twin_field,
)
from imucalib.procedures.common.options import option
from imucalib.procedures.rate_transfer.plan import AXES

__all__ = ["RateTransferAnalysisOptions", "RateTransferPlanOptions"]


@dataclass(frozen=True)
class RateTransferPlanOptions:
    """Keywords of :func:`~imucalib.procedures.rate_transfer.plan.generate_rate_transfer_plan`."""

    rates_dps: tuple[float, ...] | None = option(
        None, help="Rate magnitudes, each turned +ω and −ω (5, 12.5, 18, 27, 36, 45 and 60 °/s "
                   "when omitted).", unit="°/s", min=0.0, max=MAX_TABLE_RATE_DPS, flag="rates")
    log_spaced: tuple[float, float, int] | None = option(
        None, help="Min, max and n: n rate magnitudes spaced logarithmically instead of the "
                   "rates.", unit="°/s")
    axes: tuple[Literal["x", "y", "z"], ...] = option(
        AXES, help="Body axes tested, each up in turn.")
    revolutions: int = option(2, help="Whole revolutions per turn (≥ 2: the analysis accepts "
                                      "one fewer at the window edges).", min=2,
                              max=MAX_REVOLUTIONS)
    settle_s: float = settle_field(
        5.0, help="Settling before each record (the table reaching its rate).")
    grade: Grade = grade_field("tactical")
    sample_rate_hz: float = sample_rate_field(100.0)
    seed: int = seed_field(0)
    twin: TwinEquipment | None = twin_field(help="Another twin station (a single-axis table).")
    name: str = plan_name_field("rate-transfer")


@dataclass(frozen=True)
class RateTransferAnalysisOptions:
    """The keys :func:`~.analysis.analyze_rate_transfer` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    max_lost_fraction: float = max_lost_fraction_field(0.01)
    max_gap_s: float = max_gap_field(0.5)
    noise_block_s: float = noise_block_field(
        1.0, help="The length of the blocks whose means' scatter gives the white-noise density.")
