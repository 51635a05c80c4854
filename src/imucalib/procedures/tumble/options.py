"""The tumble's plan options (:func:`~imucalib.procedures.tumble.plan.generate_tumble_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new tumble`` builds its
flags from them (docs/plugins.md).

:class:`TumbleAnalysisOptions` holds, the same way, the keys
:func:`~imucalib.procedures.tumble.analysis.analyze_tumble` takes as ``options``; ``imucalib
calibrate`` reads them with ``--set NAME=VALUE``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from imucalib.plan.schema import TwinEquipment
from imucalib.procedures.common.option_fields import (
    Grade,
    grade_field,
    gravity_field,
    plan_name_field,
    record_field,
    sample_rate_field,
    seed_field,
    settle_field,
    twin_field,
)
from imucalib.procedures.common.options import option

__all__ = ["TumbleAnalysisOptions", "TumblePlanOptions"]


@dataclass(frozen=True)
class TumblePlanOptions:
    """Keywords of :func:`~imucalib.procedures.tumble.plan.generate_tumble_plan`."""

    n_positions: int = option(12, help="Head positions per sequence (≥ 4, dividing 360: 4, 8, "
                                       "12, 24 …).", min=4, max=360)
    axes: tuple[Literal["x", "y", "z"], ...] = option(
        ("x", "y", "z"), help="Body axes put along the head axis, in order.")
    both_directions: bool = option(False, help="Each sequence also in reverse (hysteresis "
                                               "shows as the passes' difference).")
    record_s: float = record_field(30.0)
    settle_s: float = settle_field(10.0)
    grade: Grade = grade_field("navigation")
    sample_rate_hz: float = sample_rate_field(100.0)
    seed: int = seed_field(0)
    twin: TwinEquipment | None = twin_field(help="Another twin station (a dual-axis table).")
    name: str = plan_name_field("tumble")


@dataclass(frozen=True)
class TumbleAnalysisOptions:
    """The keys :func:`~.analysis.analyze_tumble` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    coefficients: tuple[Literal["K0", "K1", "delta", "K2", "Kip", "K3", "Koq"], ...] | None = (
        option(None, help="The coefficients to estimate (default: all that the positions "
                          "resolve)."))
    method: Literal["lsq", "dft"] = option(
        "lsq", help="The Fourier stage: least squares at the measured angles, or the DFT at the "
                    "commanded ones.")
    gravity_mps2: float | None = gravity_field()
    gravity_rel_std: float | None = option(
        None, help="The relative standard uncertainty of gravity (default: 2e-5 for normal "
                   "gravity, 0 for a given value).", min=0.0)
    angle_std_arcsec: float = option(
        1.0, help="The RMS over a revolution of the head's angle error (Type B).", unit="″",
        min=0.0)
