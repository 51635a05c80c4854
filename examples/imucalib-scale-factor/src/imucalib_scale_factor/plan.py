"""The scale-factor plan: turns about the unit's z axis on the twin's single-axis rate table.

:func:`generate_scale_factor_plan` writes, with imucalib's plan schema,

1. an operator check of the mounting (role :data:`ROLE_MOUNT`): the unit on the cube's +z face,
   its z axis along the table's vertical spin axis;
2. one turn at each signed rate, +ω then −ω for each magnitude (role :data:`ROLE_RATE`, tags
   ``axis=z`` and ``rate=<°/s>``), each recorded over whole table revolutions, so that the
   horizontal Earth rate, which a turning unit sees as a once-per-revolution term, averages out.

The plan carries imucalib's single-axis twin (a high-grade table, one unit of the chosen grade on
a hexahedral fixture), so ``imucalib run PLAN --station sim`` runs it. A rate at or beyond the
gyro's full scale is refused (its samples would clip).

The name and the roles are those of :mod:`imucalib_scale_factor.roles` (re-exported here).

Contents
--------
:data:`ROLE_MOUNT`, :data:`ROLE_RATE`, :func:`generate_scale_factor_plan`
"""

from __future__ import annotations

from collections.abc import Sequence

from imucalib.errors import ConfigurationError
from imucalib.plan.schema import (
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanLimits,
    PlanStep,
    RateStep,
)
from imucalib.procedures.common.rate_table_plan import (
    check_rates_in_range,
    rate_table_twin,
    signed_rates,
)
from imucalib_scale_factor.options import DEFAULT_RATES_DPS
from imucalib_scale_factor.roles import NAME, ROLE_MOUNT, ROLE_RATE

__all__ = ["NAME", "ROLE_MOUNT", "ROLE_RATE", "generate_scale_factor_plan"]


def generate_scale_factor_plan(
    *,
    rates_dps: Sequence[float] = DEFAULT_RATES_DPS,
    revolutions: int = 2,
    settle_s: float = 5.0,
    grade: str = "tactical",
    sample_rate_hz: float = 100.0,
    seed: int = 0,
    name: str = NAME,
) -> Plan:
    """Return the scale-factor plan (module docstring).

    Parameters
    ----------
    rates_dps : sequence of float
        Rate magnitudes, each turned +ω and −ω. [°/s]
    revolutions : int
        Whole revolutions per turn (≥ 2: the analysis accepts one fewer, a sample short at each
        edge of the window).
    settle_s : float
        Settling before each record. [s]
    grade, sample_rate_hz, seed : str, float, int
        The twin unit's grade, output rate [Hz] and seed.
    name : str
        The plan's name.

    Returns
    -------
    Plan
        With a ``[twin]`` table.

    Raises
    ------
    ConfigurationError
        Fewer than two revolutions, rates not distinct and positive, a rate at or beyond the
        gyro's full scale, an unknown grade.
    """
    if revolutions < 2:
        raise ConfigurationError(f"`revolutions` must be ≥ 2 (one may be lost at the window "
                                 f"edges); got {revolutions}")
    rates = signed_rates(rates_dps, None)
    twin = rate_table_twin(grade, sample_rate_hz, seed)
    check_rates_in_range(rates, twin, grade)
    steps: list[PlanStep] = [OperatorCheckStep(
        kind="operator-check", role=ROLE_MOUNT, tags=("axis=z",),
        item="the unit on the cube's +z face, its z axis along the table's spin axis")]
    steps += [RateStep(kind="rate", axis=0, rate_dps=r, settle_s=settle_s,
                       revolutions=revolutions, role=ROLE_RATE,
                       tags=("axis=z", f"rate={r:g}"), label=f"z up, {r:+g} °/s")
              for r in rates]
    top = max(abs(r) for r in rates)
    return Plan(
        name=name, procedure=NAME,
        description=("Gyro scale factor about z (the imucalib-scale-factor plug-in): turns at "
                     "±ω over whole revolutions on a single-axis table; y = K1·ω + b."),
        imu=ImuSpecConfig(grade=grade),
        limits=PlanLimits(max_rate_dps=max(1.5 * top, 100.0)),
        twin=twin,
        steps=tuple(steps),
    )
