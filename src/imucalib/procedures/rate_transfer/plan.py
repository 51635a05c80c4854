"""The plan of the gyro rate-transfer test (docs/rate-transfer.md, "The plan").

:func:`generate_rate_transfer_plan` writes it as a :class:`~imucalib.plan.schema.Plan`:

1. an operator check of the mounting (the unit on its cube, square to the faces);
2. for each axis under test (``x``, ``y``, ``z`` by default): a remount placing the cube with
   that body axis up, along the single-axis table's vertical spin axis (an operator check whose
   ``remount`` field tells the twin, and the operator, which face), then one turn at every rate
   of the list, each over `revolutions` whole revolutions.

The default rates are those of the P4 source chapter, ±5, ±12.5, ±18, ±27, ±36, ±45, ±60 °/s;
``log_spaced=(min, max, n)`` replaces them by n rates spaced logarithmically from min to max,
both signs (IEEE Std 952-2020 / 1431-2004 rate-transfer tests). A rate at or beyond the gyro's
full scale is refused (:class:`~imucalib.errors.ConfigurationError`): its samples would clip.

Every step has a role (:mod:`imucalib.io.step_roles`: ``rate-transfer.remount``,
``rate-transfer.rate``) and the tag ``axis=<x|y|z>``; the turns also ``rate=<°/s>``.

The plan carries a ``[twin]`` table (:func:`rate_table_twin`): a high-grade single-axis table,
one unit of the chosen grade on a hexahedral fixture, its reference point on the spin axis.

Contents
--------
:data:`DEFAULT_RATES_DPS`, :func:`generate_rate_transfer_plan`, :func:`rate_table_twin`,
:func:`signed_rates`, :func:`check_rates_in_range`
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from imucalib.errors import ConfigurationError
from imucalib.io.step_roles import RATE_TRANSFER_RATE, RATE_TRANSFER_REMOUNT
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
    "check_rates_in_range",
    "generate_rate_transfer_plan",
    "rate_table_twin",
    "remounted_turns_plan",
    "signed_rates",
]

#: The P4 source chapter's rates, each turned both ways. [°/s]
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


def generate_rate_transfer_plan(
    *,
    rates_dps: Sequence[float] | None = None,
    log_spaced: tuple[float, float, int] | None = None,
    axes: Sequence[str] = AXES,
    revolutions: int = 2,
    settle_s: float = 5.0,
    grade: str = "tactical",
    sample_rate_hz: float = 100.0,
    seed: int = 0,
    twin: TwinEquipment | None = None,
    name: str = "rate-transfer",
) -> Plan:
    """Return the rate-transfer plan (module docstring).

    Parameters
    ----------
    rates_dps : sequence of float, optional
        Rate magnitudes, each turned +ω and −ω (default :data:`DEFAULT_RATES_DPS`). [°/s]
    log_spaced : (float, float, int), optional
        (min, max, n): n magnitudes spaced logarithmically instead. [°/s]
    axes : sequence of {"x", "y", "z"}
        Body axes tested, each up in turn.
    revolutions : int
        Whole revolutions per turn (≥ 2: the analysis accepts one fewer, a sample short at
        each edge of the window).
    settle_s : float
        Settling before each record (the table reaching its rate). [s]
    grade, sample_rate_hz, seed : str, float, int
        The twin's unit grade, its sample rate and seed.
    twin : TwinEquipment, optional
        Another twin station.
    name : str
        The plan's name.

    Raises
    ------
    ConfigurationError
        Bad rates, axes or revolutions; a rate at or beyond the gyro's full scale.
    """
    if revolutions < 2:
        raise ConfigurationError(f"`revolutions` must be ≥ 2 (one may be lost at the window "
                                 f"edges); got {revolutions}")
    rates = signed_rates(rates_dps, log_spaced)
    equipment = twin if twin is not None else rate_table_twin(grade, sample_rate_hz, seed)
    return remounted_turns_plan(
        name=name, procedure="rate-transfer",
        description=("Gyro rate transfer (docs/rate-transfer.md): each axis up in turn on a "
                     "single-axis table, turns at ±ω over whole revolutions; scale factor, "
                     "bias, nonlinearity and asymmetry per axis."),
        axes=axes, rates=rates, revolutions=revolutions, settle_s=settle_s, grade=grade,
        equipment=equipment, roles=(RATE_TRANSFER_REMOUNT, RATE_TRANSFER_RATE))


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
