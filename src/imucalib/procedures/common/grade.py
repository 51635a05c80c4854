"""The IMU grades a static-position plan accepts, and each grade's default warm-up.

The g-sensitivity, random-drift and Earth-rate bias plans take the unit's grade (consumer,
tactical or navigation) and, when no warm-up is given, warm the unit up for the grade's default
(docs/g-sensitivity.md, "The plan": 15/30/60 min by grade; docs/random-drift.md and
docs/earth-rate-bias.md, "The plan"). :func:`check_grade` refuses any other grade.

A plan's predicted uncertainty (docs/test-design.md) takes the noise of the unit's grade:
:func:`plan_grade` and :func:`grade_noise`, shared by every procedure's ``predict``.

Contents
--------
:data:`WARM_UP_S`, :func:`check_grade`, :func:`plan_grade`, :func:`grade_noise`
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from imucalib.errors import ConfigurationError

if TYPE_CHECKING:
    from imucalib.models.noise import NoiseModel
    from imucalib.plan.schema import Plan

__all__ = ["WARM_UP_S", "check_grade", "grade_noise", "plan_grade"]

#: Default warm-up of each grade; its keys are the grades a plan accepts. [s]
WARM_UP_S = {"consumer": 900.0, "tactical": 1800.0, "navigation": 3600.0}


def check_grade(grade: str) -> None:
    """Raise ConfigurationError for an unknown grade."""
    if grade not in WARM_UP_S:
        raise ConfigurationError(f"`grade` must be one of {sorted(WARM_UP_S)}; got {grade!r}")


def plan_grade(plan: Plan) -> str:
    """Return the unit's grade: the plan's ``[imu]``, else its twin's IMU.

    Raises
    ------
    ConfigurationError
        The plan states no grade.
    """
    if plan.imu.grade:
        return plan.imu.grade
    if plan.twin is not None and plan.twin.imus:
        return plan.twin.imus[0].grade
    raise ConfigurationError(f"plan {plan.name!r} states no IMU grade ([imu] grade or a twin "
                             "IMU): the prediction needs the unit's noise model")


def grade_noise(plan: Plan) -> dict[str, NoiseModel]:
    """Return the noise models ``{"accel", "gyro"}`` of the plan's unit grade.

    The coefficients :func:`~imucalib.models.imu.sample_imu_model` gives a unit of the grade
    (white noise, bias instability, the gyro's rate random walk; the draw does not change them),
    white terms only when the plan's twin IMU has ``noise = "white"``.

    Raises
    ------
    ConfigurationError
        The plan states no grade, or an unknown one.
    """
    from imucalib.models.imu import sample_imu_model
    from imucalib.models.noise import NoiseModel

    model = sample_imu_model(plan_grade(plan), 0, nonlinear=False)
    white = plan.twin is not None and bool(plan.twin.imus) and plan.twin.imus[0].noise == "white"
    out = {"accel": model.accel_noise, "gyro": model.gyro_noise}
    if white:
        out = {k: NoiseModel(white_density=v.white_density) for k, v in out.items()}
    return out
