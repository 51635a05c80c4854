"""The Earth-rate bias test's plan options (:func:`~.plan.generate_earth_rate_bias_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new earth-rate-bias``
builds its flags from them (docs/plugins.md).

:class:`EarthRateBiasAnalysisOptions` holds, the same way, the keys
:func:`~.analysis.analyze_earth_rate_bias` takes as ``options``; ``imucalib calibrate`` reads them
with ``--set NAME=VALUE``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from imucalib.procedures.common.option_fields import (
    Grade,
    TwinNoise,
    errors_field,
    grade_field,
    gravity_field,
    latitude_field,
    noise_block_field,
    plan_name_field,
    record_field,
    sample_rate_field,
    seed_field,
    settle_field,
    twin_noise_field,
    warm_up_field,
)
from imucalib.procedures.common.options import option
from imucalib.procedures.earth_rate_bias.plan import EARTH_RATE_POSES

__all__ = ["EarthRateBiasAnalysisOptions", "EarthRateBiasPlanOptions"]


@dataclass(frozen=True)
class EarthRateBiasPlanOptions:
    """Keywords of :func:`~.plan.generate_earth_rate_bias_plan`."""

    poses: tuple[Literal["+z", "-z", "+x", "-x", "+y", "-y"], ...] = option(
        EARTH_RATE_POSES, help="Fixture axes up in turn, distinct (each recorded at azimuths "
                               "0°, 90°, 180° and 270°).")
    record_s: float = record_field(1800.0, help="Static record at each azimuth (≥ 3 s).", min=3.0)
    settle_s: float = settle_field(60.0)
    warm_up_s: float | None = warm_up_field()
    grade: Grade = grade_field("navigation")
    sample_rate_hz: float = sample_rate_field(100.0)
    latitude_deg: float = latitude_field()
    noise: TwinNoise = twin_noise_field()
    errors: Mapping[str, Any] | None = errors_field()
    seed: int = seed_field(1)
    name: str = plan_name_field("earth-rate-bias")


@dataclass(frozen=True)
class EarthRateBiasAnalysisOptions:
    """The keys :func:`~.analysis.analyze_earth_rate_bias` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    gravity_mps2: float | None = gravity_field()
    noise_block_s: float = noise_block_field(1.0)
