"""The default plan of the random-drift test (docs/random-drift.md, "The plan").

:func:`generate_random_drift_plan` writes a mounting check, a warm-up, then ``repetitions``
runs of the multi-position sequence (the six axis-up positions of the g-sensitivity test by
default) spread evenly over ``span_s`` (12 h by default): each repetition's positions have role
``"random-drift.position"`` and tags ``rep=<k>`` and ``position=<j>``; between repetitions the
table rests level (a static step without a role). The twin: a high-grade dual-axis table and
one IMU whose grade noise (bias instability, random walks) makes the repetitions scatter.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from imucalib.errors import ConfigurationError
from imucalib.plan.schema import (
    ImuSpecConfig,
    OperatorCheckStep,
    Plan,
    PlanStep,
    PositionStep,
    StaticStep,
    WarmUpStep,
)
from imucalib.procedures.common.grade import WARM_UP_S, check_grade
from imucalib.procedures.common.static_positions import (
    G_SENSITIVITY_POSITIONS_DEG,
    dual_axis_twin,
    position_steps,
)
from imucalib.procedures.random_drift.roles import RANDOM_DRIFT_POSITION

__all__ = ["MIN_REPETITIONS", "generate_random_drift_plan"]

#: Fewest repetitions whose scatter means anything (the analysis refuses fewer).
MIN_REPETITIONS = 3


def generate_random_drift_plan(*, name: str = "random-drift", grade: str = "tactical",
                               repetitions: int = 7, span_s: float = 12 * 3600.0,
                               positions_deg: Sequence[tuple[float, float]] | None = None,
                               record_s: float = 300.0, settle_s: float = 30.0,
                               warm_up_s: float | None = None, sample_rate_hz: float = 100.0,
                               latitude_deg: float = 45.0, noise: str = "grade",
                               errors: Mapping[str, Any] | None = None,
                               seed: int = 1) -> Plan:
    """Return the default random-drift plan (module docstring).

    Parameters
    ----------
    name : str
        Plan name.
    grade : {"consumer", "tactical", "navigation"}
        The IMU's grade.
    repetitions : int
        Runs of the multi-position sequence (at least :data:`MIN_REPETITIONS`).
    span_s : float
        From the first repetition's start to the last's; the repetitions start evenly over it
        (a repetition longer than the interval follows the previous one at once). [s]
    positions_deg : sequence of (pitch, roll), optional
        One repetition's positions; the six axis-up positions when omitted. [°]
    record_s, settle_s, warm_up_s, sample_rate_hz, latitude_deg, noise, errors, seed
        Record and settling at each position, warm-up [s]; the twin's IMU rate [Hz], site
        [°], noise, known truth values and seed (:class:`~.options.RandomDriftPlanOptions`).

    Raises
    ------
    ConfigurationError
        An unknown grade, fewer than 3 repetitions or 4 positions, a record shorter than 3 s.
    """
    check_grade(grade)
    if repetitions < MIN_REPETITIONS:
        raise ConfigurationError(f"`repetitions` must be at least {MIN_REPETITIONS} (a scatter "
                                 f"needs repeated estimates); got {repetitions}")
    positions = (tuple(positions_deg) if positions_deg is not None
                 else G_SENSITIVITY_POSITIONS_DEG[:6])
    if len(positions) < 4:
        raise ConfigurationError(f"a repetition needs at least 4 positions; got {len(positions)}")
    if record_s < 3.0:
        raise ConfigurationError(f"`record_s` must be at least 3 s; got {record_s:g} s")
    one_rep_s = len(positions) * (record_s + settle_s)
    interval_s = span_s / (repetitions - 1)
    steps: list[PlanStep] = [
        OperatorCheckStep(kind="operator-check", label="mounting",
                          item="IMU fixed on the dual-axis table platform; table levelled"),
        WarmUpStep(kind="warm-up", label="warm-up",
                   duration_s=WARM_UP_S[grade] if warm_up_s is None else warm_up_s),
    ]
    for rep in range(1, repetitions + 1):
        steps += [s.model_copy(update={"label": f"rep {rep}, {s.label}"})
                  for s in position_steps(positions, RANDOM_DRIFT_POSITION, settle_s=settle_s,
                                          record_s=record_s, extra_tags=(f"rep={rep}",))]
        wait = interval_s - one_rep_s
        if rep < repetitions and wait > 1.0:
            steps += [PositionStep(kind="position", angles_deg=(0.0, 0.0), settle_s=0.0,
                                   record_s=1.0, label=f"rest level after rep {rep}"),
                      StaticStep(kind="static", duration_s=wait - 1.0,
                                 label=f"wait {wait / 60:.0f} min")]
    return Plan(name=name,
                description=f"random drift and accelerometer zero stability: {repetitions} "
                            f"repetitions of {len(positions)} positions over "
                            f"{span_s / 3600:g} h",
                procedure="random-drift", imu=ImuSpecConfig(grade=grade),
                twin=dual_axis_twin(grade, sample_rate_hz, latitude_deg, seed, noise, errors),
                steps=tuple(steps))
