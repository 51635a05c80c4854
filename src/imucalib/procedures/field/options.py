"""The field plan's options (:func:`~imucalib.procedures.field.plan.generate_field_plan`).

Each field is one keyword of the generator with its help, unit, range and help section
(:func:`~imucalib.procedures.common.options.option`); ``imucalib plan new field`` builds its
flags from them (docs/plugins.md).

:class:`FieldAnalysisOptions` holds, the same way, the keys
:func:`~imucalib.procedures.field.analysis.analyze_field` takes as ``options``; ``imucalib
calibrate`` reads them with ``--set NAME=VALUE``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from imucalib.io.import_spec import ImportSpec
from imucalib.plan.bounds import MAX_RECORD_S, MAX_STEPS
from imucalib.procedures.common.option_fields import (
    Grade,
    TermCriterion,
    grade_field,
    gravity_field,
    latitude_field,
    noise_block_field,
    plan_name_field,
    sample_rate_field,
    seed_field,
    term_criterion_field,
    term_level_field,
    terms_field,
)
from imucalib.procedures.common.options import option

__all__ = ["FieldAnalysisOptions", "FieldPlanOptions"]


@dataclass(frozen=True)
class FieldPlanOptions:
    """Keywords of :func:`~imucalib.procedures.field.plan.generate_field_plan`."""

    n_poses: int = option(12, help="Static poses after the initial rest (≥ 6; ≥ 10 for the "
                                   "gravity-norm form).", min=6, max=MAX_STEPS)
    full_turns: bool = option(True, help="Add a +360° and a −360° turn flat on the desk about "
                                         "each axis (the gyro's scale).")
    tilt_deg: float = option(20.0, help="How far the operator tilts the second round of "
                                        "poses.", unit="°", min=0.0, max=90.0)
    static_s: float = option(6.0, help="Each pose's record (≥ 2 s: the detector's windows eat "
                                       "half a second at each end).", unit="s", min=2.0,
                             max=MAX_RECORD_S, group="timing")
    init_static_s: float = option(10.0, help="The initial rest (≥ 4 s).", unit="s", min=4.0,
                                  max=MAX_RECORD_S, group="timing")
    grade: Grade = grade_field("consumer")
    sample_rate_hz: float = sample_rate_field(200.0)
    latitude_deg: float = latitude_field()
    seed: int = seed_field(1)
    name: str = plan_name_field("field")


@dataclass(frozen=True)
class FieldAnalysisOptions:
    """The keys :func:`~.analysis.analyze_field` takes as ``options``.

    They are the procedure's ``analysis_options``; ``imucalib calibrate`` reads them with
    ``--set NAME=VALUE`` and shows them in ``calibrate NAME --help``.
    """

    accel_form: Literal["auto", "gravity-norm", "six-position"] = option(
        "auto", help="The accelerometer's form: from the gravity norm of free poses, or a "
                     "fixture's six faces.")
    gyro_form: Literal["auto", "gravity", "turns", "none"] = option(
        "auto", help="The gyro's form: from the gravity directions, from the turns, or none.")
    accel_k2: Literal["auto", "yes", "no"] = option(
        "auto", help="Fit the accelerometer's quadratic terms K2 (auto: when the data support "
                     "them, by term_criterion).")
    accel_drift: Literal["auto", "yes", "no"] = option(
        "auto", help="Fit a linear drift of the accelerometer's bias over the session, "
                     "gravity-norm form (auto: by term_criterion).")
    accel_temperature: Literal["auto", "yes", "no"] = option(
        "auto", help="Fit the accelerometer's scale factors as linear in the IMU's temperature, "
                     "gravity-norm form, when the log has a temperature (auto: by "
                     "term_criterion).")
    gyro_g_sensitivity: Literal["auto", "yes", "no"] = option(
        "auto", help="Fit the gyro's g-sensitivity G from the static poses (auto: with six "
                     "poses or more, by term_criterion).")
    terms: str = terms_field(
        "Model terms forced in or out, e.g. +k2,-drift,+g (k2, k3, drift, g, temp); overrides "
        "accel_k2, accel_drift, accel_temperature and gyro_g_sensitivity.")
    term_criterion: TermCriterion = term_criterion_field("docs/field.md")
    term_level: float = term_level_field()
    gravity_mps2: float | None = gravity_field(
        help="Local gravity (default: normal gravity at the latitude).")
    gravity_std_mps2: float | None = option(
        None, help="The standard uncertainty of local gravity (default: from the latitude).",
        unit="m/s²", min=0.0)
    latitude_deg: float | None = option(
        None, help="The site's latitude (default: the recording's).", unit="°", min=-90.0,
        max=90.0)
    height_m: float | None = option(None, help="The site's height (default: the recording's).",
                                    unit="m")
    static_threshold: float | None = option(
        None, help="The static detector's threshold k (default: chosen from the log).", min=0.0)
    window_s: float = option(0.5, help="The static detector's window.", unit="s", min=0.0,
                             group="timing")
    init_static_s: float = option(2.0, help="The static start the detector learns its noise "
                                            "from.", unit="s", min=0.0, group="timing")
    min_static_s: float = option(1.0, help="The shortest still interval taken as a pose.",
                                 unit="s", min=0.0, group="timing")
    min_rotation_deg: float = option(5.0, help="The smallest rotation between poses counted.",
                                     unit="°", min=0.0)
    noise_block_s: float = noise_block_field(
        0.25, help="The block length of the pooled white-noise estimate.")
    target_accel_bias_mps2: float = option(
        1e-3, help="The accelerometer-bias σ the coverage check counts poses for.",
        unit="m/s²", min=0.0)
    target_scale: float = option(1e-4, help="The scale-factor σ the coverage check counts "
                                            "poses for.", min=0.0)
    target_angle_rad: float = option(1e-4, help="The misalignment σ the coverage check counts "
                                                "poses for.", unit="rad", min=0.0)
    accel_instability_mps2: float = option(
        0.0, help="A datasheet's accelerometer bias instability, added in quadrature to each "
                  "pose mean's standard error.", unit="m/s²", min=0.0)
    gyro_instability_rps: float = option(
        0.0, help="A datasheet's gyro bias instability, added in quadrature to each pose "
                  "mean's standard error.", unit="rad/s", min=0.0)
    accel_instability_auto: bool = option(
        False, help="Estimate the accelerometer's instability floor from the poses' own "
                    "scatter (not with accel_instability_mps2).")
    import_spec: ImportSpec | None = option(
        None, help="How to read a log file that is not a recording (default: its layout "
                   "detected from the header).",
        python_only="given by the import options of `imucalib calibrate field DATA`")
