"""The default plan of the gyro g-sensitivity test (docs/g-sensitivity.md, "The plan").

:func:`generate_g_sensitivity_plan` writes an operator check of the mounting, a warm-up, then
the static positions of :data:`G_SENSITIVITY_POSITIONS_DEG` on a dual-axis table (pitch, roll):
gravity along +z, −z, +x, −x, +y, −y and eight 45° positions for redundancy, each a long static
record with role ``"g-sensitivity.position"``. The plan carries a twin (a high-grade dual-axis
table and one IMU) so that ``imucalib run PLAN --station sim`` runs it.

The positions, their steps and the twin are those of
:mod:`~imucalib.procedures.common.static_positions`, the grades and their warm-ups those of
:mod:`~imucalib.procedures.common.grade` (both re-exported here).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from imucalib.errors import ConfigurationError
from imucalib.plan.schema import (
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanStep,
    WarmUpStep,
)
from imucalib.procedures.common.grade import WARM_UP_S, check_grade
from imucalib.procedures.common.static_positions import (
    G_SENSITIVITY_POSITIONS_DEG,
    dual_axis_twin,
    position_steps,
)
from imucalib.procedures.g_sensitivity.roles import G_SENSITIVITY_POSITION

__all__ = ["G_SENSITIVITY_POSITIONS_DEG", "check_grade", "dual_axis_twin",
           "generate_g_sensitivity_plan", "position_steps"]


def generate_g_sensitivity_plan(*, name: str = "g-sensitivity", grade: str = "tactical",
                                positions_deg: Sequence[tuple[float, float]] | None = None,
                                record_s: float = 600.0, settle_s: float = 60.0,
                                warm_up_s: float | None = None, sample_rate_hz: float = 100.0,
                                latitude_deg: float = 45.0, noise: str = "grade",
                                errors: Mapping[str, Any] | None = None,
                                seed: int = 1) -> Plan:
    """Return the default g-sensitivity plan (module docstring).

    Parameters
    ----------
    name : str
        Plan name.
    grade : {"consumer", "tactical", "navigation"}
        The IMU's grade (the twin's IMU and the default warm-up).
    positions_deg : sequence of (pitch, roll), optional
        The static positions [°]; :data:`G_SENSITIVITY_POSITIONS_DEG` when omitted. They must
        excite every gravity component (the analysis checks the design's rank).
    record_s, settle_s : float
        Static record and settling time of each position. [s]
    warm_up_s : float, optional
        Warm-up; the grade's default (15/30/60 min) when omitted. [s]
    sample_rate_hz : float
        The twin IMU's output data rate. [Hz]
    latitude_deg : float
        The twin's site. [°]
    noise : {"grade", "white"}
        The twin IMU's noise.
    errors : mapping, optional
        Known truth values for the twin (``{"gyro.g_sensitivity": ((…), (…), (…))}``, SI).
    seed : int
        Seed of the twin.

    Raises
    ------
    ConfigurationError
        An unknown grade, fewer than 4 positions, a record shorter than 3 s.
    """
    check_grade(grade)
    positions = tuple(positions_deg) if positions_deg is not None else G_SENSITIVITY_POSITIONS_DEG
    if len(positions) < 4:
        raise ConfigurationError(f"the g-sensitivity fit has 4 unknowns per gyro axis: at least 4 "
                                 f"positions are needed; got {len(positions)}")
    if record_s < 3.0:
        raise ConfigurationError(f"`record_s` must be at least 3 s (three 1 s noise blocks); "
                                 f"got {record_s:g} s")
    steps: list[PlanStep] = [
        OperatorCheckStep(kind="operator-check", label="mounting",
                          item="IMU fixed on the dual-axis table platform, its axes along the "
                               "platform's; table levelled; cables strain-relieved"),
        WarmUpStep(kind="warm-up", label="warm-up",
                   duration_s=WARM_UP_S[grade] if warm_up_s is None else warm_up_s),
        *position_steps(positions, G_SENSITIVITY_POSITION, settle_s=settle_s,
                        record_s=record_s),
    ]
    return Plan(name=name,
                description=f"gyro g-sensitivity (D0 + D1·a_x + D2·a_y + D3·a_z per axis): "
                            f"{len(positions)} static positions of {record_s:g} s",
                procedure="g-sensitivity", imu=ImuSpecConfig(grade=grade),
                twin=dual_axis_twin(grade, sample_rate_hz, latitude_deg, seed, noise, errors),
                steps=tuple(steps))
