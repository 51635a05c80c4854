"""P3's plan options (:func:`~imucalib.procedures.p3.plan.generate_p3_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new p3`` builds its
flags from them (docs/plugins.md).

:class:`P3AnalysisOptions` holds, the same way, the keys
:func:`~imucalib.procedures.p3.analysis.analyze_p3` takes as ``options``; ``imucalib calibrate``
reads them with ``--set NAME=VALUE``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

from imucalib.plan.bounds import (
    MAX_ANGLE_DEG,
    MAX_CENTRIFUGE_RATE_DPS,
    MAX_RECORD_S,
    MAX_STEPS,
)
from imucalib.plan.schema import TwinEquipment
from imucalib.procedures.common.option_fields import (
    Grade,
    grade_field,
    gravity_field,
    plan_name_field,
    sample_rate_field,
    seed_field,
    settle_field,
    twin_field,
)
from imucalib.procedures.common.options import option
from imucalib.procedures.p3.plan import ARM_POSITIONS_DEG, MIN_RATES

__all__ = ["P3AnalysisOptions", "P3PlanOptions"]

#: Largest static radius of a centrifuge (:class:`~imucalib.plan.equipment.CentrifugeConfig`).
_MAX_RADIUS_M = 20.0
#: Largest unbalance the twin's imbalance alarm (4× it, at most 10 000 µm) admits. [µm]
_MAX_UNBALANCE_UM = 2500.0


@dataclass(frozen=True)
class P3PlanOptions:
    """Keywords of :func:`~imucalib.procedures.p3.plan.generate_p3_plan`."""

    static_radius_m: float = option(1.0, help="Static radius r_t of the test position.",
                                    unit="m", min=0.0, max=_MAX_RADIUS_M, flag="radius-m")
    reference_radius_m: float | None = option(
        None, help="Radius of the reference accelerometers (r_t/3 when omitted).", unit="m",
        min=0.0, max=_MAX_RADIUS_M)
    test_range_g: float = option(20.0, help="Specific force at r_t at the top rate.", unit="g",
                                 min=0.0)
    n_rates: int = option(5, help="Rate points (≥ 4), equally spaced in specific force.",
                          min=MIN_RATES, max=MAX_STEPS)
    rates_dps: tuple[float, ...] | None = option(
        None, help="Explicit rates instead (≥ 4 distinct, taken positive).", unit="°/s",
        min=-MAX_CENTRIFUGE_RATE_DPS, max=MAX_CENTRIFUGE_RATE_DPS, flag="rates")
    both_directions: bool = option(False, help="Run every rate at +ω and −ω.")
    arm_positions_deg: tuple[float, ...] = option(
        ARM_POSITIONS_DEG, help="The arm positions at rest (spread evenly around the circle).",
        unit="°", min=-MAX_ANGLE_DEG, max=MAX_ANGLE_DEG)
    test_load_kg: float = option(2.0, help="The test load mounted for configuration 3 (the "
                                           "twin's c′ grows with it).", unit="kg", min=0.0,
                                 max=1000.0)
    tumble: bool = option(True, help="Record the 1 g tumble (K1, K0 of each accelerometer; "
                                     "without it the analysis needs them as inputs).")
    rate_record_s: float = option(60.0, help="Least record at each rate (whole revolutions).",
                                  unit="s", min=0.0, max=MAX_RECORD_S, group="timing")
    rest_record_s: float = option(30.0, help="Record at each arm position at rest.", unit="s",
                                  min=0.0, max=MAX_RECORD_S, group="timing")
    settle_s: float = settle_field(
        20.0, help="Settling before each record (a rate step's ramp included).")
    tumble_record_s: float = option(30.0, help="Record in each tumble pose.", unit="s",
                                    min=0.0, max=MAX_RECORD_S, group="timing")
    unbalance_um: float = option(10.0, help="The twin's rotor-centre shift at the top rate "
                                            "with the test load.", unit="µm",
                                 min=-_MAX_UNBALANCE_UM, max=_MAX_UNBALANCE_UM, group="twin")
    grade: Grade = grade_field("navigation")
    sample_rate_hz: float = sample_rate_field(100.0)
    seed: int = seed_field(0)
    twin: TwinEquipment | None = twin_field(
        help="Another twin station (its units named REF-A, REF-B and TEST).")
    name: str = plan_name_field("p3-centrifuge-k2")


@dataclass(frozen=True)
class P3AnalysisOptions:
    """The keys :func:`~.analysis.analyze_p3` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    reference_a: str | None = option(
        None, help="The unit (IMU stream) of reference accelerometer A (default: from the "
                   "recording's mounting check).", group="unit")
    reference_b: str | None = option(
        None, help="The unit (IMU stream) of reference accelerometer B (default: from the "
                   "recording's mounting check).", group="unit")
    test: str | None = option(
        None, help="The unit (IMU stream) of the test accelerometer (default: from the "
                   "recording's mounting check).", group="unit")
    k1: Mapping[str, tuple[float, float]] | None = option(
        None, help="K1 (output per m/s²) and its standard uncertainty per unit, instead of the "
                   "tumble's (default: none, the tumble's).",
        python_only="a mapping of unit to (K1, σ): `imucalib calibrate --k1 UNIT=VALUE,STD` "
                    "(repeat per unit), or from Python")
    k0: Mapping[str, tuple[float, float]] | None = option(
        None, help="K0 (output) and its standard uncertainty per unit, reported with the result "
                   "(default: none, the tumble's).",
        python_only="a mapping of unit to (K0, σ); pass it from Python "
                    "(analyze(..., options={'k0': {...}}))")
    gravity_mps2: float | None = gravity_field(
        help="Local gravity for the tumble (default: normal gravity at the recorded latitude).")
    gravity_rel_std: float | None = option(
        None, help="The relative standard uncertainty of gravity (default: 2e-5 for normal "
                   "gravity, 0 for a given value).", min=0.0)
    radii: Literal["fitted", "nominal"] = option(
        "fitted", help="The radius of each series: its own fitted effective radius or the "
                       "nominal ones.")
    nominal_radii_m: tuple[float, ...] | None = option(
        None, help="The nominal reference and test radii (two values) for radii=nominal.",
        unit="m", min=0.0)
    k2_target_g_per_g2: float = option(
        1e-7, help="The expanded uncertainty (k = 2) the test accelerometer's K2 must reach.",
        unit="g/g²", min=0.0)
    input_axis: Literal["x", "y", "z"] = option(
        "x", help="The accelerometer of each unit that is the instrument (its input axis "
                  "radial).", group="unit")
