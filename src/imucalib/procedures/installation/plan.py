"""The plan of the installation-error test (docs/installation.md, "The plan").

:func:`generate_installation_plan`: an operator check of the mounting, then for each axis
(``x``, ``y``, ``z``) a remount with that body axis up on a single-axis table and a +ω and a −ω
turn over `revolutions` whole revolutions each (the MIMU chapter's one revolution, 360°, per
direction, docs/installation.md; two by default, the analysis accepting one fewer at the window
edges), at each rate of `rate_dps`. Roles ``installation.remount`` and ``installation.rate``, tags
``axis=<k>`` and ``rate=<°/s>``. The twin is that of the rate-transfer test
(:func:`~imucalib.procedures.common.rate_table_plan.rate_table_twin`).

Contents
--------
:func:`generate_installation_plan`
"""

from __future__ import annotations

from collections.abc import Sequence

from imucalib.errors import ConfigurationError
from imucalib.plan.equipment import TwinEquipment
from imucalib.plan.schema import Plan
from imucalib.procedures.common.rate_table_plan import (
    AXES,
    rate_table_twin,
    remounted_turns_plan,
    signed_rates,
)
from imucalib.procedures.installation.roles import INSTALLATION_RATE, INSTALLATION_REMOUNT

__all__ = ["generate_installation_plan"]


def generate_installation_plan(
    *,
    rate_dps: float | Sequence[float] = 30.0,
    axes: Sequence[str] = AXES,
    revolutions: int = 2,
    settle_s: float = 5.0,
    grade: str = "tactical",
    sample_rate_hz: float = 100.0,
    seed: int = 0,
    twin: TwinEquipment | None = None,
    name: str = "installation",
) -> Plan:
    """Return the installation-error plan (module docstring).

    Parameters
    ----------
    rate_dps : float or sequence of float
        |ω| of the turns (several: each turned both ways). [°/s]
    axes : sequence of {"x", "y", "z"}
        Body axes up in turn (each gives the column of M of that input axis).
    revolutions : int
        Whole revolutions per turn (≥ 2).
    settle_s, grade, sample_rate_hz, seed, twin, name :
        Settling before each turn [s], the twin IMU's grade, output rate [Hz] and seed, another
        twin station, the plan's name (:class:`~.options.InstallationPlanOptions` says each).

    Raises
    ------
    ConfigurationError
        Bad rates, axes or revolutions; a rate at or beyond the gyro's full scale.
    """
    if revolutions < 2:
        raise ConfigurationError(f"`revolutions` must be ≥ 2 (one may be lost at the window "
                                 f"edges); got {revolutions}")
    mags = [rate_dps] if isinstance(rate_dps, int | float) else list(rate_dps)
    rates = signed_rates(mags, None)
    equipment = twin if twin is not None else rate_table_twin(grade, sample_rate_hz, seed)
    return remounted_turns_plan(
        name=name, procedure="installation",
        description=("Installation errors (docs/installation.md): each axis up in turn on a "
                     "single-axis table, a +ω and a −ω turn over whole revolutions; the "
                     "misalignment angles of the gyro triad."),
        axes=axes, rates=rates, revolutions=revolutions, settle_s=settle_s, grade=grade,
        equipment=equipment, roles=(INSTALLATION_REMOUNT, INSTALLATION_RATE))
