"""P1's declared-noise floor: the declared flicker and random walk where the records are short.

A static record shorter than a few flicker corners of the unit's noise cannot show the flicker
floor; the noise model of the window means then takes the noise the recording declares
(docs/p1.md, "Noise model of the window means";
:func:`~imucalib.procedures.common.noise.with_declared_floor`): the noise characterisation its
plan carries (``[imu.noise]``), else its unit grade's.

Contents
--------
:func:`declared_floor`; :func:`recording_declared_noise` is
:func:`imucalib.procedures.common.grade.recording_declared_noise` (shared with the rate transfer)
"""

from __future__ import annotations

from collections.abc import Sequence

from imucalib.io.reader import Recording
from imucalib.models.noise import NoiseModel
from imucalib.plan.schema import ImuSpecConfig
from imucalib.procedures.common.grade import recording_declared_noise
from imucalib.procedures.common.noise import longest_cluster_s, noise_records, with_declared_floor
from imucalib.procedures.p1.windows import WindowObservation

__all__ = ["declared_floor", "recording_declared_noise"]  # the latter: common.grade's


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
