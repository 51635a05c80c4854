"""The g-sensitivity test's plan options (:func:`~.plan.generate_g_sensitivity_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new g-sensitivity`` builds
its flags from them (docs/plugins.md).

:class:`GSensitivityAnalysisOptions` holds, the same way, the keys
:func:`~.analysis.analyze_g_sensitivity` takes as ``options``; ``imucalib calibrate`` reads them
with ``--set NAME=VALUE``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from imucalib.plan.bounds import (
    MAX_ANGLE_DEG,
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

__all__ = ["GSensitivityAnalysisOptions", "GSensitivityPlanOptions"]


@dataclass(frozen=True)
class GSensitivityPlanOptions:
    """Keywords of :func:`~imucalib.procedures.g_sensitivity.plan.generate_g_sensitivity_plan`."""

    positions_deg: tuple[tuple[float, float], ...] | None = option(
        None, help="The static (pitch, roll) positions, at least 4 exciting every gravity "
                   "component (the six axis-up and eight 45° positions when omitted).",
        unit="°", min=-MAX_ANGLE_DEG, max=MAX_ANGLE_DEG)
    record_s: float = record_field(600.0, help="Static record at each position (≥ 3 s).", min=3.0)
    settle_s: float = settle_field(60.0)
    warm_up_s: float | None = warm_up_field()
    grade: Grade = grade_field("tactical")
    sample_rate_hz: float = sample_rate_field(100.0)
    latitude_deg: float = latitude_field()
    noise: TwinNoise = twin_noise_field()
    errors: Mapping[str, Any] | None = errors_field()
    seed: int = seed_field(1)
    name: str = plan_name_field("g-sensitivity")


@dataclass(frozen=True)
class GSensitivityAnalysisOptions:
    """The keys :func:`~.analysis.analyze_g_sensitivity` takes as ``options``.

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
