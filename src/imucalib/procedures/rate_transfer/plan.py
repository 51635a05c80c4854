"""The plan of the gyro rate-transfer test (docs/rate-transfer.md, "The plan").

:func:`generate_rate_transfer_plan` writes it as a :class:`~imucalib.plan.schema.Plan`:

1. an operator check of the mounting (the unit on its cube, square to the faces);
2. for each axis under test (``x``, ``y``, ``z`` by default): a remount placing the cube with
   that body axis up, along the single-axis table's vertical spin axis (an operator check whose
   ``remount`` field tells the twin, and the operator, which face), then one turn at every rate
   of the list, each over `revolutions` whole revolutions.

The default rates, ±5, ±12.5, ±18, ±27, ±36, ±45, ±60 °/s, are those of a Chinese textbook
chapter on MIMU error analysis and calibration (docs/procedures.md, "The MIMU chapter");
``log_spaced=(min, max, n)`` replaces them by n rates spaced logarithmically from min to max,
both signs (IEEE Std 952-2020 / 1431-2004 rate-transfer tests). A rate at or beyond the gyro's
full scale is refused (:class:`~imucalib.errors.ConfigurationError`): its samples would clip.

Every step has a role (:mod:`.roles`: ``rate-transfer.remount``,
``rate-transfer.rate``) and the tag ``axis=<x|y|z>``; the turns also ``rate=<°/s>``.

The plan carries a ``[twin]`` table (:func:`rate_table_twin`): a high-grade single-axis table,
one unit of the chosen grade on a hexahedral fixture, its reference point on the spin axis.

The rates, the remounts, the turns and the twin are written by
:mod:`~imucalib.procedures.common.rate_table_plan` (shared with the installation test); its
names are re-exported here.

Contents
--------
:data:`DEFAULT_RATES_DPS`, :func:`generate_rate_transfer_plan`, :func:`rate_table_twin`,
:func:`signed_rates`, :func:`check_rates_in_range`, :func:`remounted_turns_plan`
"""

from __future__ import annotations

from collections.abc import Sequence

from imucalib.errors import ConfigurationError
from imucalib.plan.equipment import TwinEquipment
from imucalib.plan.schema import Plan
from imucalib.procedures.common.rate_table_plan import (
    AXES,
    DEFAULT_RATES_DPS,
    POSE_OF_AXIS,
    UNIT_NAME,
    check_rates_in_range,
    rate_table_twin,
    remount_step,
    remounted_turns_plan,
    signed_rates,
)
from imucalib.procedures.rate_transfer.roles import RATE_TRANSFER_RATE, RATE_TRANSFER_REMOUNT

__all__ = ["AXES", "DEFAULT_RATES_DPS", "POSE_OF_AXIS", "UNIT_NAME", "check_rates_in_range",
           "generate_rate_transfer_plan", "rate_table_twin", "remount_step",
           "remounted_turns_plan", "signed_rates"]


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
