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
    MAX_SAMPLE_RATE_HZ,
    MAX_SETTLE_S,
    MAX_TABLE_RATE_DPS,
    MIN_SAMPLE_RATE_HZ,
)
from imucalib.plan.equipment import TwinEquipment
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
    settle_s: float = option(5.0, help="Settling before each record (the table reaching its "
                                       "rate).", unit="s", min=0.0, max=MAX_SETTLE_S,
                             group="timing")
    grade: Literal["consumer", "tactical", "navigation"] = option(
        "tactical", help="The unit's grade (the twin's unit and the gyro range the rate must "
                         "stay below).", group="twin")
    sample_rate_hz: float = option(100.0, help="The twin unit's output rate.", unit="Hz",
                                   min=MIN_SAMPLE_RATE_HZ, max=MAX_SAMPLE_RATE_HZ,
                                   group="twin")
    seed: int = option(0, help="Seed of the twin.", min=-(2**63), max=2**63 - 1, group="twin")
    twin: TwinEquipment | None = option(
        None, help="Another twin station (a single-axis table).", group="twin",
        python_only="a TwinEquipment object; edit the plan's [twin] table instead")
    name: str = option("installation", help="The plan's name (the recording's file name "
                                            "starts with it).", group="plan")


@dataclass(frozen=True)
class InstallationAnalysisOptions:
    """The keys :func:`~.analysis.analyze_installation` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    max_lost_fraction: float = option(
        0.01, help="The fraction of a window's expected samples that dropouts may take.",
        min=0.0, max=1.0)
    max_gap_s: float = option(0.5, help="The longest single dropout in a window.", unit="s",
                              min=0.0, group="timing")
    noise_block_s: float = option(
        1.0, help="The length of the blocks whose means' scatter gives the white-noise density.",
        unit="s", min=0.0, group="timing")
    common_bias: bool = option(
        False, help="Fit one gyro bias common to every turn in the least-squares triad model.")
