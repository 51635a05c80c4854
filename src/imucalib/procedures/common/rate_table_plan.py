"""Plan parts of the turn tests on a single-axis rate table, each body axis up in turn.

Shared by the rate-transfer test (docs/rate-transfer.md, "The plan") and the installation test
(docs/installation.md, "The plan"): :func:`remounted_turns_plan` writes an operator check of the
mounting, then for each axis a remount placing the cube with that body axis up along the table's
vertical spin axis (:func:`remount_step`; the fixture pose of :data:`POSE_OF_AXIS`) and one turn
over whole revolutions at every rate. :func:`signed_rates` turns magnitudes into +ω, −ω pairs
(:data:`DEFAULT_RATES_DPS` when none are given, or ``log_spaced=(min, max, n)``: IEEE Std
952-2020 / 1431-2004 logarithmic spacing); :func:`check_rates_in_range` refuses a rate at or
beyond the gyro's full scale (its samples would clip). The twin (:func:`rate_table_twin`): a
high-grade single-axis table, one unit of the chosen grade on a hexahedral fixture, its
reference point on the spin axis.

Contents
--------
:data:`DEFAULT_RATES_DPS`, :data:`AXES`, :data:`POSE_OF_AXIS`, :data:`UNIT_NAME`,
:func:`signed_rates`, :func:`check_rates_in_range`, :func:`rate_table_twin`, :func:`remount_step`,
:func:`remounted_turns_plan`
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from imucalib.errors import ConfigurationError
from imucalib.models.imu import GRADES
from imucalib.plan.equipment import (
    FixtureConfig,
    ImuConfig,
    MountConfig,
    SiteConfig,
    TableConfig,
    TwinEquipment,
)
from imucalib.plan.fixture_poses import FixtureAxis
from imucalib.plan.schema import (
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanLimits,
    PlanStep,
    RateStep,
)

__all__ = [
    "AXES",
    "DEFAULT_RATES_DPS",
    "POSE_OF_AXIS",
    "UNIT_NAME",
    "check_rates_in_range",
    "rate_table_twin",
    "remount_step",
    "remounted_turns_plan",
    "signed_rates",
]

#: The rates of the MIMU chapter (a Chinese textbook chapter on MIMU error analysis and
#: calibration; docs/procedures.md), each turned both ways. [°/s]
DEFAULT_RATES_DPS: tuple[float, ...] = (5.0, 12.5, 18.0, 27.0, 36.0, 45.0, 60.0)
#: Body axes that can be tested.
AXES: tuple[str, ...] = ("x", "y", "z")
#: The fixture pose that puts each body axis up (the unit on the cube's +z face).
POSE_OF_AXIS: dict[str, FixtureAxis] = {"x": "+x", "y": "+y", "z": "+z"}
#: The name of the twin's unit.
UNIT_NAME = "IMU-0001"



def signed_rates(rates_dps: Sequence[float] | None,
                 log_spaced: tuple[float, float, int] | None) -> tuple[float, ...]:
    """Return the magnitudes as signed rates, each +ω then −ω, smallest first. [°/s]

    Raises
    ------
    ConfigurationError
        A rate ≤ 0 or repeated, a log spacing with min ≥ max or n < 2, or both options.
    """
    if log_spaced is not None:
        lo, hi, n = float(log_spaced[0]), float(log_spaced[1]), int(log_spaced[2])
        if not (0.0 < lo < hi) or n < 2:
            raise ConfigurationError(f"`log_spaced` must be (min, max, n) with 0 < min < max and "
                                     f"n ≥ 2; got {tuple(log_spaced)}")
        mags = [float(v) for v in np.geomspace(lo, hi, n)]
    else:
        mags = [abs(float(r)) for r in (rates_dps if rates_dps is not None
                                         else DEFAULT_RATES_DPS)]
    if not mags or any(not np.isfinite(r) or r <= 0.0 for r in mags):
        raise ConfigurationError(f"rates must be finite and > 0 °/s; got {mags}")
    if len(set(mags)) != len(mags):
        raise ConfigurationError(f"rates must be distinct; got {mags}")
    return tuple(s * r for r in sorted(mags) for s in (1.0, -1.0))


def check_rates_in_range(rates_dps: Sequence[float], twin: TwinEquipment, grade: str) -> float:
    """Return the gyro full scale [°/s]; refuse a rate at or beyond it.

    Raises
    ------
    ConfigurationError
        A rate whose magnitude reaches the full scale of any of the twin's units (or the grade's).
    """
    ranges = [u.gyro_range_dps if u.gyro_range_dps is not None else GRADES[u.grade].gyro_range_dps
              for u in twin.imus] or [GRADES[grade].gyro_range_dps]
    full = float(min(ranges))
    top = max(abs(float(r)) for r in rates_dps)
    if top >= full:
        raise ConfigurationError(f"rate {top:g} °/s reaches the gyro range ±{full:g} °/s: the "
                                 "output would saturate; choose rates below the full scale")
    return full


def rate_table_twin(grade: str, sample_rate_hz: float, seed: int,
                    latitude_deg: float = 45.0) -> TwinEquipment:
    """Return the twin: a high-grade single-axis table, one unit on a cube, on the spin axis."""
    if grade not in GRADES:
        raise ConfigurationError(f"`grade` must be one of {sorted(GRADES)}; got {grade!r}")
    return TwinEquipment(
        seed=seed,
        site=SiteConfig(latitude_deg=latitude_deg),
        table=TableConfig(kind="single-axis", grade="high"),
        fixture=FixtureConfig(kind="hexahedral", half_edge_m=0.05,
                              mounts=(MountConfig(face="+z", lever_arm_m=(0.0, 0.0, 0.0)),)),
        imus=(ImuConfig(name=UNIT_NAME, grade=grade, sample_rate_hz=sample_rate_hz),),
    )


def remount_step(axis: str, role: str) -> OperatorCheckStep:
    """Return the operator check that places the cube with body axis `axis` up."""
    if axis not in POSE_OF_AXIS:
        raise ConfigurationError(f"axes must be among {AXES}; got {axis!r}")
    pose = POSE_OF_AXIS[axis]
    return OperatorCheckStep(kind="operator-check", remount=pose,
                             item=f"place the cube with its {pose} face up (body {axis} up)",
                             role=role, tags=(f"axis={axis}",), label=f"remount {axis} up")


def remounted_turns_plan(*, name: str, procedure: str, description: str, axes: Sequence[str],
                         rates: Sequence[float], revolutions: int, settle_s: float, grade: str,
                         equipment: TwinEquipment, roles: tuple[str, str]) -> Plan:
    """Return a plan of turns at `rates` with each of `axes` up in turn (remount checks).

    Shared by the rate transfer and the installation test: a mounting check, then per axis a
    remount (role ``roles[0]``) and a turn over whole revolutions at each rate (role
    ``roles[1]``, tags ``axis=`` and ``rate=``).

    Raises
    ------
    ConfigurationError
        Axes not distinct, or a rate beyond the twin's gyro range.
    """
    check_rates_in_range(rates, equipment, grade)
    if not axes or len(set(axes)) != len(axes):
        raise ConfigurationError(f"`axes` must be distinct axes among {AXES}; got {tuple(axes)}")
    steps: list[PlanStep] = [OperatorCheckStep(
        kind="operator-check",
        item="the unit on the cube's +z face, square to it; cables strain-relieved")]
    for axis in axes:
        steps.append(remount_step(axis, roles[0]))
        steps += [RateStep(kind="rate", axis=0, rate_dps=r, settle_s=settle_s,
                           revolutions=revolutions, role=roles[1],
                           tags=(f"axis={axis}", f"rate={r:g}"),
                           label=f"{axis} up, {r:+g} °/s") for r in rates]
    top = max(abs(r) for r in rates)
    return Plan(
        name=name, description=description, procedure=procedure,
        imu=ImuSpecConfig(grade=grade),
        limits=PlanLimits(max_rate_dps=max(1.5 * top, 100.0)),
        twin=equipment,
        steps=tuple(steps),
    )
