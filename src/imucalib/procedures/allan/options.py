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
from typing import Literal

from imucalib.plan.bounds import (
    MAX_RECORD_S,
    MAX_SAMPLE_RATE_HZ,
    MAX_TEMPERATURE_DEGC,
    MAX_WAIT_S,
    MIN_SAMPLE_RATE_HZ,
    MIN_TEMPERATURE_DEGC,
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
    warm_up_s: float | None = option(None, help="Warm-up duration (the grade's 15/30/60 min "
                                                "when omitted).", unit="s", min=0.0,
                                     max=MAX_WAIT_S, group="timing")
    grade: Literal["consumer", "tactical", "navigation"] = option(
        "tactical", help="The IMU's grade (the twin's IMU and the default warm-up).",
        group="twin")
    sample_rate_hz: float = option(1000.0, help="The twin IMU's output rate.", unit="Hz",
                                   min=MIN_SAMPLE_RATE_HZ, max=MAX_SAMPLE_RATE_HZ,
                                   group="twin")
    latitude_deg: float = option(45.0, help="Latitude of the twin station.", unit="°",
                                 min=-90.0, max=90.0, group="twin")
    seed: int = option(1, help="Seed of the twin.", min=-(2**63), max=2**63 - 1, group="twin")
    name: str = option("allan", help="The plan's name (the recording's file name starts with "
                                     "it).", group="plan")


@dataclass(frozen=True)
class AllanAnalysisOptions:
    """The keys :func:`~.analysis.analyze_allan_recording` takes as ``options``: none."""
