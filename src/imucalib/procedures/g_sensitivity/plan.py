"""The default plan of the gyro g-sensitivity test (docs/g-sensitivity.md, "The plan").

:func:`generate_g_sensitivity_plan` writes an operator check of the mounting, a warm-up, then
the static positions of :data:`G_SENSITIVITY_POSITIONS_DEG` on a dual-axis table (pitch, roll):
gravity along +z, −z, +x, −x, +y, −y and eight 45° positions for redundancy, each a long static
record with role ``"g-sensitivity.position"``. The plan carries a twin (a high-grade dual-axis
table and one IMU) so that ``imucalib run PLAN --station sim`` runs it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from imucalib.errors import ConfigurationError
from imucalib.io.step_roles import G_SENSITIVITY_POSITION
from imucalib.plan.equipment import ImuConfig, SiteConfig, TableConfig, TwinEquipment
from imucalib.plan.schema import (
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanStep,
    PositionStep,
    WarmUpStep,
)

__all__ = ["G_SENSITIVITY_POSITIONS_DEG", "generate_g_sensitivity_plan", "position_steps"]

#: (pitch, roll) [°]: the six axis-up positions, then eight 45° positions (redundancy).
G_SENSITIVITY_POSITIONS_DEG: tuple[tuple[float, float], ...] = (
    (0.0, 0.0), (0.0, 180.0), (90.0, 0.0), (-90.0, 0.0), (0.0, 90.0), (0.0, 270.0),
    (45.0, 0.0), (-45.0, 0.0), (135.0, 0.0), (-135.0, 0.0),
    (0.0, 45.0), (0.0, 135.0), (0.0, 225.0), (0.0, 315.0),
)
_WARM_UP_S = {"consumer": 900.0, "tactical": 1800.0, "navigation": 3600.0}


def position_steps(positions_deg: Sequence[tuple[float, float]], role: str, *, settle_s: float,
                   record_s: float, extra_tags: tuple[str, ...] = ()) -> list[PlanStep]:
    """Return one static position step per (pitch, roll), tagged ``position=<k>``."""
    return [PositionStep(kind="position", angles_deg=(float(p), float(r)), settle_s=settle_s,
                         record_s=record_s, role=role,
                         label=f"position {k} (pitch {p:g}°, roll {r:g}°)",
                         tags=(f"position={k}", *extra_tags))
            for k, (p, r) in enumerate(positions_deg)]


def check_grade(grade: str) -> None:
    """Raise ConfigurationError for an unknown grade."""
    if grade not in _WARM_UP_S:
        raise ConfigurationError(f"`grade` must be one of {sorted(_WARM_UP_S)}; got {grade!r}")


def dual_axis_twin(grade: str, sample_rate_hz: float, latitude_deg: float, seed: int,
                   noise: str, errors: Mapping[str, Any] | None) -> TwinEquipment:
    """Return a twin: a high-grade dual-axis table and one IMU ``IMU-0001``."""
    return TwinEquipment(
        seed=seed, site=SiteConfig(latitude_deg=latitude_deg),
        table=TableConfig(kind="dual-axis", grade="high"),
        imus=(ImuConfig(name="IMU-0001", grade=grade, sample_rate_hz=sample_rate_hz,
                        noise=noise, errors=dict(errors or {})),))


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
                   duration_s=_WARM_UP_S[grade] if warm_up_s is None else warm_up_s),
        *position_steps(positions, G_SENSITIVITY_POSITION, settle_s=settle_s,
                        record_s=record_s),
    ]
    return Plan(name=name,
                description=f"gyro g-sensitivity (D0 + D1·a_x + D2·a_y + D3·a_z per axis): "
                            f"{len(positions)} static positions of {record_s:g} s",
                procedure="g-sensitivity", imu=ImuSpecConfig(grade=grade),
                twin=dual_axis_twin(grade, sample_rate_hz, latitude_deg, seed, noise, errors),
                steps=tuple(steps))
