"""P1's declared-noise floor: the declared flicker and random walk where the records are short.

A static record shorter than a few flicker corners of the unit's noise cannot show the flicker
floor; the noise model of the window means then takes the noise the recording declares
(docs/p1.md, "Noise model of the window means";
:func:`~imucalib.procedures.common.noise.with_declared_floor`): the noise characterisation its
plan carries (``[imu.noise]``), else its unit grade's.

Contents
--------
:func:`declared_floor`, :func:`recording_declared_noise`
"""

from __future__ import annotations

from collections.abc import Sequence

from imucalib.errors import ConfigurationError
from imucalib.io.reader import Recording
from imucalib.models.noise import NoiseModel
from imucalib.plan.schema import ImuSpecConfig
from imucalib.procedures.common.noise import longest_cluster_s, noise_records, with_declared_floor
from imucalib.procedures.p1.windows import WindowObservation

__all__ = ["declared_floor", "recording_declared_noise"]


def recording_declared_noise(rec: Recording, imu_spec: ImuSpecConfig | None
                             ) -> tuple[dict[str, NoiseModel], str] | None:
    """Return the noise a recording declares for its unit, with its source; None if none.

    In order: the stated IMU specification's ``noise`` (a noise characterisation,
    :func:`~imucalib.procedures.common.grade.spec_noise`); the stored plan's declared noise
    (:func:`~imucalib.procedures.common.grade.declared_noise`: its ``[imu.noise]``, else its
    grade's, white only for a plan whose twin says so) when the plan's grade is the stated one
    (or none is stated); the stated grade's. The source is ``"characterisation FILE (sha256
    …)"`` or ``"grade G"`` (docs/test-design.md, "A noise characterisation in place of the
    grade's").
    """
    from imucalib.models.imu import sample_imu_model
    from imucalib.plan import parse_plan
    from imucalib.procedures.common.grade import declared_noise, plan_grade, spec_noise

    stated = spec_noise(imu_spec)
    if stated is not None:
        return stated
    grade: str = imu_spec.grade if imu_spec is not None else ""
    text = rec.metadata.get("plan_toml")
    if text:
        try:
            plan = parse_plan(str(text))
            if not grade or plan_grade(plan) == grade:
                return declared_noise(plan)
        except ConfigurationError:
            pass
    if not grade:
        return None
    model = sample_imu_model(grade, 0, nonlinear=False)
    return {"accel": model.accel_noise, "gyro": model.gyro_noise}, f"grade {grade}"


def declared_floor(rec: Recording, imu_spec: ImuSpecConfig | None,
                   windows: Sequence[WindowObservation], noise: dict[str, NoiseModel],
                   sample_rate_hz: float) -> tuple[dict[str, NoiseModel], str | None]:
    """Raise the fitted flicker and random walk to the plan's declared noise where needed.

    When the pooled static records' longest Allan cluster is shorter than
    :data:`~imucalib.procedures.common.noise.FLICKER_CORNERS_MIN` flicker corners of the noise
    the recording declares (:func:`recording_declared_noise`: the noise characterisation its
    plan carries, else its unit grade's), the records cannot show the flicker floor:
    :func:`~imucalib.procedures.common.noise.with_declared_floor` (docs/p1.md, "Noise model of
    the window means"); its note names the declared noise's source. Unchanged when the
    recording declares no noise.
    """
    declared = recording_declared_noise(rec, imu_spec)
    if declared is None:
        return noise, None
    records = noise_records(windows)
    tau_max = max(longest_cluster_s(w.duration_s, sample_rate_hz) for w in records)
    return with_declared_floor(noise, declared[0], tau_max, source=declared[1])
