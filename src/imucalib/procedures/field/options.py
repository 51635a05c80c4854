"""The field plan's options (:func:`~imucalib.procedures.field.plan.generate_field_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new field`` builds its
flags from them (docs/plugins.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from imucalib.plan.bounds import MAX_RECORD_S, MAX_SAMPLE_RATE_HZ, MAX_STEPS, MIN_SAMPLE_RATE_HZ
from imucalib.procedures.common.options import option

__all__ = ["FieldPlanOptions"]


@dataclass(frozen=True)
class FieldPlanOptions:
    """Keywords of :func:`~imucalib.procedures.field.plan.generate_field_plan`."""

    n_poses: int = option(12, help="Static poses after the initial rest (≥ 6; ≥ 10 for the "
                                   "gravity-norm form).", min=6, max=MAX_STEPS)
    full_turns: bool = option(True, help="Add a +360° and a −360° turn flat on the desk about "
                                         "each axis (the gyro's scale).")
    tilt_deg: float = option(20.0, help="How far the operator tilts the second round of "
                                        "poses.", unit="°", min=0.0, max=90.0)
    static_s: float = option(6.0, help="Each pose's record (≥ 2 s: the detector's windows eat "
                                       "half a second at each end).", unit="s", min=2.0,
                             max=MAX_RECORD_S, group="timing")
    init_static_s: float = option(10.0, help="The initial rest (≥ 4 s).", unit="s", min=4.0,
                                  max=MAX_RECORD_S, group="timing")
    grade: Literal["consumer", "tactical", "navigation"] = option(
        "consumer", help="The IMU's grade (the twin's IMU).", group="twin")
    sample_rate_hz: float = option(200.0, help="The twin IMU's output rate.", unit="Hz",
                                   min=MIN_SAMPLE_RATE_HZ, max=MAX_SAMPLE_RATE_HZ,
                                   group="twin")
    latitude_deg: float = option(45.0, help="Latitude of the twin station.", unit="°",
                                 min=-90.0, max=90.0, group="twin")
    seed: int = option(1, help="Seed of the twin.", min=-(2**63), max=2**63 - 1, group="twin")
    name: str = option("field", help="The plan's name (the recording's file name starts with "
                                     "it).", group="plan")
