"""P1's declared-noise floor: the unit grade's flicker and random walk where the records are short.

A static record shorter than a few flicker corners of the unit's noise cannot show the flicker
floor; the noise model of the window means then takes the noise the recording declares
(docs/p1.md, "Noise model of the window means";
:func:`~imucalib.procedures.common.noise.with_declared_floor`).

Contents
--------
:func:`declared_floor`
"""

from __future__ import annotations

from collections.abc import Sequence

from imucalib.errors import ConfigurationError
from imucalib.io.reader import Recording
from imucalib.models.noise import NoiseModel
from imucalib.plan.schema import ImuSpecConfig
from imucalib.procedures.common.noise import longest_cluster_s, noise_records, with_declared_floor
from imucalib.procedures.p1.windows import WindowObservation

__all__ = ["declared_floor"]


def declared_floor(rec: Recording, imu_spec: ImuSpecConfig | None,
                   windows: Sequence[WindowObservation], noise: dict[str, NoiseModel],
                   sample_rate_hz: float) -> tuple[dict[str, NoiseModel], str | None]:
    """Raise the fitted flicker and random walk to the plan's declared noise where needed.

    When the pooled static records' longest Allan cluster is shorter than
    :data:`~imucalib.procedures.common.noise.FLICKER_CORNERS_MIN` flicker corners of the noise
    the recording declares — its unit grade's (the stated IMU specification's grade, else the
    stored plan's; :func:`~imucalib.procedures.common.grade.grade_noise`, white only for a
    plan whose twin says so) — the records cannot show the flicker floor:
    :func:`~imucalib.procedures.common.noise.with_declared_floor` (docs/p1.md, "Noise model of
    the window means"). Unchanged when the recording states no grade.
    """
    from imucalib.models.imu import sample_imu_model
    from imucalib.plan import parse_plan
    from imucalib.procedures.common.grade import grade_noise, plan_grade

    declared: dict[str, NoiseModel] | None = None
    grade: str = imu_spec.grade if imu_spec is not None else ""
    text = rec.metadata.get("plan_toml")
    if text:
        try:
            plan = parse_plan(str(text))
            if not grade or plan_grade(plan) == grade:
                declared, grade = grade_noise(plan), plan_grade(plan)
        except ConfigurationError:
            pass
    if declared is None and grade:
        model = sample_imu_model(grade, 0, nonlinear=False)
        declared = {"accel": model.accel_noise, "gyro": model.gyro_noise}
    if declared is None:
        return noise, None
    records = noise_records(windows)
    tau_max = max(longest_cluster_s(w.duration_s, sample_rate_hz) for w in records)
    return with_declared_floor(noise, declared, tau_max, source=f"grade {grade}")
