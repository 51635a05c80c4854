"""The random-drift test's plan options (:func:`~.plan.generate_random_drift_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new random-drift`` builds
its flags from them (docs/plugins.md).

:class:`RandomDriftAnalysisOptions` holds, the same way, the keys
:func:`~.analysis.analyze_random_drift` takes as ``options``; ``imucalib calibrate`` reads them
with ``--set NAME=VALUE``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from imucalib.plan.bounds import (
    MAX_ANGLE_DEG,
    MAX_TOTAL_S,
)
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
from imucalib.procedures.random_drift.plan import MIN_REPETITIONS

__all__ = ["RandomDriftAnalysisOptions", "RandomDriftPlanOptions"]


@dataclass(frozen=True)
class RandomDriftPlanOptions:
    """Keywords of :func:`~imucalib.procedures.random_drift.plan.generate_random_drift_plan`."""

    repetitions: int = option(7, help="Runs of the multi-position sequence (at least 3).",
                              min=MIN_REPETITIONS)
    span_s: float = option(12 * 3600.0, help="From the first repetition's start to the last's, "
                                             "the repetitions starting evenly over it.",
                           unit="s", min=0.0, max=MAX_TOTAL_S)
    positions_deg: tuple[tuple[float, float], ...] | None = option(
        None, help="One repetition's (pitch, roll) positions, at least 4 (the six axis-up "
                   "positions when omitted).", unit="°", min=-MAX_ANGLE_DEG, max=MAX_ANGLE_DEG)
    record_s: float = record_field(300.0, help="Static record at each position (≥ 3 s).", min=3.0)
    settle_s: float = settle_field(30.0)
    warm_up_s: float | None = warm_up_field()
    grade: Grade = grade_field("tactical")
    sample_rate_hz: float = sample_rate_field(100.0)
    latitude_deg: float = latitude_field()
    noise: TwinNoise = twin_noise_field()
    errors: Mapping[str, Any] | None = errors_field()
    seed: int = seed_field(1)
    name: str = plan_name_field("random-drift")


@dataclass(frozen=True)
class RandomDriftAnalysisOptions:
    """The keys :func:`~.analysis.analyze_random_drift` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    gravity_mps2: float | None = gravity_field()
    scale_misalignment: Any = option(
        None, help="The gyro's scale-factor and misalignment matrix M (y = (I + M)·ω), taken as "
                   "known (default: zero).",
        python_only="a 3×3 matrix; pass it from Python "
                    "(analyze(..., options={'scale_misalignment': M}))")
    scale_misalignment_std: float = option(
        1e-3, help="The Type B standard uncertainty of each element of M.", min=0.0)
    noise_block_s: float = noise_block_field(1.0)
