"""The installation-error test's plan options (:func:`~.plan.generate_installation_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new installation`` builds
its flags from them (docs/plugins.md).

:class:`InstallationAnalysisOptions` holds, the same way, the keys
:func:`~.analysis.analyze_installation` takes as ``options``; ``imucalib calibrate`` reads them
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
from imucalib.procedures.installation.plan import AXES

__all__ = ["InstallationAnalysisOptions", "InstallationPlanOptions"]


@dataclass(frozen=True)
class InstallationPlanOptions:
    """Keywords of :func:`~imucalib.procedures.installation.plan.generate_installation_plan`.

    The generator also takes several rates for `rate_dps` (each turned both ways); the option
    is one rate, as on today's command line, so that its default is the generator's 30.0.
    """

    rate_dps: float = option(30.0, help="Rate magnitude |ω| of the turns, each turned +ω and "
                                        "−ω.", unit="°/s", min=0.0, max=MAX_TABLE_RATE_DPS)
    axes: tuple[Literal["x", "y", "z"], ...] = option(
        AXES, help="Body axes up in turn (each gives the column of M of that input axis).")
    revolutions: int = option(2, help="Whole revolutions per turn (≥ 2: the analysis accepts "
                                      "one fewer at the window edges).", min=2,
                              max=MAX_REVOLUTIONS)
    settle_s: float = settle_field(
        5.0, help="Settling before each record (the table reaching its rate).")
    grade: Grade = grade_field("tactical")
    sample_rate_hz: float = sample_rate_field(100.0)
    seed: int = seed_field(0)
    twin: TwinEquipment | None = twin_field(help="Another twin station (a single-axis table).")
    name: str = plan_name_field("installation")


@dataclass(frozen=True)
class InstallationAnalysisOptions:
    """The keys :func:`~.analysis.analyze_installation` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    max_lost_fraction: float = max_lost_fraction_field(0.01)
    max_gap_s: float = max_gap_field(0.5)
    noise_block_s: float = noise_block_field(
        1.0, help="The length of the blocks whose means' scatter gives the white-noise density.")
    common_bias: bool = option(
        False, help="Fit one gyro bias common to every turn in the least-squares triad model.")
