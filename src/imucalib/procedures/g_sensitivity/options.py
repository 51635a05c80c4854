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
from typing import Any, Literal

from imucalib.plan.bounds import (
    MAX_ANGLE_DEG,
    MAX_RECORD_S,
    MAX_SAMPLE_RATE_HZ,
    MAX_SETTLE_S,
    MAX_WAIT_S,
    MIN_SAMPLE_RATE_HZ,
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
    record_s: float = option(600.0, help="Static record at each position (≥ 3 s).", unit="s",
                             min=3.0, max=MAX_RECORD_S, group="timing")
    settle_s: float = option(60.0, help="Settling before each record.", unit="s", min=0.0,
                             max=MAX_SETTLE_S, group="timing")
    warm_up_s: float | None = option(
        None, help="Warm-up (the grade's 15, 30 or 60 min when omitted).", unit="s", min=0.0,
        max=MAX_WAIT_S, group="timing")
    grade: Literal["consumer", "tactical", "navigation"] = option(
        "tactical", help="The IMU's grade (the twin's IMU and the default warm-up).",
        group="twin")
    sample_rate_hz: float = option(100.0, help="The twin IMU's output rate.", unit="Hz",
                                   min=MIN_SAMPLE_RATE_HZ, max=MAX_SAMPLE_RATE_HZ,
                                   group="twin")
    latitude_deg: float = option(45.0, help="Latitude of the twin's site.", unit="°",
                                 min=-90.0, max=90.0, group="twin")
    noise: Literal["grade", "white"] = option(
        "grade", help="The twin IMU's noise (the grade's full model, or white only).",
        group="twin")
    errors: Mapping[str, Any] | None = option(
        None, help="Known truth values of the twin IMU (SI).", group="twin",
        python_only="a mapping of truth values; pass it from Python or edit the errors of the "
                    "plan's [twin] IMU")
    seed: int = option(1, help="Seed of the twin.", min=-(2**63), max=2**63 - 1, group="twin")
    name: str = option("g-sensitivity", help="The plan's name (the recording's file name "
                                             "starts with it).", group="plan")


@dataclass(frozen=True)
class GSensitivityAnalysisOptions:
    """The keys :func:`~.analysis.analyze_g_sensitivity` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    gravity_mps2: float | None = option(
        None, help="Local gravity (default: normal gravity at the recorded latitude).",
        unit="m/s²", min=0.0)
    scale_misalignment: Any = option(
        None, help="The gyro's scale-factor and misalignment matrix M (y = (I + M)·ω), taken as "
                   "known (default: zero).",
        python_only="a 3×3 matrix; pass it from Python "
                    "(analyze(..., options={'scale_misalignment': M}))")
    scale_misalignment_std: float = option(
        1e-3, help="The Type B standard uncertainty of each element of M.", min=0.0)
    noise_block_s: float = option(1.0, help="The block length of the white-noise estimate.",
                                  unit="s", min=0.0, group="timing")
