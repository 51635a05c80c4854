"""P1's plan options (:func:`~imucalib.procedures.p1.plan.generate_p1_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new p1`` builds its
flags from them (docs/plugins.md).

:class:`P1AnalysisOptions` holds, the same way, the keys
:func:`~imucalib.procedures.p1.analysis.analyze_p1` takes as ``options``; ``imucalib calibrate``
reads them with ``--set NAME=VALUE``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from imucalib.plan.bounds import (
    MAX_RECORD_S,
    MAX_REVOLUTIONS,
    MAX_SETTLE_S,
    MAX_STEPS,
    MAX_TABLE_RATE_DPS,
)
from imucalib.procedures.common.option_fields import (
    TermCriterion,
    latitude_field,
    plan_name_field,
    record_field,
    sample_rate_field,
    seed_field,
    settle_field,
    term_criterion_field,
    term_level_field,
    terms_field,
    warm_up_field,
)
from imucalib.procedures.common.options import option

__all__ = ["P1AnalysisOptions", "P1PlanOptions"]


@dataclass(frozen=True)
class P1PlanOptions:
    """Keywords of :func:`~imucalib.procedures.p1.plan.generate_p1_plan`."""

    rates_dps: tuple[float, ...] = option(
        (-100.0, -50.0, 0.0, 50.0, 100.0),
        help="Rate points per axis (5–7 points, both signs and 0; docs/p1.md, step 3).",
        unit="°/s", min=-MAX_TABLE_RATE_DPS, max=MAX_TABLE_RATE_DPS, flag="rates")
    held_out_rates_dps: tuple[float, ...] = option(
        (-75.0, 25.0), help="Rate points per axis kept out of the fit for verification.",
        unit="°/s", min=-MAX_TABLE_RATE_DPS, max=MAX_TABLE_RATE_DPS)
    revolutions: int = option(3, help="Whole turns recorded at each non-zero rate.", min=1,
                              max=MAX_REVOLUTIONS)
    held_out_revolutions: int | None = option(
        None, help="Whole turns at each non-zero held-out rate (revolutions when omitted).",
        min=1, max=MAX_REVOLUTIONS)
    repetitions: int = option(3, help="Complete calibrations (three, for the repeatability "
                                      "check; docs/p1.md, rule 6).", min=1, max=MAX_STEPS)
    reverse_last: bool = option(
        False, help="Run the last repetition in reverse order (held-out positions, rates, "
                    "static, six positions): the six positions close the run.")
    z_rates: bool = option(True, help="Add rate points about pitch with roll at 90° (about the "
                                      "IMU's Z axis: the Z gyro's scale and misalignments).")
    acceptance: Literal["simple", "guarded"] = option(
        "simple", help="The decision rule: simple, or guarded (|value| + 2u within the limit).")
    static_s: float = option(3600.0, help="Level static record for the gyro bias (≥ 60 min; "
                                          "docs/p1.md, step 2).", unit="s", min=0.0,
                             max=MAX_RECORD_S, group="timing")
    settle_s: float = settle_field(30.0, help="Settling at each position (≥ 30 s).")
    record_s: float = record_field(10.0, help="Record at each position (≥ 10 s).")
    held_out_record_s: float | None = option(
        None, help="Record at each held-out position (record_s when omitted).", unit="s",
        min=0.0, max=MAX_RECORD_S, group="timing")
    rate_settle_s: float = option(20.0, help="Settling at each rate (≥ 20 s).", unit="s",
                                  min=0.0, max=MAX_SETTLE_S, group="timing")
    warm_up_s: float | None = warm_up_field(help="Warm-up duration (the grade's when omitted).")
    serial: str = option("", help="The unit's serial number, carried into the result.",
                         group="unit")
    model: str = option("", help="The unit's model, carried into the result.", group="unit")
    maker: str = option("", help="The unit's maker, carried into the result.", group="unit")
    noise_characterization: str = option(
        "", help="A noise characterisation of the unit (the JSON `imucalib allan` writes): its "
                 "noise, carried in the plan's [imu.noise], replaces the grade's in the "
                 "prediction and the analysis's declared flicker floor.", group="unit")
    grade: Literal["consumer", "tactical", "navigation"] = option(
        "tactical", help="The IMU's grade (the twin's IMU, the warm-up and the specification "
                         "checked).", group="twin")
    sample_rate_hz: float = sample_rate_field(1000.0, help="The twin IMU's output rate (≥ 100 Hz).")
    latitude_deg: float = latitude_field()
    heading_deg: float = option(0.0, help="Heading of the twin station.", unit="°",
                                min=-360.0, max=360.0, group="twin")
    seed: int = seed_field(1)
    name: str = plan_name_field("p1-dual-axis")


@dataclass(frozen=True)
class P1AnalysisOptions:
    """The keys :func:`~.analysis.analyze_p1` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    model: Literal["triad", "per-axis"] = option(
        "triad", help="The model fitted: the full triad model or the procedure's per-axis one.")
    workers: int = option(1, help="Local processes the windows are reduced in (1: this one); "
                                  "the result is the same.", min=1)
    terms: str = terms_field(
        "Model terms forced in or out, e.g. +k2,-g (k2: the accelerometer's quadratic scale "
        "factor; g: the gyro's g-sensitivity); the others are chosen by the data (docs/p1.md, "
        "\"Model terms\").")
    term_criterion: TermCriterion = term_criterion_field("docs/p1.md")
    term_level: float = term_level_field()
