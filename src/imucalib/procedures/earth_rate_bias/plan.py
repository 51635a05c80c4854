"""The default plan of the Earth-rate gyro bias test (docs/earth-rate-bias.md, "The plan").

:func:`generate_earth_rate_bias_plan` writes an operator check, a warm-up, then for each fixture
pose of :data:`EARTH_RATE_POSES` (the fixture axis up: +z, −z, +x, −x, +y, −y) a remount (role
``"earth-rate-bias.remount"``) and a static record at each table azimuth 0°, 90°, 180°, 270°
(role ``"earth-rate-bias.position"``, tags ``pose=<axis>`` and ``azimuth=<deg>``). Each gyro
axis is thus horizontal pointing N, E, S, W in four poses (the 4-position method) and vertical
up and down in two (the up/down method), each averaged over the four azimuths.
The twin: a high-grade single-axis table and one IMU (navigation grade by default).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from imucalib.errors import ConfigurationError
from imucalib.plan.equipment import ImuConfig, SiteConfig, TableConfig, TwinEquipment
from imucalib.plan.fixture_poses import FIXTURE_AXES
from imucalib.plan.schema import (
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanStep,
    PositionStep,
    WarmUpStep,
)
from imucalib.procedures.common.grade import WARM_UP_S, check_grade
from imucalib.procedures.earth_rate_bias.roles import (
    EARTH_RATE_BIAS_POSITION,
    EARTH_RATE_BIAS_REMOUNT,
)

__all__ = ["EARTH_RATE_AZIMUTHS_DEG", "EARTH_RATE_POSES", "generate_earth_rate_bias_plan"]

#: The fixture poses (axis up), in the order of the plan.
EARTH_RATE_POSES: tuple[str, ...] = ("+z", "-z", "+x", "-x", "+y", "-y")
#: Table azimuths of each pose [°].
EARTH_RATE_AZIMUTHS_DEG: tuple[float, ...] = (0.0, 90.0, 180.0, 270.0)


def generate_earth_rate_bias_plan(*, name: str = "earth-rate-bias", grade: str = "navigation",
                                  poses: Sequence[str] = EARTH_RATE_POSES,
                                  record_s: float = 1800.0, settle_s: float = 60.0,
                                  warm_up_s: float | None = None, sample_rate_hz: float = 100.0,
                                  latitude_deg: float = 45.0, noise: str = "grade",
                                  errors: Mapping[str, Any] | None = None,
                                  seed: int = 1) -> Plan:
    """Return the default Earth-rate bias plan (module docstring).

    Parameters
    ----------
    name : str
        Plan name.
    grade : {"consumer", "tactical", "navigation"}
        The IMU's grade (twin and default warm-up).
    poses : sequence of str
        Fixture axes up, among +z, −z, +x, −x, +y, −y.
    record_s, settle_s : float
        Static record and settling time at each azimuth. [s]
    warm_up_s : float, optional
        Warm-up; the grade's default when omitted. [s]
    sample_rate_hz, latitude_deg, noise, errors, seed
        The twin's IMU rate [Hz], site [°], noise, known truth values and seed.

    Raises
    ------
    ConfigurationError
        An unknown grade or pose, a repeated pose, a record shorter than 3 s.
    """
    check_grade(grade)
    bad = [p for p in poses if p not in FIXTURE_AXES]
    if bad or len(set(poses)) != len(poses) or not poses:
        raise ConfigurationError(f"`poses` must be distinct among {FIXTURE_AXES}; got "
                                 f"{list(poses)}")
    if record_s < 3.0:
        raise ConfigurationError(f"`record_s` must be at least 3 s; got {record_s:g} s")
    steps: list[PlanStep] = [
        OperatorCheckStep(kind="operator-check", label="mounting",
                          item="fixture on the single-axis table, table levelled and its zero "
                               "azimuth pointing north"),
        WarmUpStep(kind="warm-up", label="warm-up",
                   duration_s=WARM_UP_S[grade] if warm_up_s is None else warm_up_s),
    ]
    for pose in poses:
        steps.append(OperatorCheckStep(kind="operator-check", label=f"remount {pose} up",
                                       item=f"place the fixture with its {pose} axis up",
                                       remount=pose,
                                       role=EARTH_RATE_BIAS_REMOUNT, tags=(f"pose={pose}",)))
        steps += [PositionStep(kind="position", angles_deg=(az,), settle_s=settle_s,
                               record_s=record_s, role=EARTH_RATE_BIAS_POSITION,
                               label=f"{pose} up, azimuth {az:g}°",
                               tags=(f"pose={pose}", f"azimuth={az:g}"))
                  for az in EARTH_RATE_AZIMUTHS_DEG]
    twin = TwinEquipment(
        seed=seed, site=SiteConfig(latitude_deg=latitude_deg),
        table=TableConfig(kind="single-axis", grade="high"),
        imus=(ImuConfig(name="IMU-0001", grade=grade, sample_rate_hz=sample_rate_hz,
                        noise=noise, errors=dict(errors or {})),))
    return Plan(name=name,
                description=f"Earth-rate gyro bias (4-position and up/down): {len(poses)} poses "
                            f"× 4 azimuths of {record_s:g} s",
                procedure="earth-rate-bias", imu=ImuSpecConfig(grade=grade), twin=twin,
                steps=tuple(steps))
